"""The simulator's network camera: MJPEG over HTTP read by cv2.VideoCapture, as a robot would.

Most tests run in lock-step: publish a frame, then read it, so each client's frames are
known exactly. Every server listens on an ephemeral loopback port.
"""

from __future__ import annotations

import socket
import struct
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import BinaryIO
from urllib.error import HTTPError
from urllib.request import Request, urlopen

import cv2
import numpy as np
import numpy.typing as npt
import pytest

from shared.camera_model import CameraModel
from shared.errors import ShapeError, TransportError
from shared.guarded_http import HttpLimits
from sim.camera_server import DEFAULT_JPEG_QUALITY, CameraFeed, CameraServer
from sim.config import SensorConfig, SimConfig
from sim.sim_camera import SimFrameSource
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from tests.sim.camera_stream import eventually, frame_number, numbered_frame
from tests.sim.rooms import box_room

CAPTURE_PARAMS = [cv2.CAP_PROP_OPEN_TIMEOUT_MSEC, 3000, cv2.CAP_PROP_READ_TIMEOUT_MSEC, 3000]
"""A broken test fails in 3 s instead of hanging."""


@pytest.fixture(autouse=True)
def no_thread_left() -> Iterator[None]:
    before = set(threading.enumerate())
    yield
    assert set(threading.enumerate()) - before == set()


@contextmanager
def capture(url: str) -> Iterator[cv2.VideoCapture]:
    cap = cv2.VideoCapture(url, cv2.CAP_FFMPEG, CAPTURE_PARAMS)
    try:
        assert cap.isOpened()
        yield cap
    finally:
        cap.release()


def read_grey(cap: cv2.VideoCapture) -> npt.NDArray[np.uint8]:
    ok, image = cap.read()
    assert ok
    return cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)


@contextmanager
def raw_stream(server: CameraServer) -> Iterator[tuple[socket.socket, BinaryIO]]:
    """A bare HTTP client of the stream, past the response headers."""
    sock = socket.create_connection((server.host, server.port), timeout=5.0)
    reader = sock.makefile("rb")
    try:
        host = f"{server.host}:{server.port}".encode()
        sock.sendall(b"GET /stream.mjpg HTTP/1.1\r\nHost: " + host + b"\r\n\r\n")
        assert reader.readline().startswith(b"HTTP/1.0 200")
        while reader.readline() not in (b"\r\n", b""):
            pass
        yield sock, reader
    finally:
        reader.close()  # the socket stays open while its file is
        sock.close()


def read_part(reader: BinaryIO) -> bytes:
    """One part of the multipart stream: its JPEG bytes."""
    assert reader.readline() == b"--vmnavframe\r\n"
    length = None
    while (line := reader.readline()) != b"\r\n":
        name, _, value = line.decode("ascii").partition(":")
        if name.lower() == "content-length":
            length = int(value)
    assert length is not None
    body = reader.read(length)
    assert reader.readline() == b"\r\n"
    return body


def decode(jpeg: bytes) -> npt.NDArray[np.uint8] | None:
    return cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_GRAYSCALE)


def blockiness(image: npt.NDArray[np.uint8]) -> float:
    """Mean step between horizontal neighbours across JPEG's 8 px block boundaries over
    that within blocks (1: no blocks), in the middle of the image."""
    steps = np.abs(np.diff(image[96:504, 200:600].astype(float), axis=1))
    boundary = np.arange(steps.shape[1]) % 8 == 7  # between columns 8k - 1 and 8k
    return float(steps[:, boundary].mean() / steps[:, ~boundary].mean())


