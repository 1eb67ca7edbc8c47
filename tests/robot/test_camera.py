"""VideoCaptureSource against the simulator's real MJPEG server on loopback, and files.

Streams come from :class:`sim.camera_server.CameraServer` over real HTTP on ephemeral
ports, publishing numbered frames (``tests.sim.camera_stream``).
"""

from __future__ import annotations

import dataclasses
import itertools
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import pytest

from robot.camera import Frame, FrameStall, VideoCaptureSource
from robot.config import CameraSourceConfig
from shared.camera_model import CameraModel
from shared.clock import ManualClock, WallClock
from shared.errors import InputError, TransportError
from sim.camera_server import CameraServer
from tests.sim.camera_stream import SHAPE, eventually, frame_number, numbered_frame, publishing

FAST = CameraSourceConfig(open_timeout_ns=1_000_000_000, read_timeout_ns=1_000_000_000,
                          reconnect_initial_ns=50_000_000, reconnect_max_ns=200_000_000)
"""Short timeouts and backoff: a failing test fails in about a second."""
CLOCK = WallClock()


def config_for(source: str, **changes: int) -> CameraSourceConfig:
    return dataclasses.replace(FAST, source=source, **changes)


@pytest.fixture(autouse=True)
def no_thread_left() -> Iterator[None]:
    before = set(threading.enumerate())
    yield
    assert set(threading.enumerate()) - before == set()


@pytest.fixture
def server() -> Iterator[CameraServer]:
    with CameraServer() as camera_server:
        yield camera_server


def frame_of(result: Frame | FrameStall | None) -> Frame:
    assert isinstance(result, tuple), f"expected a frame, got {result!r}"
    return result


class TestStream:
    def test_grey_frames_newer_each_time_stamped_on_arrival(self, server: CameraServer) -> None:
        clock = ManualClock(7_000_000_000)
        with publishing(server), \
                VideoCaptureSource(config_for(server.stream_url), clock) as source:
            assert source.size_wh == (SHAPE[1], SHAPE[0])
            frames = [frame_of(source.read()) for _ in range(5)]
            clock.advance(1.0)
            source.read()  # may have arrived before the advance
            after = frame_of(source.read())
        for t_ns, image in frames:
            assert t_ns == 7_000_000_000
            assert image.shape == SHAPE and image.dtype == np.uint8
        numbers = [frame_number(image) for _, image in frames]
        assert all((b - a) % 20 > 0 for a, b in itertools.pairwise(numbers))  # newer each time
        assert after[0] == 8_000_000_000

    def test_a_slow_reader_gets_the_newest_frame(self, server: CameraServer) -> None:
        server.publish(0, numbered_frame(0))
        config = config_for(server.stream_url, read_timeout_ns=300_000_000)  # a quick close
        with VideoCaptureSource(config, CLOCK) as source:
            for k in (1, 2):
                server.publish(k, numbered_frame(k))
                assert eventually(lambda k=k: source.stats().frames == k + 1)
            assert frame_number(frame_of(source.read())[1]) == 2
            assert source.stats().skipped == 2  # frames 0 and 1, never read

    def test_a_stall_is_reported_then_frames_return(self, server: CameraServer) -> None:
        config = config_for(server.stream_url, read_timeout_ns=3_000_000_000)  # no reopen
        with publishing(server), VideoCaptureSource(config, CLOCK) as source:
            frame_of(source.read_within(1_000_000_000))
            server.stall(1_000_000_000)
            stalls: list[FrameStall] = []
            started = time.monotonic()
            while time.monotonic() - started < 4.0:
                result = source.read_within(200_000_000)
                if isinstance(result, FrameStall):
                    stalls.append(result)
                elif stalls:  # the first frame after the stall
                    break
            resumed = frame_of(result)
            later = frame_of(source.read_within(500_000_000))
            assert source.stats().reopens == 0
        assert len(stalls) >= 3  # ~1 s without frames, reported every 0.2 s
        lasted = [s.t_ns - s.last_frame_ns for s in stalls]
        assert lasted == sorted(lasted) and lasted[-1] >= 600_000_000
        assert resumed[0] > stalls[-1].t_ns and later[0] > resumed[0]

    def test_undecodable_frames_are_skipped(self, server: CameraServer) -> None:
        with publishing(server), VideoCaptureSource(config_for(server.stream_url), CLOCK) as source:
            frame_of(source.read())
            server.corrupt(3)
            for _ in range(10):
                frame_of(source.read_within(500_000_000))
            assert eventually(lambda: source.stats().failed_reads == 3)
            assert source.stats().reopens == 0 and server.stats().corrupted == 3

    def test_reopens_after_the_server_restarts(self) -> None:
        first = CameraServer()
        port = first.port
        with publishing(first):
            source = VideoCaptureSource(config_for(first.stream_url), CLOCK)
            frame_of(source.read())
        first.close()
        with source:
            # Frames received before the close may still come (under load, late); then none.
            for _ in range(20):
                if isinstance(source.read_within(300_000_000), FrameStall):
                    break
            else:
                pytest.fail("frames kept coming after the server closed")
            with CameraServer(port=port) as second, publishing(second):
                resumed = [frame_of(source.read_within(2_000_000_000)) for _ in range(3)]
                stats = source.stats()
        assert stats.reopens == 1 and stats.failed_reads >= FAST.max_failed_reads
        assert resumed[0][0] < resumed[1][0] < resumed[2][0]

    def test_a_reopened_stream_of_another_size_is_dropped(self) -> None:
        first = CameraServer()
        port = first.port
        with publishing(first):
            source = VideoCaptureSource(config_for(first.stream_url), CLOCK)
        first.close()
        with source, CameraServer(port=port) as second, publishing(second, shape=(60, 80)):
            assert eventually(lambda: source.stats().wrong_size >= 3)
            source.read()  # the frame that came before the restart
            assert isinstance(source.read_within(100_000_000), FrameStall)
            assert source.size_wh == (SHAPE[1], SHAPE[0])

    def test_close_ends_reading_also_a_read_waiting_elsewhere(self, server: CameraServer) -> None:
        server.publish(0, numbered_frame(0))
        config = config_for(server.stream_url, read_timeout_ns=300_000_000)
        source = VideoCaptureSource(config, CLOCK)
        frame_of(source.read())
        results: list[Frame | None] = []
        waiting = threading.Thread(target=lambda: results.append(source.read()))
        waiting.start()  # no frame comes: it waits until the close
        started = time.monotonic()
        source.close()  # joins the capture thread, in a silent read for up to 0.3 s
        assert time.monotonic() - started < 1.5
        waiting.join(timeout=5.0)
        assert results == [None]
        assert source.read() is None and source.read_within(1_000_000) is None


