"""People as textured figures through the fisheye: trousers, a shirt with sleeves, skin,
a face and hair, ray-cast per pixel through the shared camera model.

A figure is a few solids standing on the floor at the person's position, turned to
their heading (person frame: forward, left, up; heights scaled to the person's
height, :data:`_REFERENCE_HEIGHT_M` as drawn here):

=========  ==============================  ========================================
part       solid                           look
=========  ==============================  ========================================
legs       two vertical cylinders          trousers; swing with the walk
torso      a vertical elliptic cylinder    shirt
arms       two vertical cylinders          shirt sleeves, skin hands; swing
neck       a vertical cylinder             skin
head       a sphere                        face in front, hair on top and behind
=========  ==============================  ========================================

Per frame and person (:meth:`PersonFigures.draw`): the figure's bounding box on the
image (its bounding cylinder's outline, projected); for each pixel there, its ray
(precomputed bearings, turned into the world) meets each solid (closed-form
ray-cylinder and ray-sphere intersections); the nearest hit gives the part, the
texture coordinates (arc length around the solid and height, m, times the texture's
pixels per metre, at the mip level nearest the figure's scale on the image; tiling
textures wrap) and a shade (the surface's normal against the line of sight, so the
figure looks round). Small figures are computed at twice the resolution and averaged
down (anti-aliased outlines); large ones (a person a metre away) at less than one ray
per pixel (:data:`_MAX_SAMPLES`), then interpolated. A pixel is drawn only where its
line of sight passes above every wall or piece of furniture between the camera and the
person (heights from the simulation's ray query along the person's centre line).
People are drawn far to near, so nearer ones hide farther ones.

Looks (textures, grey levels of clothes, skin, hair, long or short hair) are drawn
once per person from the generator given, so they are fixed for a seed.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from sim.simulation import OCCLUDER_FILTER, Simulation
from sim.texture_library import Texture, TextureLibrary

FloatArray = npt.NDArray[np.float64]
Canvas = npt.NDArray[np.uint8] | npt.NDArray[np.float32]
"""(H, W) grey levels a figure is drawn into: a frame, or the renderer's radiance."""
LightAt = Callable[[npt.ArrayLike], npt.ArrayLike]
"""Light on the floor plan at points (N, 2), world frame, m -> (N,) relative light."""

_REFERENCE_HEIGHT_M = 1.75
"""The figure's heights below are for a person this tall, m; others scale."""
_LEG = (0.0, 0.09, 0.075, 0.0, 0.86)
"""Leg: forward offset, lateral offset (either side), radius, bottom, top, m."""
_TORSO = (0.0, 0.0, 0.12, 0.19, 0.84, 1.45)
"""Torso: forward, lateral offset, forward and lateral semi-axes, bottom, top, m."""
_ARM = (0.0, 0.235, 0.05, 0.80, 1.42)
"""Arm: forward, lateral offset, radius, bottom, top, m."""
_HAND_M = 0.10
"""Bottom of each arm drawn as skin, m."""
_NECK = (0.0, 0.0, 0.055, 1.42, 1.54)
"""Neck: forward, lateral, radius, bottom, top, m."""
_HEAD = (0.01, 0.0, 1.635, 0.105)
"""Head: forward, lateral, height of the centre, radius, m."""
_FACE_HALF_ANGLE = math.radians(70.0)
"""The face covers the head's front within this angle of the heading."""
_STRIDE_M = 1.4
"""Distance walked per gait cycle (two steps), m."""
_SWING_M = 0.12
"""Peak forward swing of a foot or hand, m."""
_NEAR_M = 0.15
"""People whose body comes nearer than this to the optical centre are not drawn, m."""
_MAX_SAMPLES = 4_000
"""Rays cast per figure at most: small figures get 2 x 2 per pixel, near ones fewer than
one (then interpolated: softer, like a lens focused further away)."""
_REMAP_COLUMNS = 1024
"""Texture look-ups go through cv2.remap in rows this long (it wants maps < 32767 wide)."""


@dataclass(frozen=True, slots=True)
class PersonLook:
    """How one person looks.

    Attributes:
        textures: texture name of each of trousers, shirt, skin, hair, face.
        greys: each one's grey-level factor (multiplies the texture).
        long_hair: hair reaches the neck at the back (else only the top of the head).
    """

    textures: tuple[str, str, str, str, str]
    greys: tuple[float, float, float, float, float]
    long_hair: bool


