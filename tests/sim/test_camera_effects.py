"""A real camera's flaws (sim/camera_effects.py): each changes the image as its model says."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import numpy.typing as npt
import pytest

from shared.camera_model import CameraModel
from shared.config import CameraMountConfig
from shared.pose import Pose2
from sim.camera_effects import CameraEffects, CameraMotion, camera_motion
from sim.config import SensorConfig, SimConfig
from sim.renderer import FisheyeRenderer
from sim.simulation import Simulation
from tests.sim.rooms import box_room

CAMERA = CameraModel.default()
MOUNT = CameraMountConfig()
FRAME_NS = 66_666_667
IDEAL = SensorConfig.ideal()
PX_PER_RAD = CAMERA.K[0, 0] / (1.0 + CAMERA.xi)
"""The default lens's scale at the image centre (unified model: f / (1 + xi))."""


def effects(config: SensorConfig, seed: int = 5) -> CameraEffects:
    return CameraEffects(CAMERA, MOUNT, config, np.random.default_rng(seed))


def uniform(level: float) -> npt.NDArray[np.float32]:
    return np.full((CAMERA.height, CAMERA.width), level, dtype=np.float32)


def yaw(omega_rad_s: float) -> CameraMotion:
    """A level, forward-looking camera turning left: about camera -y."""
    return CameraMotion(omega_cam_rad_s=(0.0, -omega_rad_s, 0.0))


def line_width_px(image: npt.NDArray[np.uint8], axis: int) -> float:
    """Std of a centred bright line's profile across the line, px (rows 280-320 or
    columns 380-420 averaged along the line, within 10 px of the peak)."""
    if axis == 1:  # vertical line: profile along x
        profile = image[280:320, 360:440].astype(float).mean(axis=0)
    else:
        profile = image[260:340, 380:420].astype(float).mean(axis=1)
    peak = int(np.argmax(profile))
    profile = np.maximum(profile[peak - 10:peak + 11] - np.median(profile), 0.0)
    x = np.arange(profile.size)
    mean = (profile * x).sum() / profile.sum()
    return float(np.sqrt((profile * (x - mean) ** 2).sum() / profile.sum()))


