"""Worlds: floor plans (walls, furniture), ceilings, textures and decor, lighting, start, routes.

A world is plain data: frozen dataclasses, written by hand as a TOML file (the
built-in ``sim/worlds/lab.toml`` and ``sim/worlds/campus.toml`` are commented
examples of the format) or built in Python. Frame: x, y on the floor plan, z up,
the floor at z = 0, metres; yaw counter-clockwise from +x, degrees in files and
in furniture, radians in the start pose (:class:`shared.pose.Pose2`; a file's
``start`` table gives degrees, converted when the file is read).

Rules a world must satisfy (checked when it is built; a file that breaks one
raises :class:`ConfigError` naming the file and the problem):

* every number finite; walls of non-zero length; heights, sizes and landmark
  patch sizes > 0;
* walls are :data:`WALL_HALF_THICKNESS_M` * 2 thick, centred on their segment;
* the start pose, every route waypoint and every route leg stay at least
  :data:`CLEARANCE_M` from the surface of walls and furniture, and every waypoint
  is reachable from the start;
* route names are unique and a route has at least two distinct waypoints;
* every texture named exists in the world's texture set (the built-in one plus
  ``texture_set``), every scale is > 0, every picture fits on the wall nearest its
  ``at`` (:mod:`sim._world_checks`), every lamp is under a ceiling; placed objects
  (as they stand: doors open or closed) and tree trunks are obstacles like furniture.

What the surfaces carry (textures, pictures, objects, lamps, trees, sky) is in
:mod:`sim.decor`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from shared.config import from_mapping, load_toml, require
from shared.errors import ConfigError
from shared.pose import Pose2
from sim._geometry import box_corners
from sim._world_checks import CLEARANCE_M, Obstacles, check_decor, textures_for
from sim.decor import (
    FURNITURE_KINDS,
    FloorPlan,
    Lamp,
    Picture,
    PlacedObject,
    Sky,
    Tree,
    check_scale,
)
from sim.free_space import WALL_HALF_THICKNESS_M, FreeSpaceMap
from sim.texture_library import TextureLibrary

__all__ = [
    "CLEARANCE_M",
    "WALL_HALF_THICKNESS_M",
    "Box",
    "Ceiling",
    "LandmarkDensity",
    "Lighting",
    "Route",
    "Wall",
    "World",
    "builtin_world_names",
    "load_world",
]


_MIN_WALL_LENGTH_M = 0.01


def _finite(name: str, *values: float) -> None:
    require(all(math.isfinite(v) for v in values), f"{name} must be finite, got {values}")


def _check_patch_size(value: float | None) -> None:
    if value is not None:
        require(
            math.isfinite(value) and value > 0, f"patch_size_m must be finite and > 0, got {value}"
        )


@dataclass(frozen=True, slots=True)
class Wall:
    """A straight wall: a vertical slab from the floor up to ``height_m``."""

    start: tuple[float, float]
    """(x, y) of one end, m."""
    end: tuple[float, float]
    """(x, y) of the other end, m."""
    height_m: float
    """Height, m."""
    patch_size_m: float | None = None
    """Side of the landmark patches on both faces, m; None = ``landmarks.patch_size_m``."""
    texture: str = ""
    """Texture of both faces; "" = the default wall texture."""
    left: str = ""
    """Texture of the face on the left walking from ``start`` to ``end``; "" = ``texture``."""
    right: str = ""
    """Texture of the face on the right; "" = ``texture``."""
    scale_m: float | None = None
    """Width one copy of the texture covers, m; None = the texture's own size."""

    def __post_init__(self) -> None:
        _finite("wall ends", *self.start, *self.end)
        check_scale(self.scale_m)
        length = math.dist(self.start, self.end)
        require(length >= _MIN_WALL_LENGTH_M, f"wall has zero length ({self.start} to {self.end})")
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        _check_patch_size(self.patch_size_m)

    @property
    def length_m(self) -> float:
        """Length, m."""
        return math.dist(self.start, self.end)