@dataclass(frozen=True, slots=True)
class FigurePose:
    """Where a figure stands and how far into its gait it is.

    Attributes:
        x_m, y_m: position on the floor, world frame, m.
        heading_rad: the way the person faces, world frame.
        walked_m: distance walked so far (the gait's phase), m.
        height_m: the person's height, m.
        radius_m: the body's radius (the bounding cylinder), m.
    """

    x_m: float
    y_m: float
    heading_rad: float
    walked_m: float
    height_m: float
    radius_m: float


def draw_look(rng: np.random.Generator, library: TextureLibrary) -> PersonLook:
    """A random look: clothes among the library's ``person`` textures, skin, hair, face."""
    clothes = [n for n in library.names("person") if n.startswith("clothing_")]
    trousers = str(rng.choice([n for n in clothes if n in ("clothing_denim", "clothing_suit",
                                                             "clothing_plain")] or clothes))
    shirt = str(rng.choice(clothes))
    skin = float(rng.uniform(0.45, 1.1))
    # The face photograph at the skin's mean grey.
    face = skin * float(library.get("skin").image.mean() / library.get("person_face").image.mean())
    greys = (float(rng.uniform(0.35, 1.0)), float(rng.uniform(0.5, 1.4)), skin,
             float(rng.uniform(0.3, 2.0)), face)
    return PersonLook((trousers, shirt, "skin", "hair", "person_face"), greys,
                      bool(rng.random() < 0.4))


