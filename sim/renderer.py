"""The fisheye renderer: textured grey frames of a world through the shared camera model.

Per frame:

1. The camera pose follows from the robot's true pose and the camera mount.
2. Every pixel's ray (its bearing from :meth:`CameraModel.lift`, computed once) is
   traced against the world's textured surfaces (:mod:`sim.surfaces` compiles them,
   :mod:`sim._raycast` traces them): the nearest wall face, piece of furniture,
   placed object, picture, tree, floor, ceiling, lamp or the sky, textured with
   trilinear mip-mapping from the pixel's footprint (no aliasing shimmer) and lit
   by the light map (:mod:`sim.lightmap`: lamps, daylight through windows, open sky).
   Objects placed in the simulation while it runs are in the surfaces from the first
   frame after they were placed until they are removed (:func:`sim.surfaces.with_objects`,
   recompiled when :attr:`Simulation.objects_revision` changes).
   The image is a float radiance, grey levels (lamps and sky may exceed 255).
3. People are drawn as textured figures (:mod:`sim.person_figure`, hidden per pixel
   by the depth image), then the legacy landmark patches of a world that asks for them.
4. The post-process stage (:meth:`FisheyeRenderer._post_process`) turns radiance into
   the uint8 frame: a global illumination gain (slow sinusoid, times the scene's
   light change ``Simulation.light_gain_at``), then the camera's flaws
   (:class:`sim.camera_effects.CameraEffects`: motion blur, vignetting,
   auto-exposure, noise, clipping; outside the lens's image circle stays black).

Ground truth is exact: the true pose, the depth along each pixel's ray, and the
"landmarks" in view: the corners of the pictures on the walls (their 3D corners
projected by the camera model, where the depth image shows the picture there), or
in a world with landmark patches, the patches' centres.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numba
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.camera_mount import camera_pose_world, rotation_base_cam
from shared.config import CameraMountConfig
from shared.pose import Pose2
from sim._atlas import Atlas
from sim._patches import NEAR_M, PatchPainter
from sim._raycast import bin_primitives, sub_rays, trace
from sim.camera_effects import CameraEffects, camera_motion
from sim.config import RenderConfig, SensorConfig, SimConfig
from sim.landmarks import LandmarkField
from sim.person_figure import PersonFigures
from sim.simulation import Simulation
from sim.surfaces import Scene, build_scene, with_objects
from sim.texture_library import TextureLibrary
from sim.world import World, load_world

FloatArray = npt.NDArray[np.float64]

WEDGES = 1024
"""Azimuth wedges of the ray kernel's candidate lists (see :mod:`sim._raycast`)."""
_RENDER_STREAM = 0x52454E44
"""Mixed with the simulation seed for the renderer's own random stream."""
_CORNER_DEPTH_TOLERANCE = 0.05
"""A picture corner is in view when the depth image there is within this fraction of its
distance (+ 2 cm) of it, m / m."""
_KERNEL = threading.Lock()
"""One frame at a time goes through the ray kernel in a process: its threads are shared
(numba's default "workqueue" layer aborts the process on concurrent calls)."""


def set_render_threads(count: int) -> None:
    """Spread each frame's rays over ``count`` threads (default: one per usable CPU).

    One per process where several rendering processes share the CPUs (a pool of
    teaching drives) or where a benchmark measures one core; the image is the same.

    Raises:
        ValueError: ``count`` is below 1 or above the threads numba started.
    """
    numba.set_num_threads(count)


def compile_kernels() -> None:
    """Compile the ray and light kernels into numba's cache on disk (``sim/__pycache__``)
    by rendering one frame of the default world; ``make``'s set-up runs it once.

    Processes started later load the compiled kernels at once; without the cache the
    first frame of each process takes about 14 s (each worker of a parallel teach
    compiles its own).
    """
    config = SimConfig()
    sim = Simulation(load_world(config.world), config)
    FisheyeRenderer.for_simulation(sim, CameraModel.default()).render(sim)


@dataclass(frozen=True, eq=False)
class RenderedFrame:
    """One rendered frame with its ground truth.

    Attributes:
        t_ns: simulation time of the exposure, ns.
        image: (H, W) uint8 grey image.
        pose_w: true robot pose in the world frame.
        T_world_cam: (4, 4) float64 true camera pose (camera frame -> world frame).
        visible_ids: (K,) int64 ids of the landmarks in view, near to far: picture
            corners ``4 * picture + corner`` (corners top-left, top-right,
            bottom-right, bottom-left), or the patch ids of a world with patches.
        visible_pixels_xy: (K, 2) float64 their projections by the camera model, px.
        visible_distances_m: (K,) float64 their distances to the optical centre, m.
        illumination_gain: the global gain applied to this frame.
        depth_m: (H, W) float32 distance along each pixel's ray to the surface it
            shows, m (inf: sky, or outside the image circle); people not included.
    """

    t_ns: int
    image: npt.NDArray[np.uint8]
    pose_w: Pose2
    T_world_cam: FloatArray
    visible_ids: npt.NDArray[np.int64]
    visible_pixels_xy: FloatArray
    visible_distances_m: FloatArray
    illumination_gain: float
    depth_m: npt.NDArray[np.float32] | None = None


