"""What a world's surfaces carry and what stands in it: textures, pictures, objects, trees.

Plain frozen dataclasses, read from a world file's tables by
:func:`shared.config.from_mapping` (``sim/worlds/lab.toml``'s header is the format's
reference). Frame and units as in :mod:`sim.world`: x, y on the floor plan, z up,
metres, degrees in files.

A texture is named by its manifest name in the world's texture set (the built-in
``sim/textures/``, see :mod:`sim.texture_library`), with an optional ``scale_m``:
the width in metres one copy of the picture covers on the surface (the height
follows the picture's aspect); unset, the picture keeps its manifest ``size_m``.
An empty name means "the default for this kind of surface" (:data:`DEFAULT_TEXTURES`).
Names are checked against the set when the world is built (:func:`texture_uses`
lists every name a world uses, with the entry that uses it).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

from shared.config import require

__all__ = [
    "DEFAULT_TEXTURES",
    "FURNITURE_KINDS",
    "OBJECT_KINDS",
    "PICTURE_REACH_M",
    "FloorPlan",
    "FloorRegion",
    "Lamp",
    "Picture",
    "PlacedObject",
    "Sky",
    "Tree",
    "check_scale",
    "named",
    "texture_uses",
]

#: Kinds of furniture box; each has default textures (top, long faces, short ends).
FURNITURE_KINDS = ("desk", "table", "shelf", "cabinet", "counter", "bench", "kiosk", "box")

#: Kinds of placed object: a solid box, a thin board (whiteboard, screen, sign stand),
#: a door leaf (turned about its hinge by ``open_deg``).
OBJECT_KINDS = ("box", "board", "door")

#: The texture a surface takes when its entry names none: (top, long faces, short ends)
#: per furniture kind, and one name per other surface.
DEFAULT_TEXTURES: dict[str, tuple[str, str, str]] = {
    "desk": ("desk_top", "desk_side", "desk_side"),
    "table": ("wood_oak", "wood_oak", "wood_oak"),
    "shelf": ("wood_oak", "bookshelf", "wood_oak"),
    "cabinet": ("wood_oak", "cabinet_drawers", "wood_oak"),
    "counter": ("marble_floor", "cabinet_doors", "wood_oak"),
    "bench": ("wood_oak", "wood_oak", "wood_oak"),
    "kiosk": ("brushed_metal", "noticeboard", "brushed_metal"),
    "box": ("brushed_metal", "brushed_metal", "brushed_metal"),
    "board": ("brushed_metal", "whiteboard", "brushed_metal"),
    "door": ("wood_oak", "door_wood", "wood_oak"),
    "wall": ("plaster_wall_painted", "", ""),
    "floor": ("carpet_floor", "", ""),
    "ceiling": ("ceiling_tiles", "", ""),
    "lamp": ("lamp_troffer", "", ""),
    "tree": ("tree_bark", "foliage", ""),
}


def check_scale(scale_m: float | None) -> None:
    """``scale_m`` is unset or a finite number > 0 (raises ``ValueError`` naming it)."""
    if scale_m is not None:
        require(math.isfinite(scale_m) and scale_m > 0,
                f"scale_m must be a finite number > 0 (m), got {scale_m}")


def _finite(name: str, *values: float) -> None:
    require(all(math.isfinite(v) for v in values), f"{name} must be finite, got {values}")


@dataclass(frozen=True, slots=True)
class FloorRegion:
    """A polygon of the floor with its own texture (a rug, a tiled hall, a lawn)."""

    polygon: tuple[tuple[float, float], ...]
    """(x, y) corners in order, m; at least 3. Later regions lie on top of earlier ones."""
    texture: str
    """Texture name."""
    scale_m: float | None = None
    """Width one copy of the texture covers, m; None = the texture's own size."""

    def __post_init__(self) -> None:
        require(len(self.polygon) >= 3,
                f"polygon needs at least 3 corners, got {len(self.polygon)}")
        for p in self.polygon:
            _finite("polygon corner", *p)
        require(bool(self.texture.strip()), "texture must be named")
        check_scale(self.scale_m)


@dataclass(frozen=True, slots=True)
class FloorPlan:
    """The floor's textures: one everywhere, regions on top."""

    texture: str = ""
    """Texture of the floor outside every region; "" = :data:`DEFAULT_TEXTURES` floor."""
    scale_m: float | None = None
    """Width one copy of the texture covers, m; None = the texture's own size."""
    regions: tuple[FloorRegion, ...] = ()
    """Polygons with other textures, painted in order."""

    def __post_init__(self) -> None:
        check_scale(self.scale_m)