class TestFile:
    def test_every_frame_in_order_then_the_end(self, tmp_path: Path) -> None:
        path = tmp_path / "drive.avi"
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15.0, (80, 60),
                                 False)
        assert writer.isOpened()
        for k in range(6):
            writer.write(numbered_frame(k, (60, 80)))
        writer.release()
        with VideoCaptureSource(config_for(str(path)), CLOCK) as source:
            numbers = []
            while (frame := source.read()) is not None:
                numbers.append(frame_number(frame[1]))
            assert numbers == list(range(6))
            assert source.read_within(1_000_000) is None
            assert source.stats().skipped == 0


class TestOpenErrors:
    """Each fails at once with one line naming the source."""

    def test_a_missing_file(self, tmp_path: Path) -> None:
        missing = tmp_path / "none.avi"
        with pytest.raises(InputError, match=f"{missing}: no such video file"):
            VideoCaptureSource(config_for(str(missing)), CLOCK)

    def test_a_file_that_is_not_a_video(self, tmp_path: Path) -> None:
        text = tmp_path / "notes.txt"
        text.write_text("not a video\n")
        with pytest.raises(TransportError, match="not a video file OpenCV can decode"):
            VideoCaptureSource(config_for(str(text)), CLOCK)

    def test_a_device_that_is_not_there(self) -> None:
        with pytest.raises(TransportError, match=r"^99: cannot open with OpenCV \(no camera"):
            VideoCaptureSource(config_for("99"), CLOCK)

    @pytest.mark.parametrize("path", ["/nothing.mjpg", None])
    def test_a_wrong_url(self, server: CameraServer, path: str | None) -> None:
        url = (f"http://127.0.0.1:{server.port}{path}" if path is not None
               else "http://127.0.0.1:1/stream.mjpg")  # port 1: refused
        started = time.monotonic()
        with pytest.raises(TransportError, match=f"^{url}: cannot open with OpenCV"):
            VideoCaptureSource(config_for(url), CLOCK)
        assert time.monotonic() - started < 1.0

    def test_a_stream_without_frames(self, server: CameraServer) -> None:
        config = config_for(server.stream_url, open_timeout_ns=300_000_000)
        started = time.monotonic()
        with pytest.raises(TransportError, match=r"nothing within 0\.3 s"):
            VideoCaptureSource(config, CLOCK)
        assert time.monotonic() - started < 2.0

    def test_frames_of_another_size_than_the_calibration(self, server: CameraServer) -> None:
        with publishing(server), pytest.raises(
                InputError, match="frames are 160x120 px, the camera calibration's are 800x600"):
            VideoCaptureSource(config_for(server.stream_url), CLOCK, CameraModel.default())