@dataclass(frozen=True, slots=True, eq=False)
class _Trace:
    """The last :meth:`FisheyeRenderer.trace`: the scene and camera pose it saw, its images."""

    scene: Scene
    pose: bytes  #: the camera pose and heading, as bytes to compare
    radiance: npt.NDArray[np.float32]
    depth: npt.NDArray[np.float32]


class FisheyeRenderer:
    """Renders grey fisheye frames of a :class:`~sim.simulation.Simulation`.

    Args:
        camera: the simulated lens.
        mount: the camera's pose on the robot.
        config: illumination.
        sensor: the camera's flaws.
        world: the textured surfaces and their lighting.
        landmarks: legacy landmark patches to paint over them (usually none).
        rng: seeds the illumination phase, people's looks and the sensor's noise.

    Attributes:
        effects: the camera's flaws, applied to every frame (its ``last`` says how
            the last frame was exposed).

    Raises:
        ConfigError: a texture the world names is missing from its set.
    """

    def __init__(
        self,
        camera: CameraModel,
        mount: CameraMountConfig,
        config: RenderConfig,
        sensor: SensorConfig,
        world: World,
        landmarks: LandmarkField,
        rng: np.random.Generator,
    ) -> None:
        self.camera = camera
        self.mount = mount
        self.config = config
        self.landmarks = landmarks
        self.scene: Scene = build_scene(world, Atlas(world.textures()))
        self._world, self._world_scene, self._objects_revision = world, self.scene, 0
        self._patches = PatchPainter(camera, landmarks, world.lighting) if len(landmarks) else None
        self._rng = rng
        self._brightness = world.lighting.brightness
        self._rays(rotation_base_cam(mount))
        self.effects = CameraEffects(camera, mount, sensor, rng.spawn(1)[0])
        self._illumination_phase = float(rng.uniform(0.0, 2.0 * math.pi))
        self._figures: PersonFigures | None = None
        self._last_trace: _Trace | None = None

    @classmethod
    def for_simulation(cls, sim: Simulation, camera: CameraModel) -> FisheyeRenderer:
        """A renderer for ``sim``'s world, landmarks and config (the camera at its
        ``camera_mount``), seeded from its seed."""
        rng = np.random.default_rng([sim.config.seed, _RENDER_STREAM])
        return cls(camera, sim.config.camera_mount, sim.config.render, sim.config.sensor,
                   sim.world, sim.landmarks, rng)

    @property
    def landmark_count(self) -> int:
        """How many landmarks the frames' ground truth may list: the pictures' corners, or
        in a world with patches, the patches."""
        if self._patches is not None:
            return len(self.landmarks)
        return int(self.scene.picture_corners_w.shape[0] * 4)

    def _rays(self, R_base_cam: FloatArray) -> None:
        """Per valid pixel: index, neighbours, bearing, wedge of its azimuth, angular size
        (once); the ray kernel's scratch arrays."""
        cam = self.camera
        u, v = np.meshgrid(np.arange(cam.width, dtype=np.float64), np.arange(cam.height))
        pixels = np.column_stack([u.ravel(), v.ravel()])
        bearings, valid = cam.lift(pixels)
        self._pixels = np.flatnonzero(valid)
        self._neighbours = _neighbours(self._pixels, cam.width, cam.height)
        self._work = (np.empty(self._pixels.shape[0], np.int32),
                      np.empty(self._pixels.shape[0], np.int32))
        rays = bearings[self._pixels]
        self._rays_c = np.ascontiguousarray(rays)
        base = rays @ R_base_cam.T
        azimuth = np.arctan2(base[:, 1], base[:, 0])
        self._wedge = np.clip(((azimuth + math.pi) / (2 * math.pi) * WEDGES).astype(np.int64),
                              0, WEDGES - 1)
        # Angular size: the angle between the bearings half a pixel to either side.
        sizes = []
        for du, dv in ((0.5, 0.0), (0.0, 0.5)):
            a, ok_a = cam.lift(pixels[self._pixels] - (du, dv))
            b, ok_b = cam.lift(pixels[self._pixels] + (du, dv))
            cos = np.clip(np.einsum("ij,ij->i", a, b), -1.0, 1.0)
            sizes.append(np.where(ok_a & ok_b, np.arccos(cos), np.nan))
        size = np.sqrt(sizes[0] * sizes[1])
        self._pix_angle = np.where(np.isfinite(size), size, np.nanmedian(size))
        self._sub_c, self._sub_wedge = sub_rays(self._rays_c, self._neighbours, R_base_cam,
                                                WEDGES)

    def render(self, sim: Simulation) -> RenderedFrame:
        """Render the simulation's current state from the robot's camera.

        Returns:
            the frame and its ground truth.
        """
        if sim.objects_revision != self._objects_revision:
            self.scene = with_objects(self._world_scene, self._world, sim.added_objects.values())
            self._objects_revision = sim.objects_revision
        pose_w = sim.body.pose_w
        T_world_cam = camera_pose_world(pose_w, self.mount)
        R_cam_world = T_world_cam[:3, :3].T
        centre_w = T_world_cam[:3, 3]
        radiance, depth = self._trace_again_if_moved(T_world_cam, pose_w[2])

        self._draw_people(sim, radiance, R_cam_world, centre_w, depth)
        if self._patches is not None:
            ids, pix, dist, affines = self._patches.visible(sim, R_cam_world, centre_w)
            self._patches.paint(radiance, ids, affines, dist)
            ids = self.landmarks.ids[ids]
        else:
            ids, pix, dist = self._picture_corners(R_cam_world, centre_w, depth)

        gain = self.illumination_gain(sim.now_ns) * sim.light_gain_at(sim.now_ns)
        image = self._post_process(radiance, sim, gain)
        near = np.argsort(dist, kind="stable")
        return RenderedFrame(
            t_ns=sim.now_ns,
            image=image,
            pose_w=pose_w,
            T_world_cam=T_world_cam,
            visible_ids=ids[near],
            visible_pixels_xy=pix[near],
            visible_distances_m=dist[near],
            illumination_gain=gain,
            depth_m=depth,
        )

    def _trace_again_if_moved(
        self, T_world_cam: FloatArray, yaw_rad: float
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """:meth:`trace`, run again only when the camera moved or the scene changed (a robot
        standing still sees the same surfaces; people, light and noise come after).

        Returns:
            copies of :meth:`trace`'s images, the caller's to draw on.
        """
        pose = T_world_cam.tobytes() + np.float64(yaw_rad).tobytes()
        last = self._last_trace
        if last is None or last.scene is not self.scene or last.pose != pose:
            last = _Trace(self.scene, pose, *self.trace(T_world_cam, yaw_rad))
            self._last_trace = last
        return last.radiance.copy(), last.depth.copy()

    def trace(
        self, T_world_cam: FloatArray, yaw_rad: float
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
        """Radiance and depth images of the world from a camera pose (no people, no noise).

        Args:
            T_world_cam: (4, 4) camera pose (camera frame -> world frame).
            yaw_rad: the robot's heading, rad (the wedges turn with it).

        Returns:
            radiance: (H, W) float32 grey levels (may exceed 255), 0 outside the circle.
            depth: (H, W) float32 distance along each ray, m (inf: sky or outside).
        """
        sc = self.scene
        R = np.ascontiguousarray(T_world_cam[:3, :3])
        o = np.ascontiguousarray(T_world_cam[:3, 3])
        start, ids = bin_primitives(
            o[0], o[1], yaw_rad, WEDGES, sc.max_height_m, sc.quad_a, sc.quad_d, sc.quad_len,
            sc.quad_n, sc.quad_z, sc.flat_c, sc.flat_ax, sc.flat_half, sc.cyl_c, sc.cyl_r,
            sc.sph_c, sc.sph_r)
        cam = self.camera
        radiance = np.zeros(cam.height * cam.width, np.float32)
        depth = np.full(cam.height * cam.width, np.inf, np.float32)
        atlas, light = sc.atlas, sc.light
        with _KERNEL:
            trace(
                self._pixels, self._neighbours, self._rays_c, self._wedge, self._pix_angle,
                self._sub_c, self._sub_wedge, R, o, start, ids,
                (sc.quad_a, sc.quad_d, sc.quad_len, sc.quad_n, sc.quad_z, sc.quad_tex, sc.quad_uv,
                 sc.quad_shade, sc.quad_emit),
                (sc.flat_c, sc.flat_ax, sc.flat_half, sc.flat_z, sc.flat_up, sc.flat_tex,
                 sc.flat_uv),
                (sc.cyl_c, sc.cyl_r, sc.cyl_z, sc.cyl_tex, sc.cyl_uv),
                (sc.sph_c, sc.sph_r, sc.sph_tex, sc.sph_uv),
                (sc.grid_origin, sc.floor_map, sc.floor_tex, sc.floor_uv, sc.ceil_lo, sc.ceil_hi,
                 sc.ceil_z, sc.ceil_tex, sc.ceil_uv),
                (sc.lamp_map, sc.lamp_c, sc.lamp_ax, sc.lamp_half, sc.lamp_tex, sc.lamp_emit),
                (atlas.texels, atlas.levels, atlas.level_count, atlas.wraps),
                (light.values, light.origin, light.res_m),
                sc.sky, sc.sun_w, self._brightness / 128.0, self._work, radiance, depth)
        return radiance.reshape(cam.height, cam.width), depth.reshape(cam.height, cam.width)

    def _picture_corners(
        self, R_cam_world: FloatArray, centre_w: FloatArray, depth: npt.NDArray[np.float32]
    ) -> tuple[npt.NDArray[np.int64], FloatArray, FloatArray]:
        """Picture corners in view: ids, projections (K, 2) px, distances (K,) m.

        A corner is in view when its picture faces the camera, it projects inside
        the image, and the depth image at its pixel or one of its 8 neighbours (a
        corner lies on the picture's edge) is its distance within
        :data:`_CORNER_DEPTH_TOLERANCE`.
        """
        corners = self.scene.picture_corners_w.reshape(-1, 3)
        rel_c = (corners - centre_w) @ R_cam_world.T
        dist = np.linalg.norm(rel_c, axis=1)
        pix, ok = self.camera.project(rel_c)
        normals = np.repeat(self.scene.picture_normals_w, 4, axis=0)
        ok &= (dist > NEAR_M) & (np.einsum("ij,ij->i", normals, centre_w - corners) > 0.0)
        cam = self.camera
        col = np.clip(np.round(pix[:, 0]).astype(int), 1, cam.width - 2)
        row = np.clip(np.round(pix[:, 1]).astype(int), 1, cam.height - 2)
        seen = np.zeros(corners.shape[0], bool)
        tolerance = _CORNER_DEPTH_TOLERANCE * dist + 0.02
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                seen |= np.abs(depth[row + dr, col + dc] - dist) <= tolerance
        keep = np.flatnonzero(ok & seen)
        return keep.astype(np.int64), pix[keep], dist[keep]

    def _post_process(
        self, radiance: npt.NDArray[np.float32], sim: Simulation, gain: float
    ) -> npt.NDArray[np.uint8]:
        """The camera's effects, radiance to frame: the one post-process stage.

        Args:
            radiance: (H, W) float32 grey levels of the scene (people drawn in).
            sim: the simulation (the body's motion during the exposure).
            gain: the scene's light relative to ``radiance`` this frame.

        Returns:
            (H, W) uint8 frame, 0 outside the image circle.
        """
        motion = camera_motion(sim.body.velocity_base, self.mount)
        return self.effects.apply(radiance, sim.now_ns, motion, gain)

    def illumination_gain(self, t_ns: int) -> float:
        """The global illumination gain at time ``t_ns`` (1 ± amplitude, slow sinusoid)."""
        phase = (
            2.0 * math.pi * (t_ns / 1e9) / self.config.illumination_period_s
            + self._illumination_phase
        )
        return 1.0 + self.config.illumination_amplitude * math.sin(phase)

    def _draw_people(
        self,
        sim: Simulation,
        image: npt.NDArray[np.float32],
        R_cam_world: FloatArray,
        centre_w: FloatArray,
        depth_m: npt.NDArray[np.float32],
    ) -> None:
        """Draw the people as textured figures (:mod:`sim.person_figure`), hidden per pixel
        by what the depth image shows nearer, lit by the light map where they stand."""
        if len(sim.people) == 0:
            return
        if self._figures is None:
            self._figures = PersonFigures(self.camera, TextureLibrary.builtin(),
                                          self._brightness, self._rng.spawn(1)[0])
        self._figures.draw_people(sim, image, R_cam_world, centre_w, depth_m,
                                  self.scene.light.at)


def _neighbours(pixels: npt.NDArray[np.int64], width: int, height: int) -> npt.NDArray[np.int32]:
    """(P, 4) the valid pixels' right, lower, left and upper neighbours as indices into
    ``pixels`` (flat indices of the valid pixels), or all four -1 where a neighbour is not
    valid or the pixel is on the first or last row (see :func:`sim._raycast.trace`).

    int32: the kernel reads them for every pixel of every frame, in half the memory."""
    size = width * height
    where = np.full(size, -1, np.int32)
    where[pixels] = np.arange(pixels.shape[0])
    steps = np.array([1, width, -1, -width])
    around = where[np.clip(pixels[:, None] + steps, 0, size - 1)]
    ok = (pixels >= width) & (pixels < size - width) & (around >= 0).all(axis=1)
    around[~ok] = -1
    return np.ascontiguousarray(around)
