"""A real camera's flaws on each rendered frame: motion blur, vignetting, exposure and gain
(auto-exposure that lags), shot and read noise, clipping.

The renderer draws the scene as the grey levels a sensor records with
``SensorConfig.reference_exposure_s`` at unity gain (the scene's light). This stage
turns that ideal picture into what a small CMOS camera behind the lens records, in the
order light meets the sensor (:meth:`CameraEffects.apply`):

1. **Motion blur.** The exposure is centred on the frame's time stamp; during it the
   camera turns (``omega``) and moves (``v``), and a static point's bearing ``b``
   moves as ``db/dt = -omega x b - (I - b b^T) v / d`` (d: its distance). Its pixel
   moves by the camera model's Jacobian of that over the exposure time: the blur
   vector field, exact for rotation (which dominates on a turning robot); for
   translation ``d`` is a depth prior (the floor plane below the horizon, 3 m
   elsewhere). The image is averaged along that field: 3^k equally spaced taps
   (spacing <= 1.5 px, k <= 3), made with 2k ``cv2.remap`` calls as a cascade of
   3-tap averages (taps at -s, 0, +s, then -3s, 0, +3s, ...); a blur of up to 3 px
   has one level, its outer taps weighted so that the blur's variance is the box's
   (bilinear taps blur by themselves).
2. **Vignetting.** The lens's relative illumination ``(1 + rho^2 tan^2 a)^-2`` with
   ``rho`` the ray's angle from the optical axis over half the field of view, and
   ``cos^4 a = vignetting_rim``: the cos^4 law of a lens whose rim is at angle ``a``.
3. **Exposure and gain.** The signal scales with ``exposure_s / reference_exposure_s
   * gain``.
4. **Noise.** Shot noise, Poisson in photo-electrons (``K`` e- per grey level at unity
   gain): variance ``gain * grey / K`` grey levels^2 (the normal approximation, valid
   above a few electrons); Gaussian read noise ``gain * read_noise_grey``.
5. **Clipping.** Rounded and clipped to 0-255 (a saturated pixel stays 255); outside
   the lens's image circle stays black (the black clamp).
6. **Auto-exposure**, after the frame: the mean grey ``m`` of the image circle
   (clipped, as the camera meters it) moves the exposure value ``E`` (exposure time x
   gain) as a first-order lag in log exposure,
   ``log E += (1 - exp(-dt / tau)) log(target / m)``, so after a brightness step the
   image's log mean returns to the target as ``exp(-t / tau)``. ``E`` is spent on
   exposure time first (up to ``max_exposure_s``), then on gain. The first frame is
   metered before it is exposed (a camera that was already running).

Rules: the only state is the exposure value and the last frame's metering (time
stamp, mean grey); a frame's exposure follows from the frames before its time stamp
(``dt`` from successive time stamps), so rendering again at the same time repeats the
exposure. The noise is deterministic given the ``rng``: a small bank of standard
normal images is drawn once, and each frame sums windows of two of them at random
offsets (fresh normals would cost 6 ms a frame at 800x600).
JPEG compression is not here: it happens where frames travel as MJPEG
(:mod:`sim.camera_server`, ``SensorConfig.jpeg_quality``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from shared.camera_model import CameraModel
from shared.camera_mount import rotation_base_cam
from shared.config import CameraMountConfig
from sim.config import SensorConfig

FloatArray = npt.NDArray[np.float64]

_BLUR_GRID_PX = 8
"""The blur field is computed on a grid this many pixels apart, then interpolated."""
_MIN_BLUR_PX = 0.4
"""Blur shorter than this (px) is not drawn (rows of the image where all of it is shorter
are left as they are)."""
_MAX_TAP_SPACING_PX = 1.5
"""Blur taps are at most this far apart, px (bilinear taps: a smooth blur)."""
_MAX_BLUR_LEVELS = 3
"""At most 3^3 = 27 taps (a blur longer than 39 px gets taps further apart)."""
_FAR_DEPTH_M = 3.0
"""Depth prior of rays that do not meet the floor nearer, m (a room's walls)."""
_NOISE_BANK = 4
_NOISE_MARGIN_PX = 48
"""The noise windows' offsets range over this many pixels in each direction."""
_METER_STEP_PX = 4
"""Auto-exposure meters every 4th pixel of every 4th row."""


@dataclass(frozen=True, slots=True)
class CameraMotion:
    """The camera's velocity during an exposure.

    Attributes:
        omega_cam_rad_s: (x, y, z) angular velocity of the camera, camera frame, rad/s.
        velocity_cam_m_s: (x, y, z) velocity of the optical centre, camera frame, m/s.
    """

    omega_cam_rad_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity_cam_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class SensorReading:
    """How one frame was exposed.

    Attributes:
        exposure_s: exposure time, s.
        gain: analogue gain, factor.
        blur_px: the longest blur in the image, px (0 when not drawn).
        mean_grey: mean grey level of the image circle as recorded (every 4th pixel).
    """

    exposure_s: float
    gain: float
    blur_px: float
    mean_grey: float


def camera_motion(velocity_base: tuple[float, float, float],
                  mount: CameraMountConfig) -> CameraMotion:
    """The camera's velocity on a robot moving on the floor.

    Args:
        velocity_base: (vx_m_s forward, vy_m_s left, omega_rad_s), robot frame (as
            :attr:`sim.body.PioneerBody.velocity_base`).
        mount: where the camera sits on the robot.
    """
    vx, vy, omega = velocity_base
    R_cam_base = rotation_base_cam(mount).T
    omega_c = R_cam_base @ np.array([0.0, 0.0, omega])
    # The optical centre's velocity: v + omega x r, r = (x_m, y_m) on the robot.
    v_c = R_cam_base @ np.array([vx - omega * mount.y_m, vy + omega * mount.x_m, 0.0])
    return CameraMotion(tuple(float(w) for w in omega_c),  # type: ignore[arg-type]
                        tuple(float(v) for v in v_c))  # type: ignore[arg-type]


class CameraEffects:
    """The sensor stage of one simulated camera (see the module docstring).

    Args:
        camera: the lens (image size, image circle, projection).
        mount: the camera's pose on the robot (the floor's depth prior for blur).
        config: the flaws.
        rng: draws the noise bank and each frame's noise windows.

    Attributes:
        last: how the last frame was exposed (None before the first).
        circle: (H, W) uint8, 255 inside the lens's image circle, else 0.
    """

    def __init__(self, camera: CameraModel, mount: CameraMountConfig, config: SensorConfig,
                 rng: np.random.Generator) -> None:
        self.config = config
        self._rng = rng
        self._size = (camera.width, camera.height)
        angle, valid = _ray_angles(camera)
        self.circle = np.where(valid, 255, 0).astype(np.uint8)
        # Every per-pixel step works on the image circle's bounding box only.
        x, y, w, h = cv2.boundingRect(self.circle)
        self._roi = (slice(y, y + h), slice(x, x + w))
        self._roi_size = (w, h)
        self._circle_roi = self.circle[self._roi]
        self._vignette = _vignetting(angle, valid, math.radians(camera.fov_deg / 2.0),
                                     config.vignetting_rim)[self._roi]
        self._grid = np.dstack(np.meshgrid(np.arange(w, dtype=np.float32),
                                           np.arange(h, dtype=np.float32)))
        basis = _blur_basis(camera, mount, (x, y, w, h))
        self._blur_shape = basis.shape[1:]
        self._blur_basis = np.ascontiguousarray(basis.reshape(6, -1))
        m = _NOISE_MARGIN_PX
        self._noise = rng.standard_normal((_NOISE_BANK, h + m, w + m), dtype=np.float32)
        self._meter_mask = self._circle_roi[::_METER_STEP_PX, ::_METER_STEP_PX]
        self._log_e: float | None = None if config.auto_exposure else math.log(
            config.exposure_s * config.gain / config.reference_exposure_s)
        self._metered: tuple[int, float] | None = None
        self.last: SensorReading | None = None

    def apply(self, scene: npt.NDArray[np.uint8] | npt.NDArray[np.float32], t_ns: int,
              motion: CameraMotion, light_gain: float = 1.0) -> npt.NDArray[np.uint8]:
        """Record one frame of ``scene``.

        Args:
            scene: (H, W) uint8 or float32 grey levels at the reference exposure (float
                may exceed 255: light the sensor then clips), the camera's image size.
            t_ns: the exposure's time stamp (its middle), ns.
            motion: the camera's velocity during the exposure.
            light_gain: the scene's light relative to ``scene``'s grey levels (a lamp
                switched off, a cloud); not clipped before the sensor.

        Returns:
            (H, W) uint8 grey image as the camera records it.

        Raises:
            ValueError: ``scene`` is not the camera's (H, W).
        """
        w, h = self._size
        if scene.shape != (h, w):
            raise ValueError(f"scene: expected shape {(h, w)}, got {scene.shape}")
        cfg = self.config
        self._adapt(t_ns)
        light = scene[self._roi].astype(np.float32)
        step = _METER_STEP_PX
        if self._log_e is None:  # metered before the first exposure
            seen = cv2.multiply(light[::step, ::step], self._vignette[::step, ::step],
                                scale=light_gain)
            mean = cv2.mean(seen, mask=self._meter_mask)[0]
            self._log_e = self._clamped(math.log(cfg.target_grey / max(mean, 1e-3)))
        exposure_s, gain = self._split(math.exp(self._log_e))
        blur_px = 0.0
        if cfg.motion_blur:
            light, blur_px = self._blur(light, motion, exposure_s)
        # Blur first: the scene moves over the sensor; the lens's falloff is fixed to it.
        signal = cv2.multiply(light, self._vignette,
                              scale=light_gain * exposure_s / cfg.reference_exposure_s * gain)
        self._add_noise(signal, gain)
        recorded = cv2.convertScaleAbs(cv2.max(signal, 0.0))  # rounds; clips at 255
        image = np.zeros((h, w), dtype=np.uint8)
        image[self._roi] = cv2.bitwise_and(recorded, self._circle_roi)
        mean = cv2.mean(image[self._roi][::step, ::step], mask=self._meter_mask)[0]
        self._metered = (t_ns, mean)
        self.last = SensorReading(exposure_s, gain, blur_px, mean)
        return image

    # -- exposure -----------------------------------------------------------------------

    def _clamped(self, log_e: float) -> float:
        cfg = self.config
        low = cfg.min_exposure_s / cfg.reference_exposure_s
        high = cfg.max_exposure_s * cfg.max_gain / cfg.reference_exposure_s
        return min(max(log_e, math.log(low)), math.log(high))

    def _split(self, e: float) -> tuple[float, float]:
        """Exposure value -> (exposure time s, gain): time first, then gain."""
        cfg = self.config
        if not cfg.auto_exposure:
            return cfg.exposure_s, cfg.gain
        wanted_s = e * cfg.reference_exposure_s
        exposure_s = min(max(wanted_s, cfg.min_exposure_s), cfg.max_exposure_s)
        return exposure_s, min(max(wanted_s / exposure_s, 1.0), cfg.max_gain)

    def _adapt(self, t_ns: int) -> None:
        """Auto-exposure's first-order step towards the target from the last frame metered
        before ``t_ns`` (module docstring, 6)."""
        if self._metered is None or self._log_e is None or not self.config.auto_exposure:
            return
        last_ns, mean_grey = self._metered
        if t_ns <= last_ns:
            return
        self._metered = None
        alpha = 1.0 - math.exp(-(t_ns - last_ns) / 1e9 / self.config.exposure_time_constant_s)
        error = math.log(self.config.target_grey / max(mean_grey, 0.5))
        self._log_e = self._clamped(self._log_e + alpha * error)

    # -- blur and noise -----------------------------------------------------------------

    def _blur(self, light: npt.NDArray[np.float32], motion: CameraMotion,
              exposure_s: float) -> tuple[npt.NDArray[np.float32], float]:
        """``light`` averaged along the image motion of the exposure; the longest blur, px."""
        rates = np.array(motion.omega_cam_rad_s + motion.velocity_cam_m_s, dtype=np.float32)
        if not rates.any():
            return light, 0.0
        field = ((rates * np.float32(exposure_s)) @ self._blur_basis).reshape(self._blur_shape)
        row_length = np.sqrt(np.einsum("ijk,ijk->ij", field, field).max(axis=1))  # per grid row
        length = float(row_length.max())
        if length < _MIN_BLUR_PX:
            return light, 0.0
        field = cv2.resize(field, self._roi_size, interpolation=cv2.INTER_LINEAR)
        for rows, span_length in self._blurred_spans(row_length):
            levels = math.ceil(math.log(span_length / _MAX_TAP_SPACING_PX + 1.0, 3.0))
            levels = min(max(levels, 1), _MAX_BLUR_LEVELS)
            step = 1.0 / (3**levels - 1)  # tap spacing, a fraction of the blur vector
            side = _side_weight(span_length) if levels == 1 else 1.0 / 3.0
            span_field, grid = field[rows], self._grid[rows]
            for level in range(levels):  # each level reads the previous one, in place
                s = step * 3**level
                ahead = cv2.remap(light, cv2.scaleAdd(span_field, s, grid), None,
                                  cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
                behind = cv2.remap(light, cv2.scaleAdd(span_field, -s, grid), None,
                                   cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
                light[rows] = cv2.addWeighted(cv2.add(ahead, behind), side, light[rows],
                                              1.0 - 2.0 * side, 0.0)
        return light, length

    def _blurred_spans(self, row_length: FloatArray) -> list[tuple[slice, float]]:
        """Row spans of the roi whose blur is long enough to draw, with their longest blur.

        Args:
            row_length: (h,) longest blur of each row of the coarse grid, px.
        """
        active = row_length >= _MIN_BLUR_PX
        # Interpolation reads the neighbouring grid rows too.
        active[1:] |= active[:-1].copy()
        active[:-1] |= active[1:].copy()
        h = row_length.shape[0]
        height = self._roi_size[1]
        spans = []
        edges = np.flatnonzero(np.diff(np.concatenate([[0], active.astype(np.int8), [0]])))
        for i0, i1 in zip(edges[::2], edges[1::2], strict=True):
            rows = slice(math.floor(i0 * height / h), min(math.ceil(i1 * height / h), height))
            spans.append((rows, float(row_length[i0:i1].max())))
        return spans

    def _add_noise(self, signal: npt.NDArray[np.float32], gain: float) -> None:
        """Add shot and read noise to ``signal`` (grey levels) in place."""
        cfg = self.config
        read_var = (gain * cfg.read_noise_grey) ** 2
        shot = cfg.shot_noise_electrons_per_grey > 0
        if not shot and read_var == 0.0:
            return
        h, w = signal.shape
        j, k = self._rng.choice(_NOISE_BANK, size=2, replace=False)
        (y0, x0), (y1, x1) = self._rng.integers(0, _NOISE_MARGIN_PX + 1, size=(2, 2))
        normal = cv2.add(self._noise[j, y0:y0 + h, x0:x0 + w], self._noise[k, y1:y1 + h, x1:x1 + w])
        # normal has variance 2: halve the variance it scales. The signal is >= 0 here.
        if shot:
            per_grey = 0.5 * gain / cfg.shot_noise_electrons_per_grey
            std = cv2.sqrt(cv2.addWeighted(signal, per_grey, signal, 0.0, 0.5 * read_var))
            cv2.multiply(normal, std, dst=normal)
        else:
            normal *= np.float32(math.sqrt(0.5 * read_var))
        cv2.add(signal, normal, dst=signal)


def _side_weight(length_px: float) -> float:
    """Weight of each outer tap of a 3-tap blur of length ``length_px`` (taps at -L/2, 0,
    +L/2), so that the kernel's variance is the box's, L^2 / 12.

    A bilinear tap at a fractional offset f blurs by itself (variance f (1 - f)), which
    for blurs of a pixel or two would double the blur; the outer taps' weight w gives
    variance 2 w (d^2 + f (1 - f)) with d = L / 2, f its fractional part (along the
    blur; exact for blur along a pixel axis).
    """
    d = 0.5 * length_px
    f = d - math.floor(d)
    return min(length_px**2 / 12.0 / (2.0 * (d * d + f * (1.0 - f))), 1.0 / 3.0)


def _ray_angles(camera: CameraModel) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.bool_]]:
    """Each pixel's ray angle from the optical axis (rad, (H, W)) and its validity."""
    u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64),
                       np.arange(camera.height, dtype=np.float64))
    bearings, valid = camera.lift(np.column_stack([u.ravel(), v.ravel()]))
    with np.errstate(invalid="ignore"):
        angle = np.arccos(np.clip(bearings[:, 2], -1.0, 1.0))
    angle = np.where(valid, angle, 0.0).astype(np.float32)
    return angle.reshape(camera.height, camera.width), valid.reshape(camera.height, camera.width)


