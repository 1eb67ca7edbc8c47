"""The 3D landmark field: textured square patches on walls, furniture and ceilings.

Size. Each surface (a face of a wall, a vertical side of a piece of furniture,
a ceiling rectangle) carries square patches of one size: its element's
``patch_size_m``, else the world's ``landmarks.patch_size_m``. Patches are
axis-aligned on their surface (edges horizontal and vertical on walls and
furniture, along x and y on ceilings).

Placement. Each surface is covered with a jittered grid of square cells of side
``max(1 / sqrt(density), pitch)``, where ``pitch = size + 3 cm``: one candidate
per cell, uniform in a central square of side ``min(0.8 cell, cell - pitch)``.
Expected counts follow the density while no two patches clump or overlap:
centres in different cells are at least ``pitch`` apart along one of the
surface's axes, so neighbouring patches keep a plain gap of >= 3 cm. A density
above ``1 / pitch^2`` saturates at one patch per cell of side ``pitch``. A
candidate is kept only if

* it is off the floor (centre >= 0.3 m up and bottom edge >= 3 cm up on walls),
  away from wall ends, corners and edges (the whole patch fits on its surface),
  and not above a ceiling;
* the points 5 cm in front of its centre and of its two side edges are in free
  space (not in a wall, not in furniture, inside the world's extent), which
  drops patches hidden behind a desk or in a wall junction;
* the space in front of it (25 cm out) is reachable from the start
  (:class:`~sim.free_space.FreeSpaceMap`), so no patch decorates the inside of a
  building block. Both faces of a wall get patches where both face reachable space.

Patches sit :data:`PROUD_M` in front of their surface, so a line of sight to a
patch does not graze the wall it is on.

Texture (16 x 16 grey levels; row 0 at the top, column 0 at the left as one
faces the patch; level 128 is the plain surface's own level). Each patch is
an axis-aligned X-junction of four quadrants with random grey levels, such that
both arms have a strong step (>= 90 grey levels on at least one side), plus a
smooth random quadratic shading, faded radially to 128 towards the border so
that the patch blends into a plain surface without corners at its edge. Steps
dominate Harris' structure tensor while smooth shading hardly registers in it, so
the patch's one dominant Harris corner is its centre (the generator verifies this
with ``cv2.cornerHarris`` on each patch and redraws the rare failures). The
random levels and shading make 11 x 11 ZNCC scores between different patches
much lower than a patch's score with itself (see tests/sim/test_landmarks.py for
the figures); lookalikes remain possible, as with real natural landmarks.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from shared.errors import check_shape
from sim._geometry import point_segment_distances, points_in_polygons
from sim.free_space import WALL_HALF_THICKNESS_M, FreeSpaceMap
from sim.world import World

PATCH_PX = 16
"""Side of a landmark texture, pixels."""

PROUD_M = 0.005
"""Distance of a patch in front of its surface, m."""

_PROBE_M = 0.05  # free-space probe in front of the patch
_REACH_PROBE_M = 0.25  # reachability probe in front of the patch (beyond the raster's wall cells)
_WALL_MIN_Z_M = 0.3  # lowest patch centre on walls
_WALL_END_MARGIN_M = 0.25  # least distance of a patch centre from a wall's end
_EDGE_MARGIN_M = 0.03  # least gap between a patch's edge and its surface's edge
_PATCH_GAP_M = 0.03  # least gap between neighbouring patches on one surface
_JITTER = 0.8  # a candidate lies uniformly in at most the central 80 % of its grid cell

# Texture design (grey levels around 128, pixels of the 16 x 16 patch).
_LEVEL_MAX = 90.0  # quadrant levels are 128 + U(-90, 90)
_MIN_ARM_STEP = 90.0  # each arm of the X has a step of at least this on one side
_SHADING_AMPLITUDE = 40.0  # std of the smooth quadratic shading, grey levels
_FADE_START_PX = 4.0  # the radial fade to 128 begins here (from the centre)
_FADE_END_PX = 7.5  # and is complete here: the middle of the border row and column
_HARRIS_BLOCK, _HARRIS_KSIZE, _HARRIS_K = 3, 3, 0.04  # the acceptance check's detector
_HARRIS_MAX_OFFSET_PX = 1.5  # the response's maximum must lie this close to the centre
_HARRIS_SCALES = (1.0, 0.75)  # patch sizes checked, relative to 16 px


class Surface(enum.IntEnum):
    """What a landmark patch is on."""

    WALL = 0  #: a face of a wall; normal horizontal
    FURNITURE = 1  #: a vertical side of a piece of furniture; normal horizontal
    CEILING = 2  #: a ceiling; normal (0, 0, -1)


@dataclass(frozen=True, eq=False)
class LandmarkField:
    """All landmark patches of a world (arrays are read-only).

    Attributes:
        ids: (N,) int64, unique ids 0..N-1.
        positions_w: (N, 3) float64, patch centres, world frame (z up, floor at 0), m.
        normals_w: (N, 3) float64, unit normals of the patches, pointing into free space.
        surface: (N,) int8, :class:`Surface` values.
        sizes_m: (N,) float64, side of each square patch, m (the texture spans it).
        textures: (N, 16, 16) uint8, grey levels (see the module docstring).
    """

    ids: npt.NDArray[np.int64]
    positions_w: npt.NDArray[np.float64]
    normals_w: npt.NDArray[np.float64]
    surface: npt.NDArray[np.int8]
    sizes_m: npt.NDArray[np.float64]
    textures: npt.NDArray[np.uint8]

    def __post_init__(self) -> None:
        n = self.ids.shape[0]
        check_shape("ids", self.ids.shape, (n,))
        check_shape("positions_w", self.positions_w.shape, (n, 3))
        check_shape("normals_w", self.normals_w.shape, (n, 3))
        check_shape("surface", self.surface.shape, (n,))
        check_shape("sizes_m", self.sizes_m.shape, (n,))
        check_shape("textures", self.textures.shape, (n, PATCH_PX, PATCH_PX))
        arrays = (
            self.ids, self.positions_w, self.normals_w, self.surface, self.sizes_m, self.textures
        )
        for array in arrays:
            array.setflags(write=False)

    def __len__(self) -> int:
        return int(self.ids.shape[0])


def generate_landmarks(
    world: World,
    rng: np.random.Generator,
    density_scale: float = 1.0,
    free_space: FreeSpaceMap | None = None,
) -> LandmarkField:
    """Place and texture the landmark patches of ``world``.

    Args:
        world: the world (its ``landmarks`` give patches per m^2 and the default
            patch size; walls, boxes and ceilings may set their own size).
        rng: the only source of randomness; the same state gives the same field.
        density_scale: multiplies all densities (>= 0).
        free_space: the world's free-space map, if already built (else built here).

    Returns:
        The field, in the order walls, furniture, ceilings.

    Raises:
        ValueError: ``density_scale`` < 0.
    """
    if not density_scale >= 0:
        raise ValueError(f"density_scale must be >= 0, got {density_scale}")
    density = world.landmarks
    parts = [
        _wall_candidates(world, rng, density.wall_per_m2 * density_scale),
        _furniture_candidates(world, rng, density.furniture_per_m2 * density_scale),
        _ceiling_candidates(world, rng, density.ceiling_per_m2 * density_scale),
    ]
    positions, normals, sizes = (np.concatenate([p[k] for p in parts]) for k in range(3))
    surface = np.concatenate(
        [np.full(len(p[0]), kind, np.int8) for p, kind in zip(parts, Surface, strict=True)]
    )
    keep = _in_free_space(
        world, free_space or FreeSpaceMap.from_world(world), positions, normals, sizes / 2
    )
    n = int(np.count_nonzero(keep))
    return LandmarkField(
        ids=np.arange(n, dtype=np.int64),
        positions_w=positions[keep],
        normals_w=normals[keep],
        surface=surface[keep],
        sizes_m=sizes[keep],
        textures=make_textures(rng, n),
    )


# ---------------------------------------------------------------------------
# Placement
# ---------------------------------------------------------------------------

_Candidates = tuple[
    npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]
]  # positions (K, 3), normals (K, 3), patch sides (K,)


def _jittered_grid(
    rng: np.random.Generator, width: float, height: float, density: float, pitch: float
) -> npt.NDArray[np.float64]:
    """Points (K, 2) in [0, width] x [0, height], one per jittered grid cell.

    The cells are squares of side ``max(1 / sqrt(density), pitch)``; each point lies
    uniformly in a central square of its cell small enough that points in
    different cells are >= ``pitch`` apart along u or v (Chebyshev distance).
    """
    if density <= 0 or width <= 0 or height <= 0:
        return np.empty((0, 2))
    cell = max(1.0 / math.sqrt(density), pitch)
    span = min(_JITTER, 1.0 - pitch / cell)  # side of the central square, in cells
    origin = -rng.uniform(0.0, cell, 2)
    nu = math.ceil((width - origin[0]) / cell)
    nv = math.ceil((height - origin[1]) / cell)
    iu, iv = np.meshgrid(np.arange(nu), np.arange(nv), indexing="ij")
    corners = origin + cell * np.stack([iu.ravel(), iv.ravel()], axis=1)
    points = corners + cell * ((1 - span) / 2 + span * rng.uniform(0.0, 1.0, corners.shape))
    inside = (
        (points[:, 0] >= 0)
        & (points[:, 0] <= width)
        & (points[:, 1] >= 0)
        & (points[:, 1] <= height)
    )
    return points[inside]


def _vertical_face(
    rng: np.random.Generator,
    start: npt.NDArray[np.float64],
    direction: npt.NDArray[np.float64],
    length: float,
    z_range: tuple[float, float],
    u_margin: float,
    normal_xy: npt.NDArray[np.float64],
    offset: float,
    density: float,
    size: float,
) -> _Candidates:
    """Candidates on a vertical rectangle: along ``direction`` from ``start``, z in ``z_range``."""
    uv = _jittered_grid(
        rng, length - 2 * u_margin, z_range[1] - z_range[0], density, size + _PATCH_GAP_M
    )
    xy = start + np.outer(uv[:, 0] + u_margin, direction) + offset * normal_xy
    positions = np.column_stack([xy, uv[:, 1] + z_range[0]])
    normals = np.tile(np.append(normal_xy, 0.0), (len(uv), 1))
    return positions, normals, np.full(len(uv), size)


def _patch_size(own: float | None, world: World) -> float:
    """An element's own patch side, else the world's default, m."""
    return world.landmarks.patch_size_m if own is None else own


def _wall_candidates(world: World, rng: np.random.Generator, density: float) -> _Candidates:
    out: list[_Candidates] = []
    for wall in world.walls:
        size = _patch_size(wall.patch_size_m, world)
        half = size / 2
        # A wall's end may sit on another wall's centre line: keep clear of that wall too.
        u_margin = max(_WALL_END_MARGIN_M, WALL_HALF_THICKNESS_M + half + _EDGE_MARGIN_M)
        a, b = np.asarray(wall.start, dtype=float), np.asarray(wall.end, dtype=float)
        direction = (b - a) / wall.length_m
        z_range = (
            max(_WALL_MIN_Z_M, half + _EDGE_MARGIN_M),
            wall.height_m - half - _EDGE_MARGIN_M,
        )
        left = np.array([-direction[1], direction[0]])
        for normal in (left, -left):
            out.append(
                _vertical_face(
                    rng,
                    a,
                    direction,
                    wall.length_m,
                    z_range,
                    u_margin,
                    normal,
                    WALL_HALF_THICKNESS_M + PROUD_M,
                    density,
                    size,
                )
            )
    return _stack(out)


def _furniture_candidates(world: World, rng: np.random.Generator, density: float) -> _Candidates:
    out: list[_Candidates] = []
    for box, corners in zip(world.furniture, world.furniture_corners(), strict=True):
        size = _patch_size(box.patch_size_m, world)
        margin = size / 2 + _EDGE_MARGIN_M
        for k in range(4):
            a, b = corners[k], corners[(k + 1) % 4]
            length = float(np.linalg.norm(b - a))
            direction = (b - a) / length
            outward = np.array([direction[1], -direction[0]])  # corners run counter-clockwise
            out.append(
                _vertical_face(
                    rng,
                    a,
                    direction,
                    length,
                    (margin, box.height_m - margin),
                    margin,
                    outward,
                    PROUD_M,
                    density,
                    size,
                )
            )
    return _stack(out)


def _ceiling_candidates(world: World, rng: np.random.Generator, density: float) -> _Candidates:
    out: list[_Candidates] = []
    for ceiling in world.ceilings:
        size = _patch_size(ceiling.patch_size_m, world)
        margin = size / 2 + _EDGE_MARGIN_M
        lo = np.asarray(ceiling.min_corner, dtype=float) + margin
        extent = np.asarray(ceiling.max_corner, dtype=float) - margin - lo
        xy = lo + _jittered_grid(rng, extent[0], extent[1], density, size + _PATCH_GAP_M)
        positions = np.column_stack([xy, np.full(len(xy), ceiling.height_m - PROUD_M)])
        normals = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
        out.append((positions, normals, np.full(len(xy), size)))
    return _stack(out)


def _stack(parts: list[_Candidates]) -> _Candidates:
    if not parts:
        return np.empty((0, 3)), np.empty((0, 3)), np.empty(0)
    positions, normals, sizes = (np.concatenate([p[k] for p in parts]) for k in range(3))
    return positions, normals, sizes


def _in_free_space(
    world: World,
    free_space: FreeSpaceMap,
    positions: npt.NDArray[np.float64],
    normals: npt.NDArray[np.float64],
    half: npt.NDArray[np.float64],
) -> npt.NDArray[np.bool_]:
    """Which candidates face free, reachable space (see the module docstring).

    ``half`` is (K,) half the side of each candidate's patch, m.
    """
    if len(positions) == 0:
        return np.zeros(0, bool)
    # Probes 5 cm in front of the centre and of the two side edges (for a ceiling
    # patch: of two opposite corners).
    side = np.cross(normals, [0.0, 0.0, 1.0])
    flat = np.linalg.norm(side, axis=1) < 0.5
    side[flat] = [1.0, 1.0, 0.0]
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    front = positions + _PROBE_M * normals
    ok = np.ones(len(positions), bool)
    for sign in (0.0, 1.0, -1.0):
        ok &= _free_at(world, front + (sign * half)[:, None] * side)
    reach = positions[:, :2] + _REACH_PROBE_M * normals[:, :2]
    ok &= free_space.is_reachable(reach)
    return ok


def _free_at(world: World, points: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]:
    """Whether 3D points (N, 3) are in the extent, outside walls and furniture, below ceilings."""
    (x0, y0), (x1, y1) = world.extent()
    xy, z = points[:, :2], points[:, 2]
    free = (xy[:, 0] > x0) & (xy[:, 0] < x1) & (xy[:, 1] > y0) & (xy[:, 1] < y1) & (z > 0)
    a = np.array([w.start for w in world.walls], dtype=float)
    b = np.array([w.end for w in world.walls], dtype=float)
    heights = np.array([w.height_m for w in world.walls])
    in_wall = (point_segment_distances(xy, a, b) < WALL_HALF_THICKNESS_M) & (z[:, None] < heights)
    free &= ~in_wall.any(axis=1)
    if world.furniture:
        box_heights = np.array([f.height_m for f in world.furniture])
        in_box = points_in_polygons(xy, world.furniture_corners()) & (z[:, None] < box_heights)
        free &= ~in_box.any(axis=1)
    for ceiling in world.ceilings:
        under = (
            (xy[:, 0] >= ceiling.min_corner[0])
            & (xy[:, 0] <= ceiling.max_corner[0])
            & (xy[:, 1] >= ceiling.min_corner[1])
            & (xy[:, 1] <= ceiling.max_corner[1])
        )
        free &= ~(under & (z > ceiling.height_m))
    return free


# ---------------------------------------------------------------------------
# Textures
# ---------------------------------------------------------------------------


def _texture_basis() -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.intp], npt.NDArray[np.float64]
]:
    """Quadrant index (16, 16), quadratic shading basis (5, 16, 16) and radial fade (16, 16)."""
    c = (PATCH_PX - 1) / 2
    rows, cols = np.mgrid[0:PATCH_PX, 0:PATCH_PX].astype(float)
    quadrant = np.where(
        rows < c, np.where(cols < c, 0, 1), np.where(cols < c, 3, 2)
    )  # TL, TR, BR, BL
    u, v = (cols - c) / (c + 0.5), (rows - c) / (c + 0.5)
    # Zero-mean-ish, unit-variance-ish quadratic shapes; smooth, so nearly invisible to Harris.
    basis = (
        np.stack([u, v, u * u - 1 / 3, v * v - 1 / 3, u * v])
        / np.sqrt([1 / 3, 1 / 3, 4 / 45, 4 / 45, 1 / 9])[:, None, None]
    )
    t = np.clip(
        (np.hypot(cols - c, rows - c) - _FADE_START_PX) / (_FADE_END_PX - _FADE_START_PX), 0.0, 1.0
    )
    fade = 0.5 + 0.5 * np.cos(np.pi * t)  # raised cosine: 1 inside, 0 at the border
    return quadrant, basis / np.sqrt(len(basis)), fade


def make_textures(rng: np.random.Generator, count: int) -> npt.NDArray[np.uint8]:
    """Draw ``count`` landmark textures (see the module docstring for the design).

    Args:
        rng: the random generator.
        count: number of textures.

    Returns:
        (count, 16, 16) uint8.
    """
    out = np.empty((count, PATCH_PX, PATCH_PX), np.uint8)
    todo = np.arange(count)
    while todo.size:
        candidates = _draw_textures(rng, todo.size)
        good = _corner_at_centre(candidates)
        out[todo[good]] = candidates[good]
        todo = todo[~good]
    return out


def _draw_textures(rng: np.random.Generator, count: int) -> npt.NDArray[np.uint8]:
    quadrant, basis, fade = _texture_basis()
    levels = np.empty((0, 4))
    while len(levels) < count:
        q = rng.uniform(-_LEVEL_MAX, _LEVEL_MAX, (2 * count + 8, 4))  # TL, TR, BR, BL
        vertical_arm = np.maximum(abs(q[:, 0] - q[:, 1]), abs(q[:, 3] - q[:, 2]))
        horizontal_arm = np.maximum(abs(q[:, 0] - q[:, 3]), abs(q[:, 1] - q[:, 2]))
        levels = np.concatenate(
            [levels, q[(vertical_arm >= _MIN_ARM_STEP) & (horizontal_arm >= _MIN_ARM_STEP)]]
        )
    x_junction = levels[:count][:, quadrant]  # (count, 16, 16)
    shading = _SHADING_AMPLITUDE * np.einsum(
        "nk,kij->nij", rng.normal(0.0, 1.0, (count, len(basis))), basis
    )
    return np.clip(np.rint(128.0 + (x_junction + shading) * fade), 0, 255).astype(np.uint8)


def _corner_at_centre(textures: npt.NDArray[np.uint8]) -> npt.NDArray[np.bool_]:
    """Whether each texture's Harris response peaks at its centre, embedded in plain 128 grey.

    Checked at full size and at 3/4 size (a patch about 2.5 m away on the default lens).
    """
    n = len(textures)
    tile = 2 * PATCH_PX
    pad = (tile - PATCH_PX) // 2
    mosaic = np.full((n * tile, tile), 128, np.float32)  # a column of tiles with plain margins
    mosaic.reshape(n, tile, tile)[:, pad : pad + PATCH_PX, pad : pad + PATCH_PX] = textures
    ok = np.ones(n, bool)
    for scale in _HARRIS_SCALES:
        size = round(tile * scale)
        image = (
            mosaic
            if size == tile
            else cv2.resize(mosaic, (size, n * size), interpolation=cv2.INTER_AREA)
        )
        response = cv2.cornerHarris(image, _HARRIS_BLOCK, _HARRIS_KSIZE, _HARRIS_K)
        rows, cols = np.divmod(response.reshape(n, size * size).argmax(axis=1), size)
        centre = (size - 1) / 2
        ok &= np.hypot(rows - centre, cols - centre) <= _HARRIS_MAX_OFFSET_PX
    return ok
