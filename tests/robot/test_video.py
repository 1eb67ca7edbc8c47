"""The robot's live view: frames handed over at the configured rate from the loop, the
matched points of a servo cycle, the stream as the camera protocol describes it, and
``vmnav robot``'s process with it (its camera component heard by a ground station)."""

from __future__ import annotations

import threading
from pathlib import Path
from types import SimpleNamespace
from typing import Any
from urllib.request import urlopen

import cv2
import numpy as np
import pytest

from robot.config import VideoConfig, VmnavConfig
from robot.process import AfterStep, RobotParts, RobotProcess
from robot.vehicle.options import VehicleFiles
from robot.video import LiveView, matched_points, video_stream
from shared.camera_model import CameraModel
from shared.clock import ManualClock, WallClock
from shared.config import from_mapping
from shared.errors import ConfigError
from shared.memory import VisualMemory
from shared.mjpeg_server import MjpegServer
from tests.robot.test_process import MS, RecordingBase, ScriptedCamera

CAMERA = CameraModel.default()


class CountingServer:
    """Stands in for an MjpegServer: counts what is published."""

    def __init__(self) -> None:
        self.published: list[tuple[int, Any, Any]] = []
        self.keys: list[tuple[Any, int | None]] = []

    def publish(self, t_ns: int, image: Any, points_xy: Any = None, inliers: Any = None, *,
                key_xy: Any = None, key_id: int | None = None) -> None:
        self.published.append((t_ns, points_xy, inliers))
        self.keys.append((key_xy, key_id))


def follow_record(matched_xy: np.ndarray, inlier_mask: np.ndarray,
                  key_xy: np.ndarray | None = None) -> Any:
    vision = SimpleNamespace(matched_xy=matched_xy, key_xy=matched_xy + 100 if key_xy is None
                             else key_xy, state=SimpleNamespace(inlier_mask=inlier_mask))
    return SimpleNamespace(follow=SimpleNamespace(vision=vision))


class TestLiveView:
    def test_one_frame_per_period_of_frame_time(self) -> None:
        server = CountingServer()
        view = LiveView(server, VideoConfig(frame_period_ns=200 * MS))  # type: ignore[arg-type]
        image = np.zeros((4, 4), np.uint8)
        for k in range(31):  # 15 frames/s for 2 s
            view.offer(round(k * 1e9 / 15), image, None)
        assert [t // MS for t, _, _ in server.published] == [0, 200, 400, 600, 800, 1000,
                                                              1200, 1400, 1600, 1800, 2000]

    def test_after_a_gap_the_next_frame_goes_out(self) -> None:
        server = CountingServer()
        view = LiveView(server, VideoConfig(frame_period_ns=200 * MS))  # type: ignore[arg-type]
        image = np.zeros((4, 4), np.uint8)
        for t_ms in (0, 100, 1500, 1600, 1700):
            view.offer(t_ms * MS, image, None)
        assert [t // MS for t, _, _ in server.published] == [0, 1500, 1700]

    def test_the_matches_of_a_servo_cycle(self) -> None:
        xy, mask, key_xy = np.array([[1.0, 2.0], [3.0, 4.0]]), np.array([True, False]), \
            np.array([[5.0, 6.0], [7.0, 8.0]])
        points, inliers, key_points = matched_points(follow_record(xy, mask, key_xy))
        assert points is xy and inliers is mask and key_points is key_xy
        assert matched_points(follow_record(xy, np.zeros(0, bool)))[1] is None
        assert matched_points(follow_record(xy, mask, np.zeros((1, 2))))[2] is None
        nothing = (None, None, None)
        assert matched_points(follow_record(np.zeros((0, 2)), np.zeros(0, bool))) == nothing
        assert matched_points(None) == nothing
        assert matched_points(SimpleNamespace(follow=None)) == nothing  # type: ignore[arg-type]

    def test_the_key_image_goes_with_its_matches_only(self) -> None:
        server = CountingServer()
        view = LiveView(server, VideoConfig(frame_period_ns=200 * MS))  # type: ignore[arg-type]
        image = np.zeros((4, 4), np.uint8)
        xy, mask = np.array([[1.0, 2.0]]), np.array([True])
        view.offer(0, image, follow_record(xy, mask), next_key=7)
        view.offer(200 * MS, image, None, next_key=7)
        assert server.keys[0][1] == 7 and np.array_equal(server.keys[0][0], xy + 100)
        assert server.keys[1] == (None, None)


class TestVideoStream:
    def test_the_served_size_rate_and_lens(self) -> None:
        with MjpegServer(width_px=400) as server:
            stream = video_stream(server, VideoConfig(), CAMERA)
            assert stream.uri == server.stream_url
        assert (stream.width_px, stream.height_px) == (400, 300)
        assert stream.rate_hz == 5.0 and stream.hfov_deg == 185

    def test_bad_config_values_are_refused(self) -> None:
        with pytest.raises(ValueError, match="width_px"):
            VideoConfig(width_px=0)
        with pytest.raises(ValueError, match="frame_period_ns"):
            VideoConfig(frame_period_ns=1)
        with pytest.raises(ConfigError, match=r"video.*jpeg_quality"):
            from_mapping(VmnavConfig, {"video": {"jpeg_quality": 0}}, "robot.toml")


def test_the_robot_process_serves_its_frames_and_a_station_finds_the_stream(tmp_path: Path) \
        -> None:
    from ground.camera_stream import find_video_stream
    from ground.station import GroundStation

    clock = ManualClock()
    frames = ScriptedCamera(clock, [100 * MS])
    files = VehicleFiles(tmp_path / "memory", tmp_path / "upload", tmp_path / "params.parm")
    found: list[Any] = []
    with MjpegServer(width_px=400) as server:
        parts = RobotParts(VisualMemory(CAMERA), RecordingBase([]), frames, clock, VmnavConfig(),
                           files, np.random.default_rng(1), lockstep=True,
                           video=LiveView(server, VmnavConfig().video))
        with RobotProcess(parts, "udpin:127.0.0.1:0", link_clock=WallClock()) as robot:
            port = robot.vehicle.link.local_port

            def station() -> None:
                with GroundStation.open(f"udpout:127.0.0.1:{port}", WallClock()) as ground:
                    ground.wait_vehicle(20.0)
                    found.append(find_video_stream(ground))

            ground_thread = threading.Thread(target=station, daemon=True)
            ground_thread.start()
            wall = WallClock()
            give_up_ns = wall.now_ns() + 30_000 * MS

            def on_step(record: Any) -> AfterStep:  # the frame is served while time stands
                done = bool(found) or wall.now_ns() > give_up_ns
                return AfterStep.STOP if done else AfterStep.HOLD_CLOCK

            robot.run(on_step=on_step)
            ground_thread.join(30)
        with urlopen(server.snapshot_url, timeout=5.0) as reply:
            image = cv2.imdecode(np.frombuffer(reply.read(), np.uint8), cv2.IMREAD_GRAYSCALE)
    assert image.shape == (300, 400)
    assert found and found[0].uri == server.stream_url
    assert (found[0].width_px, found[0].height_px, found[0].rate_hz) == (400, 300, 5.0)
