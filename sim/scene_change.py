"""What changed between the day a route was taught and the day it is repeated.

A real building is never the same twice: lamps are on or off, the sun has moved,
chairs and boards stand elsewhere, a door is open, a poster is gone, people walk
about. Each change here is a scenario option of the repeat (``vmnav demo``,
``vmnav bench follow``) and a pure function of the world, seeded by the caller's
generator. The people are the simulation's (``SimConfig.people``): nobody walks
about while a route is taught.

Rules:

1. **Pure.** :func:`change_world` returns a new :class:`~sim.world.World`
   (``dataclasses.replace``), so the changed world is checked by the same rules
   as a world file: its start and routes keep :data:`~sim.world.CLEARANCE_M`
   from every wall and object, every waypoint stays reachable. A change the world
   cannot take (a door closed across a route, a name the world does not have)
   raises ``ValueError`` naming it.
2. **Moved objects never block the repeat.** Only objects the world file flags
   ``movable`` move (not doors: they open and close), each to a place found by
   :func:`sim._object_moves.placed_elsewhere`: within 1 m and 45 degrees, in free
   space, clear of everything else, away from the points kept clear (the
   repeat's start), with the routes still clear. An object with no such place
   stays where it was (:class:`ChangedWorld` counts it).
3. **Light.** Steady changes change the world's lighting: a scale of the whole
   scene's light, lamps switched off, daylight at another hour
   (:func:`daylight_at`; the world file describes its daylight at
   :data:`TEACH_HOUR`). A step during the repeat is a gain of the whole scene's
   light from a given time on (:meth:`LightingChange.gain_at`, the simulation's
   ``light_gain_at``), applied to the rendered scene before the camera sees it,
   so the camera's exposure control has to follow it.
4. **Removed** pictures (posters, signs) are a fraction of those flagged
   ``movable``, or pictures and objects named.
5. **Shares of nothing are nothing.** A share of the lamps, movable objects or
   movable pictures of a world that has none changes nothing (one benchmark
   command fits every world); :class:`ChangedWorld` counts what a change did. A
   name the world does not have is an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt

from shared.config import require
from sim._geometry import box_corners
from sim._object_moves import placed_elsewhere
from sim.decor import PlacedObject
from sim.world import World

TEACH_HOUR = 12.0
"""Hour of the day a world file's daylight and sun describe (solar time, h)."""
_SUN_DEG_PER_H = 15.0  # the sun's azimuth turns clockwise (seen from above) this fast
_NIGHT_SKY = 0.15  # the sky's grey levels at night, relative to the teach's
OPEN_DEG = 90.0
"""How far an opened door turns, degrees."""


@dataclass(frozen=True, slots=True)
class LightingChange:
    """How the light differs from the teach.

    Attributes:
        scale: the whole scene's light, relative to the teach (0.5: half as bright),
            for the whole repeat; > 0.
        lamps_off: share of the lit lamps switched off, in [0, 1].
        hour: daylight (outdoors and through windows) at this solar hour, in [0, 24];
            None: as taught (:data:`TEACH_HOUR`).
        step_factor: the scene's light is further multiplied by this from ``step_at_s``
            on (1 = no step; 0.4 = someone switched most lights off); > 0.
        step_at_s: time of the step, s since the repeat's simulation started; >= 0.
    """

    scale: float = 1.0
    lamps_off: float = 0.0
    hour: float | None = None
    step_factor: float = 1.0
    step_at_s: float = 0.0

    def __post_init__(self) -> None:
        require(math.isfinite(self.scale) and self.scale > 0,
                f"scale must be > 0, got {self.scale}")
        require(0.0 <= self.lamps_off <= 1.0,
                f"lamps-off must be in [0, 1], got {self.lamps_off}")
        require(self.hour is None or 0.0 <= self.hour <= 24.0,
                f"hour must be in [0, 24], got {self.hour}")
        require(math.isfinite(self.step_factor) and self.step_factor > 0,
                f"step factor must be > 0, got {self.step_factor}")
        require(math.isfinite(self.step_at_s) and self.step_at_s >= 0,
                f"step time must be >= 0 s, got {self.step_at_s}")

    def gain_at(self, t_ns: int) -> float:
        """The step's gain on the scene's light at simulation time ``t_ns``: 1 before
        ``step_at_s``, ``step_factor`` from then on (the steady changes are in the world)."""
        return self.step_factor if t_ns >= round(self.step_at_s * 1e9) else 1.0

    @property
    def has_step(self) -> bool:
        """Whether the light changes during the repeat."""
        return self.step_factor != 1.0


