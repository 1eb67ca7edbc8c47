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
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from sim.simulation import OCCLUDER_FILTER, Simulation
from sim.texture_library import Texture, TextureLibrary

FloatArray = npt.NDArray[np.float64]

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
_MAX_SAMPLES = 6_000
"""Rays cast per figure at most: small figures get 2 x 2 per pixel, near ones fewer than
one (then interpolated: softer, like a lens focused further away)."""
_REMAP_COLUMNS = 1024


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
    greys = (float(rng.uniform(0.35, 1.0)), float(rng.uniform(0.5, 1.4)), skin,
             float(rng.uniform(0.3, 2.0)), skin * 192.0 / 144.0)  # face: the skin's grey
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

    def draw_people(self, sim: Simulation, image: npt.NDArray[np.uint8],
                    R_cam_world: FloatArray, centre_w: FloatArray) -> None:
        """Draw every person of ``sim`` into ``image`` ((H, W) uint8, in place), far to near.

        Args:
            sim: the simulation (people, and the walls and furniture that hide them).
            image: the frame drawn so far.
            R_cam_world: (3, 3) rotation world -> camera.
            centre_w: (3,) the optical centre, world frame, m.
        """
        positions, radius, height = sim.people_state()
        headings, walked = sim.people.headings(), sim.people.walked_m()
        cx, cy = float(centre_w[0]), float(centre_w[1])
        distances = np.hypot(positions[:, 0] - cx, positions[:, 1] - cy)
        for k in np.argsort(-distances).tolist():
            if distances[k] <= radius + _NEAR_M:
                continue
            px, py = float(positions[k, 0]), float(positions[k, 1])
            occluders = [(info.alpha * distances[k], sim.occluder_height(info.shape))
                         for info in sim.space.segment_query((cx, cy), (px, py), 0.0,
                                                             OCCLUDER_FILTER)
                         if info.shape is not None and not sim.is_person(info.shape)]
            pose = FigurePose(px, py, float(headings[k]), float(walked[k]), height, radius)
            self.draw(image, pose, self.look(k), R_cam_world, centre_w, occluders)

    def draw(self, image: npt.NDArray[np.uint8], pose: FigurePose, look: PersonLook,
             R_cam_world: FloatArray, centre_w: FloatArray,
             occluders: list[tuple[float, float]]) -> None:
        """Draw one figure into ``image`` ((H, W) uint8, in place).

        Args:
            image: the frame drawn so far.
            pose: where the figure stands.
            look: its textures and greys.
            R_cam_world: (3, 3) rotation world -> camera.
            centre_w: (3,) the optical centre, world frame, m.
            occluders: (distance along the floor from the camera, m; height, m) of each
                wall or piece of furniture between the camera and the figure.
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
        rays_w = self._rays(x0, y0, x1, y1, R_cam_world)
        # Samples per pixel side: 2 for small figures (anti-aliased), fewer for near ones.
        scale = min(2.0, math.sqrt(_MAX_SAMPLES / (size[0] * size[1])))
        sampled = (max(round(size[0] * scale), 1), max(round(size[1] * scale), 1))
        if sampled != size:
            rays_w = cv2.resize(rays_w, sampled, interpolation=cv2.INTER_LINEAR)
            rays_w /= np.linalg.norm(rays_w, axis=2, keepdims=True)
        grey, cover = self._shade(rays_w, pose, look, centre_w, occluders,
                                  self._px_per_rad * scale / distance)
        grey *= cover
        if sampled != size:
            shrink = cv2.INTER_AREA if scale > 1.0 else cv2.INTER_LINEAR
            grey = cv2.resize(grey, size, interpolation=shrink)
            cover = cv2.resize(cover, size, interpolation=shrink)
        roi = image[y0:y1, x0:x1]
        roi[:] = np.clip(roi * (1.0 - cover) + grey + 0.5, 0, 255).astype(np.uint8)

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

    def _rays(self, x0: int, y0: int, x1: int, y1: int,
              R_cam_world: FloatArray) -> npt.NDArray[np.float32]:
        """Unit rays of the pixels in the box, world frame: (h, w, 3) float32."""
        if self._bearings is None:
            cam = self.camera
            u, v = np.meshgrid(np.arange(cam.width, dtype=np.float64),
                               np.arange(cam.height, dtype=np.float64))
            b, valid = cam.lift(np.column_stack([u.ravel(), v.ravel()]))
            b[~valid] = (0.0, 0.0, -1.0)  # never meets a figure in front
            self._bearings = b.reshape(cam.height, cam.width, 3).astype(np.float32)
        return (self._bearings[y0:y1, x0:x1] @ R_cam_world.astype(np.float32)).astype(np.float32)

    def _shade(self, rays_w: npt.NDArray[np.float32], pose: FigurePose, look: PersonLook,
               centre_w: FloatArray, occluders: list[tuple[float, float]],
               px_per_m: float) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """Grey (h, w) and coverage (h, w, 0 or 1) of the figure along ``rays_w``."""
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
        s = pose.height_m / _REFERENCE_HEIGHT_M
        swing = _SWING_M * math.sin(2.0 * math.pi * pose.walked_m / _STRIDE_M)
        hits = []  # (t, piece index, u_m, v_m, shade) per solid
        for side in (1.0, -1.0):
            f, lat, rad, z0, z1 = _LEG
            hits.append(self._cylinder(c, r, (f + side * swing, side * lat), (rad, rad),
                                       z0 * s, z1 * s, 0))
            f, lat, rad, z0, z1 = _ARM
            hits.append(self._cylinder(c, r, (f - side * swing, side * lat), (rad, rad),
                                       z0 * s, z1 * s, 1, skin_below=(z0 + _HAND_M) * s))
        f, lat, af, al, z0, z1 = _TORSO
        hits.append(self._cylinder(c, r, (f, lat), (af, al), z0 * s, z1 * s, 1))
        f, lat, rad, z0, z1 = _NECK
        hits.append(self._cylinder(c, r, (f, lat), (rad, rad), z0 * s, z1 * s, 2))
        hits.append(self._head(c, r, s, look.long_hair))
        t = np.stack([hit[0] for hit in hits])
        nearest = np.argmin(t, axis=0)
        pick = np.arange(t.shape[1])
        t_hit = t[nearest, pick]
        piece, u_m, v_m, shade = (np.stack([hit[i] for hit in hits])[nearest, pick]
                                  for i in range(1, 5))
        cover = np.isfinite(t_hit)
        horizontal = np.hypot(r[:, 0], r[:, 1])
        for along_m, top_m in occluders:  # the line of sight must pass above each
            with np.errstate(divide="ignore", invalid="ignore"):
                rise = c[2] + along_m * r[:, 2] / horizontal
            cover &= rise > top_m
        grey = np.zeros(t.shape[1])
        for i, name in enumerate(look.textures):
            sel = cover & (piece == i)
            if sel.any():
                grey[sel] = self._sample(name, u_m[sel], v_m[sel], px_per_m) * (
                    look.greys[i] * self._scale) * shade[sel]
        grey_all[rays] = grey
        cover_all[rays] = cover
        return grey_all.reshape(h, w), cover_all.reshape(h, w)

    @staticmethod
    def _cylinder(c: FloatArray, r: FloatArray, centre: tuple[float, float],
                  axes: tuple[float, float], z0: float, z1: float, piece: int,
                  skin_below: float | None = None) -> tuple[FloatArray, ...]:
        """Nearest hits of rays ``c + t r`` (person frame) with a vertical elliptic cylinder.

        Returns:
            t (inf where none), piece, u_m (arc length around it), v_m (down from z1),
            shade; each (N,).
        """
        a_f, a_l = axes
        q = np.array([(c[0] - centre[0]) / a_f, (c[1] - centre[1]) / a_l])
        e0, e1 = r[:, 0] / a_f, r[:, 1] / a_l
        a = e0 * e0 + e1 * e1
        b = 2.0 * (q[0] * e0 + q[1] * e1)
        cc = q @ q - 1.0
        disc = b * b - 4.0 * a * cc
        with np.errstate(invalid="ignore", divide="ignore"):
            t = (-b - np.sqrt(disc)) / (2.0 * a)
        z = c[2] + t * r[:, 2]
        ok = (disc > 0) & (t > 0) & (z >= z0) & (z <= z1)
        t = np.where(ok, t, np.inf)
        # The end caps: seen from below (bottom) or above (top).
        cap = z0 if c[2] < z0 else z1 if c[2] > z1 else None
        if cap is not None:
            with np.errstate(divide="ignore", invalid="ignore"):
                t_cap = (cap - c[2]) / r[:, 2]
            inside = (q[0] + t_cap * e0) ** 2 + (q[1] + t_cap * e1) ** 2 <= 1.0
            on_cap = (t_cap > 0) & inside & (t_cap < t)
            t = np.where(on_cap, t_cap, t)
            ok |= on_cap
        t_ok = np.where(ok, t, 0.0)
        hx, hy = q[0] + t_ok * e0, q[1] + t_ok * e1  # on the unit circle where ok
        with np.errstate(invalid="ignore"):
            phi = np.arctan2(hy, hx)
            # Lambert-like: the surface's normal against the line of sight.
            facing = -(hx * r[:, 0] / a_f + hy * r[:, 1] / a_l) / np.hypot(r[:, 0], r[:, 1])
        shade = 0.45 + 0.55 * np.clip(np.nan_to_num(facing), 0.0, 1.0)
        pieces = np.full(t.shape, float(piece))
        if skin_below is not None:
            pieces[z < skin_below] = 2.0
        u_m = phi * 0.5 * (a_f + a_l)
        return t, pieces, u_m, z1 - z, shade

    @staticmethod
    def _head(c: FloatArray, r: FloatArray, s: float, long_hair: bool) -> tuple[FloatArray, ...]:
        """Nearest hits with the head's sphere: face in front, hair above and behind."""
        f, lat, zc, rad = _HEAD
        o = c - np.array([f, lat, zc * s])
        b = r @ o
        disc = b * b - (o @ o - rad * rad)
        with np.errstate(invalid="ignore"):
            t = -b - np.sqrt(disc)
        ok = (disc > 0) & (t > 0)
        t = np.where(ok, t, np.inf)
        p = o + np.where(ok, t, 0.0)[:, None] * r  # on the sphere where ok, centre at 0
        with np.errstate(invalid="ignore"):
            n = p / rad
            phi = np.arctan2(n[:, 1], n[:, 0])  # 0 = straight ahead
            shade = 0.45 + 0.55 * np.clip(np.nan_to_num(-(n * r).sum(axis=1)), 0.0, 1.0)
        face = (np.abs(phi) < _FACE_HALF_ANGLE) & (n[:, 2] < 0.55)
        hair = ~face & ((n[:, 2] > -0.2) | long_hair)
        piece = np.where(face, 4.0, np.where(hair, 3.0, 2.0))
        # Face: u across the front (0 at the left edge), v down from the top of the head.
        u_face = (phi + _FACE_HALF_ANGLE) * rad
        u_m = np.where(face, u_face, phi * rad)
        v_m = (1.0 - n[:, 2]) * rad
        return t, piece, u_m, v_m, shade

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
        rows = -(-n // _REMAP_COLUMNS)  # cv2.remap wants maps narrower than 32767 px
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
