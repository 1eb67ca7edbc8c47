"""Finding a vehicle's video stream through the camera protocol, against a real vehicle
endpoint over loopback UDP: the stream found, a vehicle without one, a wildcard host."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from ground.camera_stream import find_video_stream
from ground.station import GroundError, GroundStation
from shared.clock import WallClock
from shared.mavlink.camera import VideoStream
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import make_vehicle

STREAM = VideoStream("http://127.0.0.1:8090/stream.mjpg", 400, 300, 5.0, hfov_deg=185)


def found(tmp_path: Path, stream: VideoStream | None) -> VideoStream:
    with make_vehicle(tmp_path, FakeApp(), WallClock(), video=stream) as vehicle:
        vehicle.start_thread()
        with GroundStation.open(f"udpout:127.0.0.1:{vehicle.link.local_port}",
                                WallClock()) as station:
            station.wait_vehicle(3.0)
            return find_video_stream(station)


def test_the_stream_the_camera_advertises(tmp_path: Path) -> None:
    assert found(tmp_path, STREAM) == STREAM


def test_a_wildcard_host_becomes_the_vehicle_address(tmp_path: Path) -> None:
    wildcard = VideoStream("http://0.0.0.0:8090/stream.mjpg", 400, 300, 5.0)
    assert found(tmp_path, wildcard).uri == "http://127.0.0.1:8090/stream.mjpg"


def test_a_vehicle_without_a_camera_is_one_line_soon(tmp_path: Path) -> None:
    started = time.monotonic()
    with pytest.raises(GroundError, match=r"^vehicle 1 has no camera stream \(no camera "
                                          r"HEARTBEAT for 5 s; vmnav robot serves one with "
                                          r"--video\)$"):
        found(tmp_path, None)
    assert time.monotonic() - started < 10.0