class TestFeed:
    def test_the_stream_carries_the_rendered_frames(self) -> None:
        sim = Simulation(box_room(), SimConfig(seed=3))
        with CameraServer() as server:
            feed = CameraFeed(sim, CameraModel.default(), server)
            sim.add_step_hook(feed)
            sim.step()  # the first frame, at t = 0
            with capture(server.stream_url) as cap:
                for _ in range(2):
                    assert feed.last is not None
                    rendered = feed.last.image
                    got = read_grey(cap)
                    assert got.shape == rendered.shape == (600, 800)
                    assert np.abs(got.astype(int) - rendered).mean() < 2.0  # JPEG at 80
                    _, jpeg = cv2.imencode(".jpg", rendered,
                                           [cv2.IMWRITE_JPEG_QUALITY, DEFAULT_JPEG_QUALITY])
                    same_jpeg = cv2.imdecode(jpeg, cv2.IMREAD_GRAYSCALE)
                    assert np.abs(got.astype(int) - same_jpeg).max() <= 2  # this frame's JPEG
                    frames = feed.frames
                    while feed.frames == frames:  # on to the next frame
                        sim.step()

    def test_jpeg_artefacts_only_where_frames_are_mjpeg(self) -> None:
        camera = CameraModel.default()
        config = SimConfig(seed=3, sensor=SensorConfig(jpeg_quality=60))
        sim = Simulation(box_room(), config)
        twin = Simulation(box_room(), config)
        lockstep = SimFrameSource(twin, camera, SimClock(twin))
        _, raw = lockstep.read()
        with CameraServer(jpeg_quality=config.sensor.jpeg_quality) as server:
            feed = CameraFeed(sim, camera, server)
            sim.add_step_hook(feed)
            sim.step()
            with urlopen(server.snapshot_url, timeout=5) as reply:
                served = cv2.imdecode(np.frombuffer(reply.read(), np.uint8), cv2.IMREAD_GRAYSCALE)
        assert feed.last is not None
        assert np.array_equal(raw, feed.last.image)  # the same frame, before the network
        assert blockiness(served) > 1.3 * blockiness(raw)
        assert blockiness(raw) < 1.1

    def test_one_frame_per_frame_period_on_the_step_grid(self) -> None:
        sim = Simulation(box_room(), SimConfig(seed=3))  # 10 ms steps, 15 frames/s
        with CameraServer() as server:
            feed = CameraFeed(sim, CameraModel.default(), server)
            sim.add_step_hook(feed)
            sim.step_until(1_000_000_000)
            assert feed.frames == server.stats().published == 15
            assert feed.last is not None and feed.last.t_ns == 940_000_000  # 14 periods: 933 ms


class TestClients:
    def test_snapshot_before_and_after_the_first_frame_and_unknown_paths(self) -> None:
        with CameraServer() as server:
            with pytest.raises(HTTPError) as before:
                urlopen(server.snapshot_url, timeout=5.0)
            assert before.value.code == 503
            server.publish(0, numbered_frame(7))
            with urlopen(server.snapshot_url, timeout=5.0) as reply:
                assert reply.headers["Content-Type"] == "image/jpeg"
                image = decode(reply.read())
            assert image is not None and frame_number(image) == 7
            with pytest.raises(HTTPError) as unknown:
                urlopen(f"http://{server.host}:{server.port}/", timeout=5.0)
            assert unknown.value.code == 404

    def test_two_clients_get_every_frame(self) -> None:
        with CameraServer() as server:
            server.publish(0, numbered_frame(0))
            with capture(server.stream_url) as a, capture(server.stream_url) as b:
                assert frame_number(read_grey(a)) == frame_number(read_grey(b)) == 0
                for k in range(1, 5):
                    server.publish(k * 50_000_000, numbered_frame(k))
                    assert frame_number(read_grey(a)) == k
                    assert frame_number(read_grey(b)) == k
                assert server.stats().streaming == 2
        assert server.stats().streaming == 0 and server.stats().clients == 2

    def test_a_client_leaving_disturbs_nobody(self) -> None:
        with CameraServer() as server:
            server.publish(0, numbered_frame(0))
            with capture(server.stream_url) as cap:
                assert frame_number(read_grey(cap)) == 0
                with raw_stream(server) as (sock, reader):
                    assert frame_number(decode(read_part(reader))) == 0  # type: ignore[arg-type]
                    # leave abruptly: a reset, not a polite close
                    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
                for k in range(1, 6):
                    server.publish(k * 50_000_000, numbered_frame(k))
                    assert frame_number(read_grey(cap)) == k
                assert eventually(lambda: server.stats().streaming == 1)
                assert server.stats().clients == 2

    def test_a_client_that_stops_reading_blocks_neither_frames_nor_close(self) -> None:
        noise = np.random.default_rng(5).integers(0, 256, (600, 800), dtype=np.uint8)
        server = CameraServer()
        try:
            server.publish(0, noise)
            with raw_stream(server), capture(server.stream_url) as cap:
                read_grey(cap)  # frame 0
                started = time.perf_counter()
                for k in range(1, 40):  # ~350 kB each: the stuck socket fills at once
                    server.publish(k, noise)
                    read_grey(cap)
                server.publish(40, numbered_frame(3, (600, 800)))
                assert frame_number(read_grey(cap)) == 3
                assert time.perf_counter() - started < 5.0
                closing = time.perf_counter()
                server.close()  # the stuck client is still connected
                assert time.perf_counter() - closing < 1.0
        finally:
            server.close()