@dataclass(frozen=True, slots=True)
class Box:
    """A piece of furniture: a solid box standing on the floor (desk, shelf, bench, kiosk)."""

    center: tuple[float, float]
    """(x, y) of the footprint's centre, m."""
    size: tuple[float, float]
    """(length along ``yaw_deg``, width across it), m."""
    yaw_deg: float
    """Orientation of the length axis, counter-clockwise from +x, degrees."""
    height_m: float
    """Height, m."""
    patch_size_m: float | None = None
    """Side of the landmark patches on its sides, m; None = ``landmarks.patch_size_m``."""
    kind: str = "desk"
    """One of :data:`sim.decor.FURNITURE_KINDS`; it gives the default textures."""
    top: str = ""
    """Texture of the top; "" = the kind's default."""
    front: str = ""
    """Texture of the two long faces; "" = the kind's default."""
    sides: str = ""
    """Texture of the two short ends; "" = the kind's default."""
    scale_m: float | None = None
    """Width one copy of a tiling texture covers, m; None = the texture's own size."""

    def __post_init__(self) -> None:
        require(self.kind in FURNITURE_KINDS,
                f"unknown furniture kind '{self.kind}' (known: {', '.join(FURNITURE_KINDS)})")
        check_scale(self.scale_m)
        _finite("box center, size and yaw", *self.center, *self.size, self.yaw_deg)
        require(min(self.size) > 0, f"size must be > 0 in both directions, got {self.size}")
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        _check_patch_size(self.patch_size_m)


@dataclass(frozen=True, slots=True)
class Ceiling:
    """A roofed rectangle (axis-aligned): indoor space has one, a courtyard has none."""

    min_corner: tuple[float, float]
    """(x, y) of the corner with the smallest coordinates, m."""
    max_corner: tuple[float, float]
    """(x, y) of the corner with the largest coordinates, m."""
    height_m: float
    """Height of the ceiling above the floor, m."""
    patch_size_m: float | None = None
    """Side of the landmark patches on it, m; None = ``landmarks.patch_size_m``."""
    texture: str = ""
    """Texture; "" = the default ceiling texture."""
    scale_m: float | None = None
    """Width one copy of the texture covers, m; None = the texture's own size."""

    def __post_init__(self) -> None:
        check_scale(self.scale_m)
        _finite("ceiling corners", *self.min_corner, *self.max_corner)
        require(
            self.min_corner[0] < self.max_corner[0] and self.min_corner[1] < self.max_corner[1],
            f"min_corner {self.min_corner} must be below max_corner {self.max_corner} in x and y",
        )
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        _check_patch_size(self.patch_size_m)


@dataclass(frozen=True, slots=True)
class LandmarkDensity:
    """Landmark patches: mean number per square metre of each kind of surface, default size.

    A surface holds at most one patch per square of side ``patch size + 3 cm``
    (patches never overlap), so a density above ``1 / (size + 0.03)^2`` saturates.
    """

    wall_per_m2: float = 1.0
    """On walls (both faces), patches per m^2."""
    furniture_per_m2: float = 1.0
    """On the vertical faces of furniture, patches per m^2."""
    ceiling_per_m2: float = 0.3
    """On ceilings, patches per m^2."""
    patch_size_m: float = 0.15
    """Side of a square patch, m, on every wall, box and ceiling that sets no ``patch_size_m``."""

    def __post_init__(self) -> None:
        for name in ("wall_per_m2", "furniture_per_m2", "ceiling_per_m2"):
            value = getattr(self, name)
            require(math.isfinite(value) and value >= 0, f"{name} must be >= 0, got {value}")
        _check_patch_size(self.patch_size_m)


@dataclass(frozen=True, slots=True)
class Lighting:
    """How the scene looks to the camera."""

    brightness: float = 110.0
    """Mean grey level of plain surfaces, 0..255."""
    contrast: float = 1.0
    """Scale of the landmark patches' contrast around that level (1 = as generated)."""
    ambient: float = 0.45
    """Light indoors far from any lamp or window, relative to under a lit lamp (>= 0)."""
    daylight: float = 1.0
    """Daylight outdoors and through windows, relative to a bright overcast day (0 = night)."""

    def __post_init__(self) -> None:
        require(0 < self.brightness < 255, f"brightness must be in (0, 255), got {self.brightness}")
        require(0 < self.contrast <= 4, f"contrast must be in (0, 4], got {self.contrast}")
        for name in ("ambient", "daylight"):
            value = getattr(self, name)
            require(math.isfinite(value) and 0 <= value <= 4,
                    f"{name} must be in [0, 4], got {value}")