@dataclass(frozen=True, slots=True)
class SceneChange:
    """Everything that differs between teach and repeat, except the people.

    Attributes:
        lighting: the light.
        moved_fraction: share of the movable objects moved, in [0, 1];
            ``round(fraction * count)`` of them are drawn.
        removed_fraction: share of the movable pictures taken away, in [0, 1].
        removed: names of pictures or objects taken away.
        doors: (door name, opening in degrees: 0 closed) for each door changed.
    """

    lighting: LightingChange = field(default_factory=LightingChange)
    moved_fraction: float = 0.0
    removed_fraction: float = 0.0
    removed: tuple[str, ...] = ()
    doors: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        require(0.0 <= self.moved_fraction <= 1.0,
                f"moved fraction must be in [0, 1], got {self.moved_fraction}")
        require(0.0 <= self.removed_fraction <= 1.0,
                f"removed fraction must be in [0, 1], got {self.removed_fraction}")
        for name, opening in self.doors:
            require(math.isfinite(opening) and -180.0 <= opening <= 180.0,
                    f"door '{name}': opening must be in [-180, 180] degrees, got {opening}")

    @property
    def is_none(self) -> bool:
        """Whether nothing changes."""
        return self == SceneChange()


@dataclass(frozen=True, slots=True)
class ChangedWorld:
    """The world after a change, and what the change did.

    Attributes:
        world: the changed world (it satisfies every rule of :mod:`sim.world`).
        change: the change applied.
        moved: indices of the objects moved, in ``world.objects``.
        moved_from: those objects as they stood when the route was taught.
        stuck: indices of the objects drawn to move that found no place (rule 2).
        lamps_off: indices of the lamps switched off, in ``world.lamps``.
        removed_pictures: how many pictures were taken away.
        removed_objects: how many objects were taken away.
    """

    world: World
    change: SceneChange
    moved: tuple[int, ...] = ()
    moved_from: tuple[PlacedObject, ...] = ()
    stuck: tuple[int, ...] = ()
    lamps_off: tuple[int, ...] = ()
    removed_pictures: int = 0
    removed_objects: int = 0

    def moved_footprints(self) -> list[tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]:
        """Per moved object, its footprint's corners (4, 2) as taught and as it stands, m."""
        return [(box_corners(*old.footprint()), box_corners(*self.world.objects[i].footprint()))
                for i, old in zip(self.moved, self.moved_from, strict=True)]


def change_world(world: World, change: SceneChange, rng: np.random.Generator,
                 keep_clear_xy: npt.NDArray[np.float64] | None = None) -> ChangedWorld:
    """Apply ``change`` to ``world`` (see the module's rules), in a fixed order: light,
    doors, removals, moves (so the same seed gives the same world).

    Args:
        world: the world as it was taught.
        change: what changed.
        rng: the only source of randomness (lamps, pictures and objects picked, new places).
        keep_clear_xy: (K, 2) points on the floor plan no moved object may come within
            1 m of (the repeat's start), m; None: none.

    Raises:
        ValueError: the change does not fit the world (naming what: a light scale out of
            range, an unknown name, a door that blocks a route).
    """
    world, lamps_off = relit_world(world, change.lighting, rng)
    world = doors_set(world, change.doors)
    before = world
    world = without_named(world, change.removed)
    world = without_pictures(world, change.removed_fraction, rng)
    removed_pictures = len(before.pictures) - len(world.pictures)
    removed_objects = len(before.objects) - len(world.objects)
    keep = np.empty((0, 2)) if keep_clear_xy is None else np.asarray(keep_clear_xy, float)
    unmoved = world.objects
    world, moved, stuck = move_objects(world, change.moved_fraction, rng, keep.reshape(-1, 2))
    return ChangedWorld(world, change, moved=moved, moved_from=tuple(unmoved[i] for i in moved),
                        stuck=stuck, lamps_off=lamps_off, removed_pictures=removed_pictures,
                        removed_objects=removed_objects)


def daylight_at(hour: float) -> float:
    """Daylight at a solar ``hour`` relative to :data:`TEACH_HOUR`: the sine of the sun's
    elevation on an equinox at the equator, ``sin(pi (hour - 6) / 12)``, 0 at night.

    A crude model (no latitude, season or clouds): it gives dawn and dusk their
    dimness and the night its darkness, which is what a change of hour does to a
    repeat.
    """
    return max(0.0, math.sin(math.pi * (hour - 6.0) / 12.0))


