"""The vehicle endpoint's camera component over real UDP (rule 10): its HEARTBEAT, its
answers to the camera protocol's requests, and no camera at all without a stream."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from shared.clock import ManualClock
from shared.mavlink.camera import VideoStream, stream_from_message
from shared.mavlink.dialect import mavlink
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import Ground, Net, make_vehicle

STREAM = VideoStream("http://127.0.0.1:8090/stream.mjpg", 400, 300, 5.0, hfov_deg=185)
CAMERA = (1, 100)


@pytest.fixture
def camera_net(tmp_path: Path, app: FakeApp, manual_clock: ManualClock) -> Iterator[Net]:
    """The vehicle with a camera component, and one ground station."""
    vehicle = make_vehicle(tmp_path, app, manual_clock, video=STREAM)
    network = Net(manual_clock, vehicle, Ground(f"udpout:127.0.0.1:{vehicle.link.local_port}"))
    yield network
    network.close()


def from_camera(net: Net, name: str, start: int = 0) -> list[Any]:
    return [m for _, m in net.ground.received[start:]
            if m.get_type() == name and (m.get_srcSystem(), m.get_srcComponent()) == CAMERA]


def ask_camera(net: Net, command: int, *params: float, target: int = 100) -> tuple[Any, list[Any]]:
    """COMMAND_LONG to the camera (or ``target``); its ACK and what came after it."""
    start = len(net.ground.received)
    p = list(params) + [math.nan] * (7 - len(params))
    net.ground.send(mavlink.MAVLink_command_long_message(1, target, command, 0, *p))

    def acks() -> list[Any]:
        return [m for _, m in net.ground.received[start:]
                if m.get_type() == "COMMAND_ACK" and m.command == command]

    net.run(lambda: bool(acks()))
    net.advance(0.1)
    after = [m for _, m in net.ground.received[start:] if m.get_type() != "HEARTBEAT"]
    return acks()[0], after


class TestCameraComponent:
    def test_it_beats_as_a_camera_beside_the_autopilot(self, camera_net: Net) -> None:
        camera_net.advance(5.0)
        beats = from_camera(camera_net, "HEARTBEAT")
        assert 4 <= len(beats) <= 6
        assert all(b.type == mavlink.MAV_TYPE_CAMERA
                   and b.autopilot == mavlink.MAV_AUTOPILOT_INVALID for b in beats)
        seqs = [b.get_seq() for b in beats]
        assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))  # its own sequence
        assert camera_net.ground.of_type("HEARTBEAT")[-1].type == mavlink.MAV_TYPE_GROUND_ROVER

    def test_it_advertises_the_stream_ack_first(self, camera_net: Net) -> None:
        ack, after = ask_camera(camera_net, mavlink.MAV_CMD_REQUEST_MESSAGE,
                                mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, 1)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED
        assert (ack.get_srcSystem(), ack.get_srcComponent()) == CAMERA
        camera = [m for m in after if (m.get_srcSystem(), m.get_srcComponent()) == CAMERA]
        assert [m.get_type() for m in camera] == ["COMMAND_ACK", "VIDEO_STREAM_INFORMATION"]
        assert stream_from_message(camera[1]) == STREAM

    def test_camera_information_and_the_deprecated_requests(self, camera_net: Net) -> None:
        ack, after = ask_camera(camera_net, mavlink.MAV_CMD_REQUEST_MESSAGE,
                                mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED
        info = next(m for m in after if m.get_type() == "CAMERA_INFORMATION")
        assert info.flags & mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM
        ack, after = ask_camera(camera_net, mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION, 0)
        assert ack.result == mavlink.MAV_RESULT_ACCEPTED
        assert "VIDEO_STREAM_INFORMATION" in [m.get_type() for m in after]

    def test_what_it_lacks_is_answered_at_once(self, camera_net: Net) -> None:
        ack, _ = ask_camera(camera_net, mavlink.MAV_CMD_REQUEST_MESSAGE,
                            mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, 2)
        assert ack.result == mavlink.MAV_RESULT_DENIED  # no second stream
        ack, _ = ask_camera(camera_net, mavlink.MAV_CMD_IMAGE_START_CAPTURE, 0, 0, 1)
        assert ack.result == mavlink.MAV_RESULT_UNSUPPORTED
        assert camera_net.vehicle.endpoint.stats().refused == 2

    def test_the_autopilot_does_not_answer_for_the_camera(self, camera_net: Net) -> None:
        ack, after = ask_camera(camera_net, mavlink.MAV_CMD_REQUEST_MESSAGE,
                                mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, target=1)
        assert ack.result == mavlink.MAV_RESULT_DENIED
        assert (ack.get_srcSystem(), ack.get_srcComponent()) == (1, 1)
        assert "VIDEO_STREAM_INFORMATION" not in [m.get_type() for m in after]


def test_no_stream_no_camera(net: Net) -> None:
    net.advance(3.0)
    assert from_camera(net, "HEARTBEAT") == []
    ack, after = ask_camera(net, mavlink.MAV_CMD_REQUEST_MESSAGE,
                            mavlink.MAVLINK_MSG_ID_VIDEO_STREAM_INFORMATION, target=0)
    assert ack.result == mavlink.MAV_RESULT_DENIED  # the autopilot, for every component
    assert [m for m in after if m.get_srcComponent() == 100] == []