class TestHostileClients:
    def test_idle_connections_hold_no_thread_and_a_stream_is_still_served(self) -> None:
        with CameraServer() as server:
            server.publish(0, numbered_frame(0))
            before = threading.active_count()
            idle = [socket.create_connection((server.host, server.port)) for _ in range(300)]
            try:
                full = HttpLimits().max_waiting  # the older ones were closed to make room
                assert eventually(lambda: server._http.stats().waiting == full, 20.0)
                assert threading.active_count() == before  # the lobby holds them, no thread
                with capture(server.stream_url) as cap:
                    assert frame_number(read_grey(cap)) == 0
                    assert threading.active_count() == before + 1  # the stream's
            finally:
                for conn in idle:
                    conn.close()

    def test_a_request_from_a_web_page_of_another_origin_is_refused(self) -> None:
        with CameraServer() as server:
            server.publish(0, numbered_frame(0))
            request = Request(server.snapshot_url, headers={"Origin": "http://evil.example"})
            with pytest.raises(HTTPError) as refused:
                urlopen(request, timeout=5.0)
            assert refused.value.code == 403


class TestFaults:
    def test_a_stall_withholds_frames_on_open_connections(self) -> None:
        with CameraServer() as server:
            server.publish(0, numbered_frame(0))
            with capture(server.stream_url) as cap, raw_stream(server) as (_, reader):
                assert frame_number(read_grey(cap)) == 0
                assert frame_number(decode(read_part(reader))) == 0  # type: ignore[arg-type]
                server.stall(100_000_000)
                server.publish(50_000_000, numbered_frame(1))  # withheld
                server.publish(100_000_000, numbered_frame(2))  # 100 ms on: delivered
                assert frame_number(read_grey(cap)) == 2
                assert frame_number(decode(read_part(reader))) == 2  # type: ignore[arg-type]
            stats = server.stats()
        assert (stats.published, stats.withheld) == (3, 1)

    def test_corrupt_frames_do_not_decode_and_the_next_ones_do(self) -> None:
        with CameraServer() as server:
            server.publish(0, numbered_frame(0))
            with raw_stream(server) as (_, reader):
                assert frame_number(decode(read_part(reader))) == 0  # type: ignore[arg-type]
                server.corrupt(2)
                for k in (1, 2):
                    server.publish(k, numbered_frame(k))
                    assert decode(read_part(reader)) is None
                server.publish(3, numbered_frame(3))
                assert frame_number(decode(read_part(reader))) == 3  # type: ignore[arg-type]
            assert server.stats().corrupted == 2


class TestErrors:
    def test_port_in_use(self) -> None:
        with socket.socket() as taken:
            taken.bind(("127.0.0.1", 0))
            taken.listen(1)
            port = taken.getsockname()[1]
            with pytest.raises(TransportError, match=f"http:127.0.0.1:{port}: cannot listen"):
                CameraServer(port=port)

    def test_bad_frames_and_quality_are_refused(self) -> None:
        with pytest.raises(ValueError, match="jpeg_quality"):
            CameraServer(jpeg_quality=0)
        with CameraServer() as server:
            with pytest.raises(ShapeError, match=r"\(H, W\) or \(H, W, 3\) uint8"):
                server.publish(0, np.zeros((4, 4), np.float32))  # type: ignore[arg-type]
            with pytest.raises(ShapeError):
                server.publish(0, np.zeros((4, 4, 2), np.uint8))
            server.publish(0, np.zeros((4, 4, 3), np.uint8))  # BGR is fine