def _vignetting(angle: npt.NDArray[np.float32], valid: npt.NDArray[np.bool_],
                half_fov_rad: float, rim: float) -> npt.NDArray[np.float32]:
    """Relative illumination (H, W) float32: ``(1 + rho^2 tan^2 a)^-2``, cos^4 a = ``rim``,
    rho = angle / half field of view; 0 outside the image circle."""
    tan2 = 1.0 / math.sqrt(rim) - 1.0  # tan^2 a = 1 / cos^2 a - 1
    rho2 = (angle / np.float32(half_fov_rad)) ** 2
    falloff = 1.0 / (1.0 + rho2 * np.float32(tan2)) ** 2
    return np.where(valid, falloff, 0.0).astype(np.float32)


def _blur_basis(camera: CameraModel, mount: CameraMountConfig,
                roi: tuple[int, int, int, int]) -> npt.NDArray[np.float32]:
    """Image motion per unit of the camera's velocity on a coarse grid over ``roi``
    (x, y, width, height of a part of the image, px).

    Returns:
        (6, h, w, 2) float32: pixel velocity (px/s) per rad/s about camera x, y, z and
        per m/s along camera x, y, z, at the grid points that ``cv2.resize`` to the
        full image interpolates from (outside the image circle: the nearest inside).
    """
    x0, y0, width, height = roi
    w, h = math.ceil(width / _BLUR_GRID_PX), math.ceil(height / _BLUR_GRID_PX)
    # cv2.resize (linear) reads grid point i at pixel (i + 0.5) W / w - 0.5 of the roi.
    xs = x0 + (np.arange(w) + 0.5) * width / w - 0.5
    ys = y0 + (np.arange(h) + 0.5) * height / h - 0.5
    gx, gy = np.meshgrid(xs, ys)
    b, valid = camera.lift(np.column_stack([gx.ravel(), gy.ravel()]))
    valid &= np.isfinite(b).all(axis=1)
    b = b[valid]
    # Depth prior: the floor plane where a ray meets it nearer than _FAR_DEPTH_M.
    up_c = rotation_base_cam(mount).T @ np.array([0.0, 0.0, 1.0])
    down = -(b @ up_c)
    with np.errstate(divide="ignore"):
        depth = np.where(down > 0, np.minimum(mount.height_m / down, _FAR_DEPTH_M), _FAR_DEPTH_M)
    basis = np.zeros((6, h * w, 2))
    eps = 1e-4
    for i in range(6):
        e = np.eye(3)[i % 3]
        # Rotation: dX/dt = -omega x X; translation: dX/dt = -v, on the sphere its
        # tangential part over the depth.
        db = -np.cross(e, b) if i < 3 else -(e - b * (b @ e)[:, None]) / depth[:, None]
        ahead, _ = camera.project(b + eps * db)
        behind, _ = camera.project(b - eps * db)
        basis[i, valid] = (ahead - behind) / (2.0 * eps)
    # Outside the circle: the nearest grid point inside (so interpolation near the rim
    # does not fade the blur towards zero).
    outside = (~valid).reshape(h, w).astype(np.uint8)
    _, labels = cv2.distanceTransformWithLabels(outside, cv2.DIST_L2, 5,
                                                labelType=cv2.DIST_LABEL_PIXEL)
    inside_index = np.flatnonzero(valid)
    nearest = inside_index[labels.ravel() - 1]
    return basis[:, nearest].reshape(6, h, w, 2).astype(np.float32)
