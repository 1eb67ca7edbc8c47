"""The simulator's configs: world, body, odometry, renderer, camera sensor, people, the
emulated Pioneer and the scripted teach driver.

They are the ``[sim]`` table of a vmnav config file (:data:`shared.config.SIM_TABLE`;
the file's other tables are the robot's, :mod:`robot.config`)::

    [sim]
    world = "campus"

    [sim.people]
    count = 3

    [sim.sensor]
    read_noise_grey = 2.0

The simulated camera sits where the robot's config says its camera is: whoever builds
a simulation for a robot sets :attr:`SimConfig.camera_mount` from the robot's
``[camera.mount]`` (:func:`load_sim_config` takes it).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

from shared.config import (
    IN_FILE,
    SIM_TABLE,
    AriaLinkConfig,
    CameraMountConfig,
    from_mapping,
    load_toml,
    require,
)
from shared.errors import ConfigError


@dataclass(frozen=True, slots=True)
class BodyConfig:
    """The simulated Pioneer 3-AT body (defaults: P3-AT datasheet and MobileSim's model)."""

    length_m: float = 0.626
    """Length including bumpers, m (ARIA p3at params)."""
    width_m: float = 0.505
    """Width, m."""
    mass_kg: float = 12.0
    """Mass, kg."""
    max_speed_m_s: float = 0.7
    """Forward/backward speed limit, m/s."""
    max_omega_rad_s: float = math.radians(140.0)
    """Rotational speed limit, rad/s."""
    accel_m_s2: float = 0.3
    """Translational acceleration limit, m/s^2."""
    decel_m_s2: float = 0.6
    """Translational deceleration limit, m/s^2."""
    rot_accel_rad_s2: float = 1.74
    """Rotational acceleration (and deceleration) limit, rad/s^2."""
    stall_time_s: float = 0.3
    """Blocked motion for this long under a non-zero command reports a stall, s."""

    def __post_init__(self) -> None:
        for name in (
            "length_m",
            "width_m",
            "mass_kg",
            "max_speed_m_s",
            "max_omega_rad_s",
            "accel_m_s2",
            "decel_m_s2",
            "rot_accel_rad_s2",
            "stall_time_s",
        ):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")



@dataclass(frozen=True, slots=True)
class OdometryConfig:
    """Wheel odometry errors, kept apart from the ground truth."""

    trans_scale_sigma: float = 0.01
    """Std of the per-run translational scale error (wheel radius, slip), fraction."""
    rot_scale_sigma: float = 0.03
    """Std of the per-run rotational scale error (skid-steer slip), fraction."""
    trans_noise_m_s: float = 0.005
    """Std of white noise on the measured speed, per physics step, m/s."""
    rot_noise_rad_s: float = 0.005
    """Std of white noise on the measured turn rate, per physics step, rad/s."""

    def __post_init__(self) -> None:
        for name in ("trans_scale_sigma", "rot_scale_sigma", "trans_noise_m_s", "rot_noise_rad_s"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")



@dataclass(frozen=True, slots=True)
class RenderConfig:
    """The fisheye renderer's light: a slow global change of the scene's brightness
    (the camera's own flaws are :class:`SensorConfig`'s)."""

    illumination_amplitude: float = 0.15
    """Peak relative change of the global illumination gain over time (0 = constant)."""
    illumination_period_s: float = 40.0
    """Period of the slow global illumination change, s."""

    def __post_init__(self) -> None:
        require(
            0 <= self.illumination_amplitude < 1,
            f"illumination_amplitude must be in [0, 1), got {self.illumination_amplitude}",
        )
        require(
            self.illumination_period_s > 0,
            f"illumination_period_s must be > 0, got {self.illumination_period_s}",
        )



@dataclass(frozen=True, slots=True)
class SensorConfig:
    """A real camera's flaws (:mod:`sim.camera_effects`), each on by default at a value
    typical of a small CMOS camera behind a fisheye lens.

    The renderer draws the scene as the grey levels the sensor would record with
    ``reference_exposure_s`` at unity gain; this stage blurs, exposes, vignettes, adds
    noise and clips them. :meth:`ideal` is the camera without flaws (``motion_blur =
    false``, ``vignetting_rim = 1``, ``shot_noise_electrons_per_grey = 0``,
    ``read_noise_grey = 0``, ``auto_exposure = false`` with the reference exposure).
    """

    reference_exposure_s: float = 0.008
    """Exposure time at which, with unity gain, the sensor records the renderer's grey
    levels as drawn, s: how bright the world's light is for this camera."""
    auto_exposure: bool = True
    """Whether the exposure time and gain follow the image's brightness (a lagging loop)."""
    target_grey: float = 110.0
    """Auto-exposure's target mean grey level of the image circle, grey levels (0-255)."""
    exposure_time_constant_s: float = 0.5
    """Time constant of auto-exposure's first-order response to a change of brightness
    (in log exposure), s."""
    min_exposure_s: float = 0.0001
    """Shortest exposure time auto-exposure uses, s."""
    max_exposure_s: float = 0.03
    """Longest exposure time auto-exposure uses before raising the gain, s (at most the
    frame period)."""
    max_gain: float = 8.0
    """Highest analogue gain auto-exposure uses, factor (8 = 18 dB)."""
    exposure_s: float = 0.008
    """Exposure time with ``auto_exposure = false``, s (at most the frame period)."""
    gain: float = 1.0
    """Analogue gain with ``auto_exposure = false``, factor >= 1."""
    motion_blur: bool = True
    """Whether the image is blurred along the image motion during the exposure (the
    camera's rotation and translation, from the simulated body's velocity)."""
    vignetting_rim: float = 0.65
    """Relative illumination at the rim of the lens's field of view (cos^4-like falloff
    from the centre), fraction in (0, 1]; 1 = no vignetting."""
    shot_noise_electrons_per_grey: float = 20.0
    """Photo-electrons per grey level at unity gain (Poisson shot noise: variance
    ``gain * grey / this``), e-/grey level; 0 = no shot noise."""
    read_noise_grey: float = 1.0
    """Std of the Gaussian read noise at unity gain (scales with the gain), grey levels."""
    jpeg_quality: int = 80
    """JPEG quality of the frames where they travel as MJPEG (``vmnav sim serve
    --video``'s network camera), cv2.IMWRITE_JPEG_QUALITY 1-100."""

    @classmethod
    def ideal(cls) -> SensorConfig:
        """A flawless camera: records the renderer's grey levels as drawn (rounded, clipped)."""
        return cls(auto_exposure=False, motion_blur=False, vignetting_rim=1.0,
                   shot_noise_electrons_per_grey=0.0, read_noise_grey=0.0)

    def __post_init__(self) -> None:
        for name in ("reference_exposure_s", "exposure_time_constant_s", "min_exposure_s",
                     "exposure_s"):
            require(getattr(self, name) > 0, f"{name} must be > 0 s, got {getattr(self, name)}")
        require(self.min_exposure_s <= self.max_exposure_s,
                f"max_exposure_s must be >= min_exposure_s ({self.min_exposure_s} s), "
                f"got {self.max_exposure_s}")
        require(0 < self.target_grey < 255,
                f"target_grey must be in (0, 255) grey levels, got {self.target_grey}")
        require(self.max_gain >= 1, f"max_gain must be >= 1, got {self.max_gain}")
        require(1 <= self.gain <= self.max_gain,
                f"gain must be in [1, max_gain = {self.max_gain}], got {self.gain}")
        require(0 < self.vignetting_rim <= 1,
                f"vignetting_rim must be in (0, 1], got {self.vignetting_rim}")
        for name in ("shot_noise_electrons_per_grey", "read_noise_grey"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(1 <= self.jpeg_quality <= 100,
                f"jpeg_quality must be in 1..100, got {self.jpeg_quality}")



@dataclass(frozen=True, slots=True)
class PeopleConfig:
    """People walking about: moving bodies that occlude landmarks and can bump the robot."""

    count: int = 0
    """Number of people."""
    speed_m_s: float = 1.0
    """Walking speed, m/s."""
    radius_m: float = 0.25
    """Body radius (a vertical cylinder), m."""
    height_m: float = 1.75
    """Body height, m."""
    avoid_robot: bool = True
    """Whether people yield to the robot (False: they walk into it, for bump scenarios)."""
    clearance_m: float = 0.8
    """Look-ahead: a person yields when moving this far on, relative to the robot, touches it, m."""
    yield_patience_s: float = 3.0
    """Time a person stands yielding before walking off to another goal, s."""

    def __post_init__(self) -> None:
        require(self.count >= 0, f"count must be >= 0, got {self.count}")
        require(self.speed_m_s >= 0, f"speed_m_s must be >= 0, got {self.speed_m_s}")
        require(self.radius_m > 0, f"radius_m must be > 0, got {self.radius_m}")
        require(self.height_m > 0, f"height_m must be > 0, got {self.height_m}")
        require(self.clearance_m > 0, f"clearance_m must be > 0, got {self.clearance_m}")
        require(
            self.yield_patience_s >= 0,
            f"yield_patience_s must be >= 0, got {self.yield_patience_s}",
        )



@dataclass(frozen=True, slots=True)
class EmulatorConfig:
    """The emulated Pioneer 3-AT-SH (ARIA server, ``sim.pioneer``); aria-protocol.md §11."""

    name: str = "vmnav"
    """Robot name in the SYNC2 reply and the CONFIG packet ("MobileSim" would make ARIA
    treat the server as MobileSim)."""
    watchdog_stops: bool = True
    """Whether the watchdog (``link.watchdog_timeout_ns`` without a client packet) stops
    the robot until packets return (ARCOS) or only counts (MobileSim)."""
    battery_full_v: float = 13.0
    """Battery voltage at the start, V (a charged P3-AT pack)."""
    battery_empty_v: float = 11.0
    """The battery never reports less than this, V."""
    battery_drain_v_per_m: float = 0.0005
    """Voltage lost per metre of mean wheel travel, V/m (0.5 V per km)."""
    sonar_max_range_m: float = 5.0
    """Sonar range when nothing echoes, m (MobileSim reports 5000 mm)."""
    sonar_noise_m: float = 0.01
    """Std of Gaussian noise on each sonar range, m."""
    sonar_cycle_ns: int = 40_000_000
    """Each sonar array fires its next transducer this often, ns (both arrays together)."""
    sonar_beam_width_deg: float = 30.0
    """Full width of each transducer's cone, degrees: the Polaroid 600-series
    transducers of the Pioneer rings have a main lobe about 30 degrees wide (Polaroid
    6500 ranging module data sheet; Leonard & Durrant-Whyte 1992, ch. 2)."""
    sonar_rays: int = 7
    """Rays spread evenly across the cone, edges included; the nearest echo among them
    is the reading (1: the axis only)."""
    sonar_min_range_m: float = 0.15
    """Nearer than this a surface gives no echo: it returns while the transducer still
    rings from its pulse and the receiver is blanked, m (Polaroid 6500 data sheet:
    ranging from 6 in, 0.15 m)."""
    sonar_critical_angle_deg: float = 50.0
    """A ray meeting a flat surface (wall, furniture, object) further than this from
    its normal gives no echo: the sound glances away, degrees (specular reflection,
    Kuc & Siegel 1987; Leonard & Durrant-Whyte 1992). A chosen middle of the 40-60
    degrees used for painted walls; 90: no specular misses. Round shapes (people,
    trunks) always echo."""
    link: AriaLinkConfig = field(default_factory=AriaLinkConfig)
    """The robot end's timing: SIP cycle, watchdog, frame timeout."""

    def __post_init__(self) -> None:
        require(
            0 < len(self.name) <= 20 and self.name.isascii() and self.name.isprintable(),
            f"name must be 1-20 printable ASCII characters, got {self.name!r}",
        )
        require(
            0 < self.battery_empty_v <= self.battery_full_v,
            f"battery_empty_v must be in (0, battery_full_v], got {self.battery_empty_v} "
            f"(battery_full_v {self.battery_full_v})",
        )
        require(
            self.battery_full_v < 25.5,
            f"battery_full_v must be < 25.5 V (one byte of decivolts), got {self.battery_full_v}",
        )
        for name in ("battery_drain_v_per_m", "sonar_noise_m"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(
            0 < self.sonar_max_range_m <= 65.0,
            f"sonar_max_range_m must be in (0, 65] (u16 mm), got {self.sonar_max_range_m}",
        )
        require(self.sonar_cycle_ns > 0, f"sonar_cycle_ns must be > 0, got {self.sonar_cycle_ns}")
        require(0.0 <= self.sonar_beam_width_deg <= 90.0,
                f"sonar_beam_width_deg must be in [0, 90], got {self.sonar_beam_width_deg}")
        require(1 <= self.sonar_rays <= 31, f"sonar_rays must be in [1, 31], got {self.sonar_rays}")
        require(0.0 <= self.sonar_min_range_m < self.sonar_max_range_m,
                f"sonar_min_range_m must be in [0, sonar_max_range_m), got "
                f"{self.sonar_min_range_m} (sonar_max_range_m {self.sonar_max_range_m})")
        require(0.0 < self.sonar_critical_angle_deg <= 90.0,
                f"sonar_critical_angle_deg must be in (0, 90], got "
                f"{self.sonar_critical_angle_deg}")



@dataclass(frozen=True, slots=True)
class TeachDriverConfig:
    """The simulator's scripted human-like teach driver (``sim.teach_driver``).

    Pure pursuit of the route shifted sideways by a smooth random wander, at a
    cruise speed that drifts slowly: a person steering by eye, never exactly on
    the line, never exactly at constant speed.
    """

    speed_m_s: float = 0.3
    """Mean cruise speed, m/s."""
    speed_variation: float = 0.1
    """Peak relative deviation of the cruise speed (smooth in distance), fraction in [0, 1)."""
    wander_amplitude_m: float = 0.04
    """Peak lateral offset of the pursued line from the route, m."""
    wander_wavelength_m: tuple[float, float] = (2.0, 6.0)
    """Range of the wavelengths of the wander and the speed drift, along the route, m."""
    lookahead_m: float = 0.6
    """Pure-pursuit look-ahead distance, m."""
    max_omega_rad_s: float = 0.6
    """Turn-rate limit, rad/s (a person turns slowly while teaching)."""
    goal_tolerance_m: float = 0.1
    """The drive ends within this distance of the route's last waypoint, m."""

    def __post_init__(self) -> None:
        for name in ("speed_m_s", "lookahead_m", "max_omega_rad_s", "goal_tolerance_m"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(
            0 <= self.speed_variation < 1,
            f"speed_variation must be in [0, 1), got {self.speed_variation}",
        )
        require(
            self.wander_amplitude_m >= 0,
            f"wander_amplitude_m must be >= 0, got {self.wander_amplitude_m}",
        )
        low, high = self.wander_wavelength_m
        require(
            0 < low <= high,
            f"wander_wavelength_m must be (low, high) with 0 < low <= high, got {(low, high)}",
        )



@dataclass(frozen=True, slots=True)
class SimConfig:
    """The simulated world and everything in it."""

    world: str = "lab"
    """A built-in world name (``lab``, ``campus``) or the path of a world TOML file."""
    seed: int = 1
    """Seed of every random draw in the simulation (landmarks, noise, people)."""
    physics_dt_ns: int = 10_000_000
    """Fixed physics step, ns (pymunk wants a fixed step)."""
    frame_period_ns: int = 66_666_667
    """Camera frame period, ns (15 frames/s, as in the paper)."""
    landmark_density_scale: float = 1.0
    """Multiplies the world's landmark densities (1 = as the world file says)."""
    camera_file: str | None = None
    """Calibration JSON of the simulated camera; None = the default 800x600, 185 degree model."""
    body: BodyConfig = field(default_factory=BodyConfig)
    odometry: OdometryConfig = field(default_factory=OdometryConfig)
    render: RenderConfig = field(default_factory=RenderConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    people: PeopleConfig = field(default_factory=PeopleConfig)
    emulator: EmulatorConfig = field(default_factory=EmulatorConfig)
    teach_driver: TeachDriverConfig = field(default_factory=TeachDriverConfig)
    camera_mount: CameraMountConfig = field(default_factory=CameraMountConfig,
                                            metadata={IN_FILE: False})
    """Where the simulated camera sits on the body: the robot's mount, set where a
    simulation is built for a robot config (a file sets it as the robot's
    ``[camera.mount]``, never under ``[sim]``)."""

    def __post_init__(self) -> None:
        require(self.seed >= 0, f"seed must be >= 0, got {self.seed}")
        require(self.physics_dt_ns > 0, f"physics_dt_ns must be > 0, got {self.physics_dt_ns}")
        require(
            self.frame_period_ns >= self.physics_dt_ns,
            f"frame_period_ns ({self.frame_period_ns}) must be >= "
            f"physics_dt_ns ({self.physics_dt_ns})",
        )
        frame_s = self.frame_period_ns / 1e9
        for name in ("max_exposure_s", "exposure_s"):
            value = getattr(self.sensor, name)
            require(value <= frame_s,
                    f"sensor.{name} ({value} s) must be <= the frame period ({frame_s} s)")
        require(
            self.landmark_density_scale >= 0,
            f"landmark_density_scale must be >= 0, got {self.landmark_density_scale}",
        )



def load_sim_config(path: str | Path | None, camera_mount: CameraMountConfig) -> SimConfig:
    """The ``[sim]`` table of a vmnav TOML config file (``None``: the defaults), with the
    simulated camera at ``camera_mount`` (the robot's, ``robot.config``'s ``camera.mount``).

    Raises:
        ConfigError: naming the file, table and key at fault.
    """
    table = {} if path is None else load_toml(path).get(SIM_TABLE, {})
    render = table.get("render") if isinstance(table, dict) else None
    if isinstance(render, dict) and "noise_sigma" in render:
        raise ConfigError(str(path), f"{SIM_TABLE}.render.noise_sigma: the sensor's noise moved to "
                          f"[{SIM_TABLE}.sensor] read_noise_grey and shot_noise_electrons_per_grey")
    config = SimConfig() if path is None else from_mapping(SimConfig, table, str(path), SIM_TABLE)
    return dataclasses.replace(config, camera_mount=camera_mount)