@dataclass(frozen=True, slots=True)
class Route:
    """A named polyline through free space, for the scripted teach driver."""

    name: str
    """Unique name within the world."""
    waypoints: tuple[tuple[float, float], ...]
    """(x, y) points, m, driven in order; at least two."""

    def __post_init__(self) -> None:
        require(bool(self.name.strip()), "route name must not be empty")
        require(len(self.waypoints) >= 2, f"route '{self.name}' needs at least 2 waypoints")
        for i, (p, q) in enumerate(zip(self.waypoints, self.waypoints[1:], strict=False)):
            _finite(f"route '{self.name}' waypoint {i}", *p)
            require(math.dist(p, q) > 0.01, f"route '{self.name}' repeats waypoint {i} at {p}")
        _finite(f"route '{self.name}' waypoint {len(self.waypoints) - 1}", *self.waypoints[-1])

    @property
    def length_m(self) -> float:
        """Length of the polyline, m."""
        return sum(math.dist(p, q) for p, q in zip(self.waypoints, self.waypoints[1:],
                                                    strict=False))

    def start_pose(self) -> Pose2:
        """The pose at the first waypoint, facing the second."""
        (x0, y0), (x1, y1) = self.waypoints[0], self.waypoints[1]
        return Pose2(x0, y0, math.atan2(y1 - y0, x1 - x0))