def relit_world(world: World, lighting: LightingChange, rng: np.random.Generator
                ) -> tuple[World, tuple[int, ...]]:
    """``world`` under the steady light changes; the indices of the lamps switched off.

    Raises:
        ValueError: the scaled brightness leaves (0, 255).
    """
    if lighting.scale != 1.0:
        brightness = world.lighting.brightness * lighting.scale
        require(0.0 < brightness < 255.0,
                f"light scale {lighting.scale} makes the brightness {brightness:.0f} of world "
                f"'{world.name}' leave (0, 255)")
        world = replace(world, lighting=replace(world.lighting, brightness=brightness))
    if lighting.hour is not None:
        relative = daylight_at(lighting.hour) / daylight_at(TEACH_HOUR)
        sky = max(relative, _NIGHT_SKY)
        world = replace(
            world,
            lighting=replace(world.lighting, daylight=world.lighting.daylight * relative),
            sky=replace(world.sky, horizon=world.sky.horizon * sky,
                        zenith=world.sky.zenith * sky,
                        sun_azimuth_deg=world.sky.sun_azimuth_deg
                        - _SUN_DEG_PER_H * (lighting.hour - TEACH_HOUR)))
    if lighting.lamps_off == 0.0:
        return world, ()
    lit = [i for i, lamp in enumerate(world.lamps) if lamp.on]
    off = tuple(sorted(int(i) for i in rng.choice(lit, size=round(lighting.lamps_off * len(lit)),
                                                  replace=False)))
    lamps = tuple(replace(lamp, on=False) if i in off else lamp
                  for i, lamp in enumerate(world.lamps))
    return replace(world, lamps=lamps), off


def doors_set(world: World, doors: tuple[tuple[str, float], ...]) -> World:
    """``world`` with each named door turned to its opening (degrees, 0 closed).

    Raises:
        ValueError: no door of that name, or the door as set blocks a route or the start.
    """
    for name, opening in doors:
        found = [i for i, o in enumerate(world.objects) if o.kind == "door" and o.name == name]
        if not found:
            known = sorted(o.name for o in world.objects if o.kind == "door" and o.name)
            raise ValueError(f"world '{world.name}' has no door named '{name}' (doors: "
                             f"{', '.join(known) or 'none with a name'})")
        objects = tuple(replace(o, open_deg=opening) if i in found else o
                        for i, o in enumerate(world.objects))
        try:
            world = replace(world, objects=objects)
        except ValueError as e:
            raise ValueError(f"door '{name}' at {opening:g} deg: {e}") from None
    return world


def without_named(world: World, names: tuple[str, ...]) -> World:
    """``world`` without the pictures and objects named ``names``.

    Raises:
        ValueError: a name no picture or object of the world has.
    """
    if not names:
        return world
    known = {p.name for p in world.pictures} | {o.name for o in world.objects}
    for name in names:
        if name not in known:
            raise ValueError(f"world '{world.name}' has no picture or object named '{name}' "
                             f"(named: {', '.join(sorted(known - {''})) or 'none'})")
    return replace(world, pictures=tuple(p for p in world.pictures if p.name not in names),
                   objects=tuple(o for o in world.objects if o.name not in names))


def without_pictures(world: World, fraction: float, rng: np.random.Generator) -> World:
    """``world`` without ``round(fraction * count)`` of its movable pictures, drawn at random."""
    if fraction == 0.0:
        return world
    movable = [i for i, p in enumerate(world.pictures) if p.movable]
    gone = {int(i) for i in rng.choice(movable, size=round(fraction * len(movable)),
                                       replace=False)}
    return replace(world, pictures=tuple(p for i, p in enumerate(world.pictures)
                                         if i not in gone))


def movable_indices(world: World) -> tuple[int, ...]:
    """Indices of the objects of ``world.objects`` that may move (``movable``, not doors)."""
    return tuple(i for i, o in enumerate(world.objects) if o.movable and o.kind != "door")


def move_objects(world: World, fraction: float, rng: np.random.Generator,
                 keep_clear_xy: npt.NDArray[np.float64]
                 ) -> tuple[World, tuple[int, ...], tuple[int, ...]]:
    """Move ``round(fraction * count)`` of the movable objects, chosen at random (rule 2).

    Args:
        world: the world.
        fraction: share moved, in [0, 1].
        rng: picks the objects and their new places.
        keep_clear_xy: (K, 2) points kept clear, m.

    Returns:
        The world with the objects moved, the indices of those moved and of those
        that found no place (see :class:`ChangedWorld`).
    """
    if fraction == 0.0:
        return world, (), ()
    movable = movable_indices(world)
    chosen = rng.choice(movable, size=round(fraction * len(movable)), replace=False)
    moved: list[int] = []
    stuck: list[int] = []
    for index in sorted(int(i) for i in chosen):
        placed = placed_elsewhere(world, index, rng, keep_clear_xy)
        if placed is None:
            stuck.append(index)
        else:
            world = placed
            moved.append(index)
    return world, tuple(moved), tuple(stuck)