def cross(width: int = 1) -> npt.NDArray[np.uint8]:
    """A dark image with a bright vertical and a bright horizontal line through the centre."""
    scene = np.full((CAMERA.height, CAMERA.width), 20, dtype=np.uint8)
    scene[:, 400 - width // 2:400 + (width + 1) // 2] = 220
    scene[300 - width // 2:300 + (width + 1) // 2, :] = 220
    return scene


class TestCameraMotion:
    def test_a_turning_robot_turns_its_forward_camera_about_image_y(self) -> None:
        motion = camera_motion((0.0, 0.0, 1.0), CameraMountConfig(x_m=0.2, y_m=0.0))
        np.testing.assert_allclose(motion.omega_cam_rad_s, (0.0, -1.0, 0.0), atol=1e-12)
        # The optical centre 0.2 m ahead of the centre moves left at 0.2 m/s: camera -x.
        np.testing.assert_allclose(motion.velocity_cam_m_s, (-0.2, 0.0, 0.0), atol=1e-12)

    def test_driving_forward_moves_along_the_optical_axis(self) -> None:
        motion = camera_motion((0.3, 0.0, 0.0), MOUNT)
        np.testing.assert_allclose(motion.velocity_cam_m_s, (0.0, 0.0, 0.3), atol=1e-12)


class TestMotionBlur:
    @staticmethod
    def blur_of(omega: float, exposure_s: float) -> tuple[float, float, float]:
        config = dataclasses.replace(IDEAL, motion_blur=True, exposure_s=exposure_s,
                                     reference_exposure_s=exposure_s)  # same brightness
        fx = effects(config)
        image = fx.apply(cross(), 0, yaw(omega))
        assert fx.last is not None
        return line_width_px(image, axis=1), line_width_px(image, axis=0), fx.last.blur_px

    def test_blur_length_grows_with_angular_speed_and_exposure(self) -> None:
        sharp, _, none = self.blur_of(0.0, 0.01)
        assert none == 0.0
        widths = {}
        for omega, exposure_s in ((0.5, 0.01), (1.0, 0.01), (2.0, 0.01), (1.0, 0.02)):
            across, along, longest = self.blur_of(omega, exposure_s)
            expected_px = omega * exposure_s * PX_PER_RAD  # blur length at the centre
            # A box of length L widens a line's profile to sqrt(s0^2 + L^2 / 12).
            measured_px = math.sqrt(max(across**2 - sharp**2, 0.0) * 12.0)
            assert measured_px == pytest.approx(expected_px, rel=0.25, abs=0.3)
            assert longest >= expected_px  # the longest blur in the image (towards the rim)
            assert along == pytest.approx(sharp, abs=0.1)  # a turn blurs across, not along
            widths[omega, exposure_s] = across
        assert widths[0.5, 0.01] < widths[1.0, 0.01] < widths[2.0, 0.01]
        assert widths[1.0, 0.02] == pytest.approx(widths[2.0, 0.01], abs=0.15)

    def test_no_blur_when_switched_off(self) -> None:
        fx = effects(IDEAL)
        assert np.array_equal(fx.apply(cross(), 0, yaw(2.0)), fx.apply(cross(), 0, yaw(0.0)))

    def test_driving_forward_blurs_the_floor_more_than_the_horizon(self) -> None:
        config = dataclasses.replace(IDEAL, motion_blur=True, exposure_s=0.03)
        fx = effects(config)
        rng = np.random.default_rng(1)
        scene = rng.integers(0, 255, (CAMERA.height, CAMERA.width)).astype(np.uint8)
        moving = fx.apply(scene, 0, CameraMotion(velocity_cam_m_s=(0.0, 0.0, 0.7)))
        still = effects(config).apply(scene, 0, CameraMotion())
        change = np.abs(moving.astype(float) - still.astype(float))
        floor, horizon = change[480:520, 380:420].mean(), change[280:320, 380:420].mean()
        assert floor > 3.0 * horizon


class TestAutoExposure:
    def test_gain_lags_a_brightness_step_with_the_time_constant(self) -> None:
        tau_s = 0.5
        config = dataclasses.replace(IDEAL, auto_exposure=True, exposure_time_constant_s=tau_s,
                                     target_grey=100.0)
        fx = effects(config)
        t_ns = 0
        for _ in range(5):  # settles on the first frame (metered before exposing)
            fx.apply(uniform(60.0), t_ns, CameraMotion())
            t_ns += FRAME_NS
        assert fx.last is not None and fx.last.mean_grey == pytest.approx(100.0, abs=0.6)
        errors, times = [], []
        for k in range(30):  # the light doubles
            fx.apply(uniform(120.0), t_ns, CameraMotion())
            errors.append(math.log(fx.last.mean_grey / 100.0))
            times.append(k * FRAME_NS / 1e9)
            t_ns += FRAME_NS
        assert errors[0] == pytest.approx(math.log(2.0), abs=0.01)  # first frame: all of it
        expected = math.log(2.0) * np.exp(-np.array(times) / tau_s)
        np.testing.assert_allclose(errors, expected, atol=0.01)

    def test_more_light_than_the_scene_holds_is_not_clipped_before_the_sensor(self) -> None:
        fx = effects(dataclasses.replace(IDEAL, auto_exposure=True, target_grey=60.0))
        scene = uniform(150.0)
        scene[:, 400:] = 250.0
        for k in range(40):  # the light doubles: 300 and 500 reach the lens
            image = fx.apply(scene, k * FRAME_NS, CameraMotion(), light_gain=2.0)
        left, right = image[250:350, 300:380].mean(), image[250:350, 420:500].mean()
        assert right / left == pytest.approx(500.0 / 300.0, rel=0.02)
        assert image[250:350, 300:500].mean() == pytest.approx(60.0, abs=3.0)

    def test_dark_scenes_take_longer_exposures_then_gain(self) -> None:
        config = dataclasses.replace(SensorConfig(), motion_blur=False)
        fx = effects(config)
        fx.apply(uniform(110.0), 0, CameraMotion())
        assert fx.last is not None
        bright = fx.last
        fx = effects(config)
        fx.apply(uniform(4.0), 0, CameraMotion())
        dark = fx.last
        assert dark is not None
        assert bright.gain == 1.0 and bright.exposure_s < config.max_exposure_s
        assert dark.exposure_s == config.max_exposure_s and dark.gain > 1.0

    def test_a_repeated_time_stamp_does_not_move_the_exposure(self) -> None:
        fx = effects(dataclasses.replace(IDEAL, auto_exposure=True))
        fx.apply(uniform(80.0), 0, CameraMotion())
        first = fx.apply(uniform(160.0), FRAME_NS, CameraMotion())
        again = fx.apply(uniform(160.0), FRAME_NS, CameraMotion())
        assert np.array_equal(first, again)


class TestVignetting:
    def test_the_rim_is_darker_by_the_configured_fraction(self) -> None:
        rim = 0.6
        image = effects(dataclasses.replace(IDEAL, vignetting_rim=rim)).apply(
            uniform(200.0), 0, CameraMotion())
        half_fov = math.radians(CAMERA.fov_deg / 2.0)

        def grey_at(angle_rad: float) -> float:
            ((u, v),), _ = CAMERA.project([[math.sin(angle_rad), 0.0, math.cos(angle_rad)]])
            return float(image[round(v), round(u)])

        assert grey_at(0.0) == pytest.approx(200.0, abs=1)
        a = math.acos(rim**0.25)  # cos^4 a = rim
        for fraction in (0.5, 0.98):
            expected = 200.0 / (1.0 + fraction**2 * math.tan(a) ** 2) ** 2
            assert grey_at(fraction * half_fov) == pytest.approx(expected, abs=1.5)
        assert grey_at(0.98 * half_fov) < 0.65 * 200.0


class TestNoise:
    @pytest.mark.parametrize(("level", "gain"), [(50.0, 1.0), (150.0, 1.0), (60.0, 3.0)])
    def test_variance_follows_shot_and_read_noise(self, level: float, gain: float) -> None:
        k, read = 20.0, 1.5
        config = dataclasses.replace(IDEAL, shot_noise_electrons_per_grey=k, read_noise_grey=read,
                                     gain=gain, max_gain=4.0)
        image = effects(config).apply(uniform(level / gain), 0, CameraMotion())
        patch = image[150:450, 250:550].astype(float)
        expected = gain * level / k + (gain * read) ** 2 + 1.0 / 12.0  # + rounding
        assert patch.mean() == pytest.approx(level, abs=0.3)
        assert patch.var() == pytest.approx(expected, rel=0.1)

    def test_read_noise_alone_is_the_same_at_every_level(self) -> None:
        config = dataclasses.replace(IDEAL, read_noise_grey=2.0)
        for level in (40.0, 180.0):
            patch = effects(config).apply(uniform(level), 0, CameraMotion())[200:400, 300:500]
            assert patch.astype(float).var() == pytest.approx(4.0 + 1.0 / 12.0, rel=0.1)

    def test_deterministic_for_a_seed_and_fresh_each_frame(self) -> None:
        config = SensorConfig()
        a = effects(config, seed=3)
        b = effects(config, seed=3)
        c = effects(config, seed=4)
        frames = [fx.apply(uniform(100.0), 0, CameraMotion()) for fx in (a, b, c)]
        assert np.array_equal(frames[0], frames[1])
        assert not np.array_equal(frames[0], frames[2])
        assert not np.array_equal(frames[0], a.apply(uniform(100.0), 0, CameraMotion()))


class TestClipping:
    def test_light_beyond_full_scale_saturates_and_outside_the_circle_is_black(self) -> None:
        scene = uniform(100.0)
        scene[250:350, 350:450] = 900.0  # a lamp: more light than the sensor holds
        image = effects(dataclasses.replace(IDEAL, read_noise_grey=2.0)).apply(
            scene, 0, CameraMotion())
        assert (image[260:340, 360:440] == 255).all()
        assert image[0, 0] == image[-1, -1] == 0
        assert image[100, 400] > 90

    def test_a_scene_of_the_wrong_size_is_refused(self) -> None:
        with pytest.raises(ValueError, match=r"scene: expected shape \(600, 800\)"):
            effects(IDEAL).apply(np.zeros((10, 10), np.uint8), 0, CameraMotion())


class TestInTheRenderer:
    def test_every_frame_is_recorded_with_the_bodys_motion(self) -> None:
        sim = Simulation(box_room(), SimConfig(seed=2))
        sim.place_robot(Pose2(2.0, 3.0, 0.0))
        renderer = FisheyeRenderer.for_simulation(sim, CAMERA)
        renderer.render(sim)
        still = renderer.effects.last
        sim.body.command(0.0, 1.0)
        sim.step_until(1_500_000_000)  # turning at 1 rad/s
        renderer.render(sim)
        turning = renderer.effects.last
        assert still is not None and turning is not None
        assert still.blur_px == 0.0
        # At least the centre's blur: omega x exposure x the lens's scale there.
        assert turning.blur_px >= 0.95 * turning.exposure_s * PX_PER_RAD
        assert turning.mean_grey == pytest.approx(SensorConfig().target_grey, abs=10.0)


class TestAnotherLens:
    def test_a_smaller_lens_with_distortion_gets_its_own_circle_blur_and_falloff(self) -> None:
        K = np.array([[260.0, 0.0, 321.0], [0.0, 262.0, 238.0], [0.0, 0.0, 1.0]])
        lens = CameraModel(640, 480, K, xi=1.2, D=np.array([-0.05, 0.01, 0.0, 0.0]),
                           fov_deg=170.0)
        fx = CameraEffects(lens, MOUNT, dataclasses.replace(IDEAL, motion_blur=True,
                                                            vignetting_rim=0.5),
                           np.random.default_rng(0))
        scene = np.full((480, 640), 200, dtype=np.uint8)
        image = fx.apply(scene, 0, yaw(1.0))
        assert image.shape == (480, 640)
        _, valid = lens.lift([[321.0, 238.0], [0.0, 0.0]])
        assert image[238, 321] == pytest.approx(200, abs=1) and valid[0]
        assert (image[0, 0] == 0) == (not valid[1])
        assert fx.last is not None and fx.last.blur_px > 0.5 * 0.008 * K[0, 0] / (1.0 + 1.2)
        ((u, v),), _ = lens.project([[math.sin(math.radians(84.0)), 0.0,
                                      math.cos(math.radians(84.0))]])
        assert image[round(v), round(u)] < 0.6 * 200