@dataclass(frozen=True, slots=True)
class World:
    """A simulated place: see the module docstring for the rules it must satisfy."""

    name: str
    """Short name."""
    walls: tuple[Wall, ...]
    """The floor plan's walls; their bounding box is the world's extent."""
    start: Pose2
    """Where the robot starts, on the floor plan (yaw in radians)."""
    description: str = ""
    """One or two sentences for humans."""
    furniture: tuple[Box, ...] = ()
    """Boxes standing on the floor."""
    ceilings: tuple[Ceiling, ...] = ()
    """Roofed rectangles; outside them the sky is open."""
    landmarks: LandmarkDensity = LandmarkDensity()
    """Landmark densities per kind of surface and the default patch size."""
    lighting: Lighting = Lighting()
    """Scene brightness and landmark contrast."""
    routes: tuple[Route, ...] = ()
    """Named routes through free space."""
    floor: FloorPlan = field(default_factory=FloorPlan)
    """The floor's textures."""
    lamps: tuple[Lamp, ...] = ()
    """Lamps set in the ceilings."""
    pictures: tuple[Picture, ...] = ()
    """Posters, pictures, signs, switches, windows and doors on walls."""
    objects: tuple[PlacedObject, ...] = ()
    """Boxes, boards and door leaves on the floor plan (obstacles like furniture)."""
    trees: tuple[Tree, ...] = ()
    """Trees (their trunks are obstacles)."""
    sky: Sky = field(default_factory=Sky)
    """The sky where no ceiling is."""
    texture_set: str = ""
    """Manifest of extra textures (a user's own set) beside the built-in ones; "" = none."""

    def __post_init__(self) -> None:
        require(bool(self.name.strip()), "name must not be empty")
        require(len(self.walls) > 0, "a world needs at least one wall")
        names = [r.name for r in self.routes]
        for name in names:
            require(names.count(name) == 1, f"route name '{name}' is used twice")
        _finite("start pose", *self.start)
        check_decor(self)
        obstacles = Obstacles.of(self)
        obstacles.check_point("start pose", (self.start.x_m, self.start.y_m))
        for route in self.routes:
            for i, p in enumerate(route.waypoints):
                obstacles.check_point(f"route '{route.name}' waypoint {i}", p)
            for i, (p, q) in enumerate(zip(route.waypoints, route.waypoints[1:], strict=False)):
                obstacles.check_leg(f"route '{route.name}' leg {i}->{i + 1}", p, q)
        free_space = FreeSpaceMap.from_world(self)
        for route in self.routes:
            reachable = free_space.is_reachable(np.asarray(route.waypoints, dtype=float))
            if not reachable.all():
                i = int(np.argmin(reachable))
                raise ValueError(
                    f"route '{route.name}' waypoint {i} {route.waypoints[i]} "
                    "is not reachable from the start"
                )

    def extent(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The walls' bounding box: ((x_min, y_min), (x_max, y_max)), m."""
        ends = np.array([w.start for w in self.walls] + [w.end for w in self.walls], dtype=float)
        lo, hi = ends.min(axis=0), ends.max(axis=0)
        return (float(lo[0]), float(lo[1])), (float(hi[0]), float(hi[1]))

    def furniture_corners(self) -> np.ndarray:
        """(F, 4, 2) footprint corners of the furniture, counter-clockwise, m."""
        return np.array(
            [box_corners(b.center, b.size, b.yaw_deg) for b in self.furniture], dtype=float
        ).reshape(-1, 4, 2)

    def object_corners(self) -> np.ndarray:
        """(O, 4, 2) footprint corners of the placed objects as they stand, counter-clockwise, m."""
        return np.array(
            [box_corners(*o.footprint()) for o in self.objects], dtype=float
        ).reshape(-1, 4, 2)

    def textures(self) -> TextureLibrary:
        """The world's texture set: the built-in one, plus :attr:`texture_set` if named.

        Raises:
            ConfigError: the extra set's manifest or a picture in it is bad.
        """
        return textures_for(self.texture_set)


def builtin_world_names() -> tuple[str, ...]:
    """Names of the worlds shipped in ``sim/worlds/`` (sorted)."""
    folder = resources.files("sim") / "worlds"
    return tuple(
        sorted(p.name.removesuffix(".toml") for p in folder.iterdir() if p.name.endswith(".toml"))
    )


@dataclass(frozen=True, slots=True)
class _StartInFile:
    """A world file's ``start`` table: the start pose with its heading in degrees."""

    x_m: float
    """x, m."""
    y_m: float
    """y, m."""
    yaw_deg: float = 0.0
    """Heading, counter-clockwise from +x, degrees."""

    def pose(self) -> Pose2:
        """The pose as the code holds it, heading in radians."""
        return Pose2(self.x_m, self.y_m, math.radians(self.yaw_deg))


@dataclass(frozen=True, slots=True)
class _WorldFile(World):
    """A world as its file states it: :class:`World`'s fields, the start as a :class:`_StartInFile`.

    Only :func:`load_world` builds one (with ``from_mapping``, which reads the field
    types) and turns it into a :class:`World` at once; that checks the rules.
    """

    start: _StartInFile  # type: ignore[assignment]

    def __post_init__(self) -> None:
        """Nothing to check yet: :meth:`world` builds the :class:`World` that checks."""

    def world(self, source: str) -> World:
        """The world, its start heading in radians.

        Raises:
            ConfigError: the world breaks a rule (``"<source>: <problem>"``).
        """
        values = {f.name: getattr(self, f.name) for f in dataclasses.fields(World)}
        try:
            return World(**{**values, "start": self.start.pose()})
        except ValueError as e:
            raise ConfigError(source, str(e)) from None


def load_world(name_or_path: str | Path) -> World:
    """Load a built-in world by name, or a world TOML file by path.

    Args:
        name_or_path: ``"lab"``, ``"campus"``, or the path of a ``.toml`` file.

    Raises:
        ConfigError: unknown name, unreadable file, or a world that breaks a rule
            (one line naming the file and the problem).
    """
    text = str(name_or_path)
    if text in builtin_world_names():
        with resources.as_file(resources.files("sim") / "worlds" / f"{text}.toml") as path:
            return _read(path)
    path = Path(text)
    if path.suffix != ".toml" and not path.exists():
        raise ConfigError(
            text,
            f"unknown world (built-in: {', '.join(builtin_world_names())}; "
            "or the path of a .toml world file)",
        )
    return _read(path)


def _read(path: Path) -> World:
    """The world of file ``path`` (its ``texture_set`` taken relative to the file)."""
    data = load_toml(path)
    if isinstance(data.get("texture_set"), str) and data["texture_set"]:
        data["texture_set"] = str(path.parent / data["texture_set"])
    return from_mapping(_WorldFile, data, str(path)).world(str(path))