class PersonFigures:
    """Draws a simulation's people as textured figures (see the module docstring).

    Args:
        camera: the lens (pixel bearings, the figure's outline).
        library: the textures (``person`` kind: clothing_*, skin, hair, person_face).
        brightness: the world's mean grey level of plain surfaces; a texture's mean grey
            128 is drawn at this level times its look's factor.
        rng: draws each person's look, the first time they are drawn.
    """

    def __init__(self, camera: CameraModel, library: TextureLibrary, brightness: float,
                 rng: np.random.Generator) -> None:
        self.camera = camera
        self._library = library
        self._scale = brightness / 128.0
        self._rng = rng
        self._looks: dict[int, PersonLook] = {}
        self._mips: dict[str, tuple[Texture, list[npt.NDArray[np.float32]]]] = {}
        self._bearings: npt.NDArray[np.float32] | None = None
        self._px_per_rad = float(camera.K[0, 0] / (1.0 + camera.xi))

    def look(self, index: int) -> PersonLook:
        """Person ``index``'s look (drawn the first time it is asked for)."""
        if index not in self._looks:
            self._looks[index] = draw_look(self._rng, self._library)
        return self._looks[index]

    def draw_people(self, sim: Simulation, image: Canvas, R_cam_world: FloatArray,
                    centre_w: FloatArray, depth_m: npt.NDArray[np.float32] | None = None,
                    light_at: LightAt | None = None) -> None:
        """Draw every person of ``sim`` into ``image`` (in place), far to near.

        Args:
            sim: the simulation (people, and the walls and furniture that hide them).
            image: (H, W) uint8 or float32 grey levels, the frame drawn so far.
            R_cam_world: (3, 3) rotation world -> camera.
            centre_w: (3,) the optical centre, world frame, m.
            depth_m: (H, W) distance along each pixel's ray to what ``image`` shows, m
                (inf: nothing); given, it hides the figures per pixel instead of the
                walls and furniture met along their centre lines.
            light_at: the light falling on the floor plan at points (N, 2) m, relative
                to the world's plain lighting (1); None: 1 everywhere.
        """
        positions, radius, height = sim.people_state()
        headings, walked = sim.people.headings(), sim.people.walked_m()
        cx, cy = float(centre_w[0]), float(centre_w[1])
        distances = np.hypot(positions[:, 0] - cx, positions[:, 1] - cy)
        for k in np.argsort(-distances).tolist():
            if distances[k] <= radius + _NEAR_M:
                continue
            px, py = float(positions[k, 0]), float(positions[k, 1])
            occluders = [] if depth_m is not None else [
                (info.alpha * distances[k], sim.occluder_height(info.shape))
                for info in sim.space.segment_query((cx, cy), (px, py), 0.0, OCCLUDER_FILTER)
                if info.shape is not None and not sim.is_person(info.shape)]
            pose = FigurePose(px, py, float(headings[k]), float(walked[k]), height, radius)
            light = 1.0 if light_at is None else float(np.asarray(light_at([(px, py)])).ravel()[0])
            self.draw(image, pose, self.look(k), R_cam_world, centre_w, occluders, depth_m,
                      light)

    def draw(self, image: Canvas, pose: FigurePose, look: PersonLook,
             R_cam_world: FloatArray, centre_w: FloatArray,
             occluders: list[tuple[float, float]],
             depth_m: npt.NDArray[np.float32] | None = None, light: float = 1.0) -> None:
        """Draw one figure into ``image`` (in place).

        Args:
            image: (H, W) uint8 or float32 grey levels, the frame drawn so far.
            pose: where the figure stands.
            look: its textures and greys.
            R_cam_world: (3, 3) rotation world -> camera.
            centre_w: (3,) the optical centre, world frame, m.
            occluders: (distance along the floor from the camera, m; height, m) of each
                wall or piece of furniture between the camera and the figure.
            depth_m: (H, W) distance along each pixel's ray to what ``image`` shows, m:
                the figure shows only where it is nearer.
            light: the light falling on the figure, relative to the world's plain
                lighting.
        """
        distance = math.hypot(pose.x_m - float(centre_w[0]), pose.y_m - float(centre_w[1]))
        near = max(distance - pose.radius_m, 1e-6)
        cz = float(centre_w[2])
        if any(top_m >= cz + along_m * (pose.height_m - cz) / near
               for along_m, top_m in occluders):
            return  # even the line of sight to the top of the head is blocked
        box = self._box(pose, R_cam_world, centre_w)
        if box is None:
            return
        x0, y0, x1, y1 = box
        size = (x1 - x0, y1 - y0)
        # Samples per pixel side: 2 for small figures (anti-aliased), fewer for near ones.
        scale = min(2.0, math.sqrt(_MAX_SAMPLES / (size[0] * size[1])))
        sampled = (max(round(size[0] * scale), 1), max(round(size[1] * scale), 1))
        rays_w = self._rays(box, sampled, R_cam_world)
        depth = None
        if depth_m is not None:
            depth = depth_m[y0:y1, x0:x1]
            if sampled != size:
                depth = cv2.resize(depth, sampled, interpolation=cv2.INTER_NEAREST)
        grey, cover = self._shade(rays_w, pose, look, centre_w, occluders,
                                  self._px_per_rad * scale / distance, depth)
        grey *= cover * np.float32(light)
        if sampled != size:
            shrink = cv2.INTER_AREA if scale > 1.0 else cv2.INTER_LINEAR
            grey = cv2.resize(grey, size, interpolation=shrink)
            cover = cv2.resize(cover, size, interpolation=shrink)
        roi = image[y0:y1, x0:x1]
        blended = roi * (1.0 - cover) + grey
        if image.dtype == np.uint8:
            roi[:] = np.clip(blended + 0.5, 0, 255).astype(np.uint8)
        else:
            roi[:] = blended

    # -- geometry ---------------------------------------------------------------------

    def _box(self, pose: FigurePose, R_cam_world: FloatArray,
             centre_w: FloatArray) -> tuple[int, int, int, int] | None:
        """The figure's bounding cylinder's box on the image (x0, y0, x1, y1), or None."""
        angles = np.linspace(0.0, 2.0 * math.pi, 16, endpoint=False)
        ring = np.column_stack([pose.x_m + pose.radius_m * np.cos(angles),
                                pose.y_m + pose.radius_m * np.sin(angles)])
        heights = np.linspace(0.0, pose.height_m, 5)
        points = np.array([(x, y, z) for z in heights for x, y in ring])
        pixels, valid = self.camera.project((points - centre_w) @ R_cam_world.T)
        if not valid.any():
            return None
        lo = np.floor(pixels[valid].min(axis=0)).astype(int) - 2
        hi = np.ceil(pixels[valid].max(axis=0)).astype(int) + 3
        x0, y0 = max(int(lo[0]), 0), max(int(lo[1]), 0)
        x1, y1 = min(int(hi[0]), self.camera.width), min(int(hi[1]), self.camera.height)
        return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None

    def _rays(self, box: tuple[int, int, int, int], sampled: tuple[int, int],
              R_cam_world: FloatArray) -> npt.NDArray[np.float32]:
        """Unit rays over the box (x0, y0, x1, y1) on a ``sampled`` (width, height) grid,
        world frame: (height, width, 3) float32."""
        x0, y0, x1, y1 = box
        if self._bearings is None:
            cam = self.camera
            u, v = np.meshgrid(np.arange(cam.width, dtype=np.float64),
                               np.arange(cam.height, dtype=np.float64))
            b, valid = cam.lift(np.column_stack([u.ravel(), v.ravel()]))
            b[~valid] = (0.0, 0.0, -1.0)  # never meets a figure in front
            self._bearings = b.reshape(cam.height, cam.width, 3).astype(np.float32)
        bearings = self._bearings[y0:y1, x0:x1]
        if sampled != (x1 - x0, y1 - y0):
            bearings = cv2.resize(bearings, sampled, interpolation=cv2.INTER_LINEAR)
            bearings /= np.linalg.norm(bearings, axis=2, keepdims=True)
        return bearings @ R_cam_world.astype(np.float32)

    def _shade(self, rays_w: npt.NDArray[np.float32], pose: FigurePose, look: PersonLook,
               centre_w: FloatArray, occluders: list[tuple[float, float]], px_per_m: float,
               depth: npt.NDArray[np.float32] | None,
               ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """Grey (h, w) and coverage (h, w, 0 or 1) of the figure along ``rays_w`` (where it
        is nearer than ``depth``, (h, w) m, if given).

        Two passes: each solid's distance along every ray, then the surface (part,
        texture coordinates, shade) only where a solid is the nearest.
        """
        h, w, _ = rays_w.shape
        grey_all = np.zeros(h * w, dtype=np.float32)
        cover_all = np.zeros(h * w, dtype=np.float32)
        d = rays_w.reshape(-1, 3)
        fwd = np.array([math.cos(pose.heading_rad), math.sin(pose.heading_rad)])
        left = np.array([-fwd[1], fwd[0]])
        rel = np.array([float(centre_w[0]) - pose.x_m, float(centre_w[1]) - pose.y_m])
        # Only rays that pass within the body's radius of its axis, ahead of the camera.
        along = -(d[:, :2] @ rel) / np.maximum(np.einsum("ij,ij->i", d[:, :2], d[:, :2]), 1e-12)
        closest = rel + along[:, None] * d[:, :2]
        rays = np.flatnonzero((along > 0) & (np.einsum("ij,ij->i", closest, closest)
                                             < pose.radius_m**2))
        if rays.size == 0:
            return grey_all.reshape(h, w), cover_all.reshape(h, w)
        d = d[rays].astype(np.float64)
        # Camera and rays in the person's frame (forward, left, up).
        c = np.array([rel @ fwd, rel @ left, float(centre_w[2])])
        r = np.column_stack([d[:, :2] @ fwd, d[:, :2] @ left, d[:, 2]])
        cylinders, head = _solids(pose)
        t = np.vstack([cylinders.distances(c, r), head.distances(c, r)[None, :]])
        nearest = np.argmin(t, axis=0)
        t_hit = t[nearest, np.arange(t.shape[1])]
        cover = np.isfinite(t_hit)
        if depth is not None:
            cover &= t_hit < depth.reshape(-1)[rays]
        horizontal = np.hypot(r[:, 0], r[:, 1])
        for along_m, top_m in occluders:  # the line of sight must pass above each
            with np.errstate(divide="ignore", invalid="ignore"):
                rise = c[2] + along_m * r[:, 2] / horizontal
            cover &= rise > top_m
        piece = np.full(t.shape[1], -1)
        u_m, v_m, shade = np.zeros((3, t.shape[1]))
        on_head = cover & (nearest == t.shape[0] - 1)
        on_body = cover & ~on_head
        if on_body.any():
            piece[on_body], u_m[on_body], v_m[on_body], shade[on_body] = cylinders.surface(
                nearest[on_body], c, r[on_body], t_hit[on_body])
        if on_head.any():
            piece[on_head], u_m[on_head], v_m[on_head], shade[on_head] = head.surface(
                c, r[on_head], t_hit[on_head], look.long_hair)
        grey = np.zeros(t.shape[1])
        for i, name in enumerate(look.textures):
            part = piece == i
            if part.any():
                grey[part] = self._sample(name, u_m[part], v_m[part], px_per_m) * (
                    look.greys[i] * self._scale) * shade[part]
        grey_all[rays] = grey
        cover_all[rays] = cover
        return grey_all.reshape(h, w), cover_all.reshape(h, w)

    # -- textures ---------------------------------------------------------------------

    def _sample(self, name: str, u_m: FloatArray, v_m: FloatArray,
                px_per_m: float) -> FloatArray:
        """Grey levels of texture ``name`` at (u_m, v_m) (m from its top-left), at the mip
        level nearest ``px_per_m`` (the figure's scale on the image)."""
        texture, levels = self._mip(name)
        tx_per_m, ty_per_m = texture.px_per_m
        level = int(np.clip(math.floor(math.log2(max(tx_per_m / px_per_m, 1.0))), 0,
                            len(levels) - 1))
        picture = levels[level]
        ph, pw = picture.shape
        x = u_m * (tx_per_m / 2**level) - 0.5
        y = v_m * (ty_per_m / 2**level) - 0.5
        if texture.tiles:
            x, y = np.mod(x, pw), np.mod(y, ph)
        else:
            x, y = np.clip(x, 0, pw - 1), np.clip(y, 0, ph - 1)
        n = x.shape[0]
        rows = -(-n // _REMAP_COLUMNS)
        maps = np.zeros((2, rows * _REMAP_COLUMNS), dtype=np.float32)
        maps[0, :n], maps[1, :n] = x, y
        values = cv2.remap(picture, maps[0].reshape(rows, -1), maps[1].reshape(rows, -1),
                           cv2.INTER_LINEAR,
                           borderMode=cv2.BORDER_WRAP if texture.tiles else cv2.BORDER_REPLICATE)
        return values.ravel()[:n].astype(np.float64)

    def _mip(self, name: str) -> tuple[Texture, list[npt.NDArray[np.float32]]]:
        if name not in self._mips:
            texture = self._library.get(name)
            levels = [texture.image.astype(np.float32)]
            while min(levels[-1].shape) >= 8:
                levels.append(cv2.pyrDown(levels[-1]))
            self._mips[name] = (texture, levels)
        return self._mips[name]


# -- the solids ------------------------------------------------------------------------

_TROUSERS, _SHIRT, _SKIN, _HAIR, _FACE = range(5)
"""Indices into :attr:`PersonLook.textures`."""


@dataclass(frozen=True, slots=True)
class _Cylinders:
    """The figure's vertical elliptic cylinders, person frame, each a row of (K,) arrays:
    centre (forward, left) m, semi-axes m, bottom and top heights m, part, and the height
    below which it is skin (hands), m."""

    centre_f: FloatArray
    centre_l: FloatArray
    axis_f: FloatArray
    axis_l: FloatArray
    z0: FloatArray
    z1: FloatArray
    piece: npt.NDArray[np.int64]
    skin_below_m: FloatArray

    def distances(self, c: FloatArray, r: FloatArray) -> FloatArray:
        """(K, N) distance along each ray ``c + t r`` (r: (N, 3) unit) to each cylinder,
        inf where it misses (sides, and the end cap seen from below or above)."""
        q0 = ((c[0] - self.centre_f) / self.axis_f)[:, None]
        q1 = ((c[1] - self.centre_l) / self.axis_l)[:, None]
        e0 = r[None, :, 0] / self.axis_f[:, None]
        e1 = r[None, :, 1] / self.axis_l[:, None]
        a = e0 * e0 + e1 * e1
        b = q0 * e0 + q1 * e1  # half the quadratic's b
        disc = b * b - a * (q0 * q0 + q1 * q1 - 1.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (-b - np.sqrt(disc)) / a
            z = c[2] + t * r[None, :, 2]
            side = (disc > 0) & (t > 0) & (z >= self.z0[:, None]) & (z <= self.z1[:, None])
            t = np.where(side, t, np.inf)
            cap = np.where(c[2] < self.z0, self.z0, np.where(c[2] > self.z1, self.z1, np.nan))
            t_cap = (cap[:, None] - c[2]) / r[None, :, 2]
            on_cap = ((t_cap > 0) & (t_cap < t)
                      & ((q0 + t_cap * e0) ** 2 + (q1 + t_cap * e1) ** 2 <= 1.0))
        return np.where(on_cap, t_cap, t)

    def surface(self, k: npt.NDArray[np.int64], c: FloatArray, r: FloatArray,
                t: FloatArray) -> tuple[FloatArray, ...]:
        """Part, u_m (arc length around), v_m (down from the top) and shade where ray i
        hits cylinder ``k[i]`` at ``t[i]``."""
        a_f, a_l = self.axis_f[k], self.axis_l[k]
        hx = (c[0] + t * r[:, 0] - self.centre_f[k]) / a_f
        hy = (c[1] + t * r[:, 1] - self.centre_l[k]) / a_l
        z = c[2] + t * r[:, 2]
        # Lambert-like: the surface's normal against the line of sight (the caps take
        # their rim's, near enough).
        facing = -(hx * r[:, 0] / a_f + hy * r[:, 1] / a_l) / np.hypot(r[:, 0], r[:, 1])
        shade = 0.45 + 0.55 * np.clip(facing, 0.0, 1.0)
        piece = np.where(z < self.skin_below_m[k], _SKIN, self.piece[k])
        u_m = np.arctan2(hy, hx) * 0.5 * (a_f + a_l)
        return piece, u_m, self.z1[k] - z, shade


@dataclass(frozen=True, slots=True)
class _Head:
    """The head's sphere, person frame: centre (forward, left, up) and radius, m."""

    centre: tuple[float, float, float]
    radius: float

    def distances(self, c: FloatArray, r: FloatArray) -> FloatArray:
        """(N,) distance along each ray ``c + t r`` (r: (N, 3) unit) to the sphere, inf if none."""
        o = c - np.array(self.centre)
        b = r @ o
        disc = b * b - (o @ o - self.radius**2)
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        return np.where((disc > 0) & (t > 0), t, np.inf)

    def surface(self, c: FloatArray, r: FloatArray, t: FloatArray,
                long_hair: bool) -> tuple[FloatArray, ...]:
        """Face in front, hair above (and behind, long hair), skin elsewhere."""
        n = (c - np.array(self.centre) + t[:, None] * r) / self.radius
        phi = np.arctan2(n[:, 1], n[:, 0])  # 0 = straight ahead
        shade = 0.45 + 0.55 * np.clip(-(n * r).sum(axis=1), 0.0, 1.0)
        face = (np.abs(phi) < _FACE_HALF_ANGLE) & (n[:, 2] < 0.55)
        hair = ~face & ((n[:, 2] > -0.2) | long_hair)
        piece = np.where(face, _FACE, np.where(hair, _HAIR, _SKIN))
        # Face: u across the front (0 at its left edge); v down from the top of the head.
        u_m = np.where(face, phi + _FACE_HALF_ANGLE, phi) * self.radius
        return piece, u_m, (1.0 - n[:, 2]) * self.radius, shade


def _solids(pose: FigurePose) -> tuple[_Cylinders, _Head]:
    """The figure's solids in its frame, scaled to its height, legs and arms mid-swing."""
    s = pose.height_m / _REFERENCE_HEIGHT_M
    swing = _SWING_M * math.sin(2.0 * math.pi * pose.walked_m / _STRIDE_M)
    rows = []  # centre_f, centre_l, axis_f, axis_l, z0, z1, piece, skin below
    for side in (1.0, -1.0):
        f, lat, rad, z0, z1 = _LEG
        rows.append((f + side * swing, side * lat, rad, rad, z0 * s, z1 * s, _TROUSERS, -1.0))
        f, lat, rad, z0, z1 = _ARM
        rows.append((f - side * swing, side * lat, rad, rad, z0 * s, z1 * s, _SHIRT,
                     (z0 + _HAND_M) * s))
    f, lat, af, al, z0, z1 = _TORSO
    rows.append((f, lat, af, al, z0 * s, z1 * s, _SHIRT, -1.0))
    f, lat, rad, z0, z1 = _NECK
    rows.append((f, lat, rad, rad, z0 * s, z1 * s, _SKIN, -1.0))
    columns = np.array(rows).T
    f, lat, zc, rad = _HEAD
    return (_Cylinders(*columns[:6], columns[6].astype(np.int64), columns[7]),
            _Head((f, lat, zc * s), rad))