@dataclass(frozen=True, slots=True)
class Lamp:
    """A lamp set in the ceiling above it: a bright rectangle that lights the room."""

    center: tuple[float, float]
    """(x, y) of its centre, m; a ceiling must cover it."""
    size: tuple[float, float] = (0.6, 1.2)
    """(length along ``yaw_deg``, width across it), m."""
    yaw_deg: float = 0.0
    """Orientation of the length axis, counter-clockwise from +x, degrees."""
    texture: str = ""
    """Texture (kind lamp); "" = :data:`DEFAULT_TEXTURES` lamp."""
    power: float = 1.0
    """Light it gives, relative to a standard office troffer (>= 0)."""
    on: bool = True
    """Whether it is lit (a scene change may switch lamps off)."""

    def __post_init__(self) -> None:
        _finite("lamp center, size and yaw", *self.center, *self.size, self.yaw_deg)
        require(min(self.size) > 0, f"size must be > 0 in both directions, got {self.size}")
        require(math.isfinite(self.power) and self.power >= 0,
                f"power must be >= 0, got {self.power}")


@dataclass(frozen=True, slots=True)
class Picture:
    """A flat rectangle on a wall face: poster, picture, sign, switch, window, door.

    Placed by a point ``at`` in front of the wall, within :data:`PICTURE_REACH_M` of
    its face: the picture goes on the nearest wall, centred where ``at`` projects on
    it, facing ``at``'s side.
    """

    at: tuple[float, float]
    """(x, y) in front of the wall, m."""
    texture: str
    """Texture name (its kind says what it is: picture, sign, window, door...)."""
    height_m: float
    """Height of the picture's centre above the floor, m."""
    size: tuple[float, float] | None = None
    """(width, height), m; None = the texture's own ``size_m``."""
    name: str = ""
    """Optional name, for scene changes ("poster_gone")."""
    movable: bool = False
    """Whether a scene change may take it away."""

    def __post_init__(self) -> None:
        _finite("at and height_m", *self.at, self.height_m)
        require(bool(self.texture.strip()), "texture must be named")
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        if self.size is not None:
            _finite("size", *self.size)
            require(min(self.size) > 0, f"size must be > 0 in both directions, got {self.size}")


#: How far a picture's ``at`` may be from the face of the wall it goes on, m.
PICTURE_REACH_M = 0.5


@dataclass(frozen=True, slots=True)
class PlacedObject:
    """A box or board standing on the floor plan, or a door leaf; an obstacle to the robot.

    Its long faces carry ``texture``, its short ends ``sides``, its top ``top``. A
    door is the closed leaf (``center``, ``size``, ``yaw_deg``) turned by ``open_deg``
    about the end of its length axis named by ``hinge``.
    """

    kind: str
    """One of :data:`OBJECT_KINDS`."""
    center: tuple[float, float]
    """(x, y) of the footprint's centre (a door: closed), m."""
    size: tuple[float, float]
    """(length along ``yaw_deg``, width across it), m."""
    height_m: float
    """Height of the object itself, m."""
    yaw_deg: float = 0.0
    """Orientation of the length axis (a door: closed), counter-clockwise from +x, degrees."""
    elevation_m: float = 0.0
    """Height of its bottom above the floor, m (a board on legs)."""
    texture: str = ""
    """Texture of the long faces; "" = :data:`DEFAULT_TEXTURES` of the kind."""
    sides: str = ""
    """Texture of the short ends; "" = the default."""
    top: str = ""
    """Texture of the top; "" = the default."""
    scale_m: float | None = None
    """Width one copy of a tiling texture covers, m; None = the texture's own size."""
    name: str = ""
    """Optional name, for scene changes."""
    movable: bool = False
    """Whether a scene change may move it (chairs, bins, boards)."""
    open_deg: float = 0.0
    """Doors only: how far the leaf is turned about its hinge, degrees (0 = closed)."""
    hinge: str = "start"
    """Doors only: the hinge end of the length axis, "start" (-length/2) or "end"."""
    sonar: bool = True
    """Whether the sonar ring hears it. False stands for the obstacles a sonar ring
    misses though the bumper hits them: glass at an angle, thin legs, a table top
    above the sonar plane. Still solid, still drawn (opaque, with its textures)."""

    def __post_init__(self) -> None:
        require(self.kind in OBJECT_KINDS,
                f"unknown object kind '{self.kind}' (known: {', '.join(OBJECT_KINDS)})")
        _finite("center, size, yaw, open", *self.center, *self.size, self.yaw_deg, self.open_deg)
        require(min(self.size) > 0, f"size must be > 0 in both directions, got {self.size}")
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        require(math.isfinite(self.elevation_m) and self.elevation_m >= 0,
                f"elevation_m must be >= 0, got {self.elevation_m}")
        require(self.hinge in ("start", "end"), f"hinge must be start or end, got '{self.hinge}'")
        require(self.kind == "door" or self.open_deg == 0.0, "open_deg is for doors only")
        check_scale(self.scale_m)

    def footprint(self) -> tuple[tuple[float, float], tuple[float, float], float]:
        """(center, size, yaw_deg) of the footprint as it stands (a door turned open)."""
        if self.open_deg == 0.0:
            return self.center, self.size, self.yaw_deg
        sign = -1.0 if self.hinge == "start" else 1.0
        yaw = math.radians(self.yaw_deg)
        half = 0.5 * self.size[0]
        hx = self.center[0] + sign * half * math.cos(yaw)
        hy = self.center[1] + sign * half * math.sin(yaw)
        turned = yaw + math.radians(self.open_deg)
        cx, cy = hx - sign * half * math.cos(turned), hy - sign * half * math.sin(turned)
        return (cx, cy), self.size, self.yaw_deg + self.open_deg


