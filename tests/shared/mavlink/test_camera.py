"""The camera protocol's messages, both ends in memory: what the robot's camera sends is what
a ground station reads back."""

from __future__ import annotations

import math

import pytest

from shared.mavlink.address import Address
from shared.mavlink.camera import (
    CAMERA_COMPONENT_ID,
    STREAM_ID,
    STREAM_TYPE,
    VideoStream,
    camera_handlers,
    camera_heartbeat,
    camera_information_message,
    is_camera_heartbeat,
    reachable_uri,
    stream_from_message,
    video_stream_information_message,
)
from shared.mavlink.commands.vehicle import CommandRequest
from shared.mavlink.dialect import make_codec, mavlink

STREAM = VideoStream("http://127.0.0.1:8090/stream.mjpg", 400, 300, 5.0, hfov_deg=185)


def over_the_wire(msg: object) -> object:
    """``msg`` packed by the robot's camera and parsed by a ground station."""
    robot, ground = make_codec(1, 1), make_codec(255, 190)
    (parsed,) = ground.parse(robot.pack_as(msg, CAMERA_COMPONENT_ID))  # type: ignore[arg-type]
    return parsed


def request(*params: float) -> CommandRequest:
    padded = tuple(params) + (math.nan,) * (7 - len(params))
    return CommandRequest(mavlink.MAV_CMD_REQUEST_MESSAGE, padded, Address(255, 190))  # type: ignore[arg-type]


class TestMessages:
    def test_the_stream_round_trips_through_video_stream_information(self) -> None:
        msg = over_the_wire(video_stream_information_message(STREAM))
        assert (msg.get_srcSystem(), msg.get_srcComponent()) == (1, 100)  # type: ignore[attr-defined]
        assert msg.type == STREAM_TYPE == mavlink.VIDEO_STREAM_TYPE_TCP_MPEG  # type: ignore[attr-defined]
        assert msg.stream_id == STREAM_ID and msg.count == 1  # type: ignore[attr-defined]
        assert msg.flags & mavlink.VIDEO_STREAM_STATUS_FLAGS_RUNNING  # type: ignore[attr-defined]
        assert stream_from_message(msg) == VideoStream(STREAM.uri, 400, 300, 5.0, 185)

    def test_camera_information_says_it_has_a_video_stream(self) -> None:
        msg = over_the_wire(camera_information_message(STREAM, 1234))
        assert msg.flags == mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM  # type: ignore[attr-defined]
        assert (msg.resolution_h, msg.resolution_v) == (400, 300)  # type: ignore[attr-defined]
        assert bytes(msg.vendor_name).rstrip(b"\0") == b"vmnav"  # type: ignore[attr-defined]
        assert msg.time_boot_ms == 1234  # type: ignore[attr-defined]

    def test_the_camera_heartbeat_is_no_vehicle(self) -> None:
        beat = over_the_wire(camera_heartbeat())
        assert beat.type == mavlink.MAV_TYPE_CAMERA  # type: ignore[attr-defined]
        assert beat.autopilot == mavlink.MAV_AUTOPILOT_INVALID  # type: ignore[attr-defined]
        assert is_camera_heartbeat(beat)

    def test_pack_as_keeps_a_sequence_per_component(self) -> None:
        robot, ground = make_codec(1, 1), make_codec(255, 190)
        data = [robot.pack(camera_heartbeat()), robot.pack_as(camera_heartbeat(), 100),
                robot.pack(camera_heartbeat()), robot.pack_as(camera_heartbeat(), 100)]
        seqs = [(m.get_srcComponent(), m.get_seq()) for d in data for m in ground.parse(d)]
        assert seqs == [(1, 0), (100, 0), (1, 1), (100, 1)]


class TestGroundEnd:
    @pytest.mark.parametrize("uri", ["rtsp://10.0.0.2:8554/live", "5600", ""])
    def test_streams_a_station_cannot_open_are_one_line(self, uri: str) -> None:
        msg = video_stream_information_message(VideoStream("http://x/", 400, 300, 5.0))
        msg.uri = uri.encode()  # type: ignore[attr-defined]
        with pytest.raises(ValueError, match="only http:// streams can be shown"):
            stream_from_message(msg)

    def test_a_wildcard_host_becomes_the_vehicle_address(self) -> None:
        assert reachable_uri("http://0.0.0.0:8090/stream.mjpg", "10.0.0.7") == \
            "http://10.0.0.7:8090/stream.mjpg"
        assert reachable_uri("http://[::]:8090/s", "fe80::1") == "http://[fe80::1]:8090/s"
        assert reachable_uri("http://robot.local:8090/s", "10.0.0.7") == \
            "http://robot.local:8090/s"
        assert reachable_uri("http://0.0.0.0:8090/s", None) == "http://0.0.0.0:8090/s"

    def test_bad_streams_are_refused_at_the_robot(self) -> None:
        with pytest.raises(ValueError, match="uri"):
            VideoStream("http://" + "x" * 160, 400, 300, 5.0)
        with pytest.raises(ValueError, match="rate_hz"):
            VideoStream("http://x/", 400, 300, math.nan)
        with pytest.raises(ValueError, match="size"):
            VideoStream("http://x/", 0, 300, 5.0)


class TestHandlers:
    def test_requests_for_the_stream_and_the_camera(self) -> None:
        handlers = camera_handlers(STREAM, lambda: 7)
        ask = handlers[mavlink.MAV_CMD_REQUEST_MESSAGE]
        for params, name in [((259,), "CAMERA_INFORMATION"),
                             ((269,), "VIDEO_STREAM_INFORMATION"),
                             ((269, 0), "VIDEO_STREAM_INFORMATION"),
                             ((269, 1), "VIDEO_STREAM_INFORMATION"),
                             ((270, 1), "VIDEO_STREAM_STATUS")]:
            reply = ask(request(*params))
            assert reply.result == mavlink.MAV_RESULT_ACCEPTED
            assert [m.get_type() for m in reply.messages] == [name]

    def test_a_stream_or_message_it_lacks_is_denied(self) -> None:
        ask = camera_handlers(STREAM, lambda: 7)[mavlink.MAV_CMD_REQUEST_MESSAGE]
        assert ask(request(269, 2)).result == mavlink.MAV_RESULT_DENIED
        assert ask(request(260)).result == mavlink.MAV_RESULT_DENIED  # CAMERA_SETTINGS
        assert ask(request(269, 2)).messages == ()

    def test_the_deprecated_requests(self) -> None:
        handlers = camera_handlers(STREAM, lambda: 7)

        def ask(command: int, *params: float) -> list[str]:
            padded = tuple(params) + (math.nan,) * (7 - len(params))
            reply = handlers[command](CommandRequest(command, padded,  # type: ignore[arg-type]
                                                     Address(255, 190)))
            return [m.get_type() for m in reply.messages]

        assert ask(mavlink.MAV_CMD_REQUEST_CAMERA_INFORMATION, 1) == ["CAMERA_INFORMATION"]
        assert ask(mavlink.MAV_CMD_REQUEST_CAMERA_INFORMATION, 0) == []
        assert ask(mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION, 0) == \
            ["VIDEO_STREAM_INFORMATION"]
        assert ask(mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_STATUS, 1) == ["VIDEO_STREAM_STATUS"]
        assert ask(mavlink.MAV_CMD_REQUEST_VIDEO_STREAM_INFORMATION, 3) == []