@dataclass(frozen=True, slots=True)
class Tree:
    """A tree: a textured trunk (vertical cylinder) under a foliage crown (a sphere)."""

    at: tuple[float, float]
    """(x, y) of the trunk's axis, m."""
    trunk_radius_m: float = 0.15
    """Trunk radius, m."""
    trunk_height_m: float = 2.2
    """Height of the trunk up to the crown's centre, m."""
    crown_radius_m: float = 1.3
    """Radius of the crown, m."""
    bark: str = ""
    """Trunk texture; "" = :data:`DEFAULT_TEXTURES` tree bark."""
    foliage: str = ""
    """Crown texture; "" = the default foliage."""

    def __post_init__(self) -> None:
        _finite("at", *self.at)
        for name in ("trunk_radius_m", "trunk_height_m", "crown_radius_m"):
            value = getattr(self, name)
            require(math.isfinite(value) and value > 0, f"{name} must be > 0, got {value}")
        require(self.crown_radius_m < self.trunk_height_m,
                f"crown_radius_m ({self.crown_radius_m}) must be < trunk_height_m "
                f"({self.trunk_height_m}): the crown would reach the floor")


@dataclass(frozen=True, slots=True)
class Sky:
    """Open sky where no ceiling is: a brightness gradient from horizon to zenith."""

    horizon: float = 235.0
    """Grey level at the horizon, 0..255."""
    zenith: float = 190.0
    """Grey level straight up, 0..255."""
    sun_azimuth_deg: float = 210.0
    """Azimuth the daylight comes from, counter-clockwise from +x, degrees (shading)."""

    def __post_init__(self) -> None:
        for name in ("horizon", "zenith"):
            value = getattr(self, name)
            require(0 <= value <= 255, f"{name} must be in [0, 255], got {value}")
        _finite("sun_azimuth_deg", self.sun_azimuth_deg)


def named(kind: str, name: str, part: int = 0) -> str:
    """``name``, or the default texture of ``kind`` (part 0 top, 1 long faces, 2 ends)."""
    return name or DEFAULT_TEXTURES[kind][part]


def texture_uses(world: object) -> Iterator[tuple[str, str]]:
    """(entry, texture name) for every texture a world names (defaults excluded).

    Args:
        world: a :class:`sim.world.World` (typed loosely: this module is below it).
    """
    for i, wall in enumerate(world.walls):  # type: ignore[attr-defined]
        for face in ("texture", "left", "right"):
            if getattr(wall, face):
                yield f"walls[{i}].{face}", getattr(wall, face)
    for i, box in enumerate(world.furniture):  # type: ignore[attr-defined]
        for face in ("top", "front", "sides"):
            if getattr(box, face):
                yield f"furniture[{i}].{face}", getattr(box, face)
    for i, ceiling in enumerate(world.ceilings):  # type: ignore[attr-defined]
        if ceiling.texture:
            yield f"ceilings[{i}].texture", ceiling.texture
    floor = world.floor  # type: ignore[attr-defined]
    if floor.texture:
        yield "floor.texture", floor.texture
    for i, region in enumerate(floor.regions):
        yield f"floor.regions[{i}].texture", region.texture
    for i, lamp in enumerate(world.lamps):  # type: ignore[attr-defined]
        if lamp.texture:
            yield f"lamps[{i}].texture", lamp.texture
    for i, picture in enumerate(world.pictures):  # type: ignore[attr-defined]
        yield f"pictures[{i}].texture", picture.texture
    for i, obj in enumerate(world.objects):  # type: ignore[attr-defined]
        for face in ("texture", "sides", "top"):
            if getattr(obj, face):
                yield f"objects[{i}].{face}", getattr(obj, face)
    for i, tree in enumerate(world.trees):  # type: ignore[attr-defined]
        for part in ("bark", "foliage"):
            if getattr(tree, part):
                yield f"trees[{i}].{part}", getattr(tree, part)
