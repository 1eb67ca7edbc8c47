"""The MJPEG server's own features on real sockets: frames scaled down, the matched points
drawn on request, a publisher that never waits for an encoding, a flood of clients.

The streaming itself (every frame to every client, slow and vanishing clients, hostile
ones, faults) is tested through the simulator's camera (tests/sim/test_camera_server.py).
"""

from __future__ import annotations

import json
import socket
import threading
from collections.abc import Iterator
from urllib.error import HTTPError
from urllib.request import urlopen

import cv2
import numpy as np
import numpy.typing as npt
import pytest

from shared.errors import ShapeError
from shared.mjpeg_server import MjpegServer, matches_url, scaled_size
from tests.sim.camera_stream import eventually, frame_number, numbered_frame


@pytest.fixture(autouse=True)
def no_thread_left() -> Iterator[None]:
    before = set(threading.enumerate())
    yield
    assert eventually(lambda: set(threading.enumerate()) - before == set())


def snapshot(server: MjpegServer, query: str = "") -> npt.NDArray[np.uint8]:
    with urlopen(server.snapshot_url + query, timeout=5.0) as reply:
        image = cv2.imdecode(np.frombuffer(reply.read(), np.uint8), cv2.IMREAD_COLOR)
    assert image is not None
    return image


class TestScaledSize:
    def test_wider_frames_are_scaled_to_the_width_aspect_kept(self) -> None:
        assert scaled_size((800, 600), 400) == (400, 300)
        assert scaled_size((1280, 720), 400) == (400, 225)

    def test_narrower_frames_and_no_width_stay(self) -> None:
        assert scaled_size((320, 240), 400) == (320, 240)
        assert scaled_size((800, 600), None) == (800, 600)


class TestViews:
    def test_frames_are_served_at_the_width_asked(self) -> None:
        with MjpegServer(width_px=80) as server:
            server.publish(0, numbered_frame(4, (120, 160)))
            image = snapshot(server)
        assert image.shape == (60, 80, 3)
        assert frame_number(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)) == 4

    def test_matches_are_drawn_only_when_asked_inliers_green(self) -> None:
        grey = np.full((240, 320), 128, np.uint8)
        points = np.array([[80.0, 60.0], [240.0, 180.0]])
        with MjpegServer(width_px=160, jpeg_quality=95) as server:
            server.publish(0, grey, points, np.array([True, False]))
            plain = snapshot(server)
            drawn = snapshot(server, "?matches=1")
        assert plain.shape == drawn.shape == (120, 160, 3)
        assert np.abs(plain.astype(int) - 128).max() < 8  # grey, no points
        # The circles (radius 3 px) around the scaled points: (40, 30) and (120, 90).
        inlier = drawn[27:34, 37:44].reshape(-1, 3).astype(int)
        other = drawn[87:94, 117:124].reshape(-1, 3).astype(int)
        assert (inlier[:, 1] - inlier[:, 2]).max() > 40  # green over red somewhere
        assert (other[:, 2] - other[:, 0]).max() > 40  # orange: red over blue
        assert np.abs(drawn[5:20, 5:20].astype(int) - 128).max() < 8  # elsewhere untouched

    def test_matches_asked_of_a_frame_without_points_is_the_plain_frame(self) -> None:
        with MjpegServer() as server:
            server.publish(0, numbered_frame(2))
            assert frame_number(cv2.cvtColor(snapshot(server, "?matches=1"),
                                             cv2.COLOR_BGR2GRAY)) == 2

    def test_points_of_the_wrong_shape_are_refused(self) -> None:
        with MjpegServer() as server, pytest.raises(ShapeError, match="points_xy"):
            server.publish(0, numbered_frame(0), np.zeros((3, 3)))
        with MjpegServer() as server, pytest.raises(ShapeError, match="key_xy"):
            server.publish(0, numbered_frame(0), np.zeros((3, 2)), key_xy=np.zeros((2, 2)))


class TestMatchesJson:
    def test_the_newest_frames_matches_with_the_key_images_points(self) -> None:
        with MjpegServer(width_px=80) as server:
            assert matches_url(server.stream_url) == server.matches_url
            with pytest.raises(HTTPError) as before:
                urlopen(server.matches_url, timeout=5.0)
            assert before.value.code == 503
            server.publish(5, numbered_frame(1, (120, 160)), np.array([[10.04, 20.0]]),
                           np.array([True]), key_xy=np.array([[30.0, 40.06]]), key_id=12)
            server.publish(9, numbered_frame(2, (120, 160)), np.array([[1.0, 2.0], [3.0, 4.0]]),
                           np.array([False, True]), key_xy=np.array([[5.0, 6.0], [7.0, 8.0]]),
                           key_id=13)
            with urlopen(server.matches_url, timeout=5.0) as reply:
                assert reply.headers["Content-Type"] == "application/json"
                newest = json.loads(reply.read())
            server.publish(11, numbered_frame(3, (120, 160)))
            with urlopen(server.matches_url, timeout=5.0) as reply:
                bare = json.loads(reply.read())
        # Pixels of the frame as published (160x120), not as served (80 wide).
        assert newest == {"seq": 2, "t_ns": 9, "size": [160, 120], "key": 13,
                          "frame_xy": [[1.0, 2.0], [3.0, 4.0]],
                          "key_xy": [[5.0, 6.0], [7.0, 8.0]], "inliers": [False, True]}
        assert bare == {"seq": 3, "t_ns": 11, "size": [160, 120], "key": None,
                        "frame_xy": [], "key_xy": None, "inliers": None}

    def test_bad_options_are_refused(self) -> None:
        with pytest.raises(ValueError, match="width_px"):
            MjpegServer(width_px=0)
        with pytest.raises(ValueError, match="max_clients"):
            MjpegServer(max_clients=0)


class TestPublisher:
    def test_publish_never_waits_for_an_encoding(self, monkeypatch: pytest.MonkeyPatch) -> None:
        """A client encoding (held here at will) does not hold the publisher (rule 1)."""
        from shared import mjpeg_server

        entered, release = threading.Event(), threading.Event()
        encode = mjpeg_server._FrameBoard._encode

        def slow_encode(self: object, frame: object, matches: bool) -> bytes:
            entered.set()
            release.wait(10.0)
            return encode(self, frame, matches)  # type: ignore[arg-type]

        monkeypatch.setattr(mjpeg_server._FrameBoard, "_encode", slow_encode)
        with MjpegServer() as server:
            server.publish(0, numbered_frame(0))
            client = threading.Thread(target=lambda: urlopen(server.snapshot_url, timeout=10.0)
                                      .read())
            client.start()
            try:
                assert entered.wait(5.0)
                publisher = threading.Thread(
                    target=lambda: [server.publish(k, numbered_frame(k)) for k in range(1, 50)])
                publisher.start()
                publisher.join(5.0)
                assert not publisher.is_alive()  # done while the encoding still waits
                assert server.stats().published == 50
            finally:
                release.set()
                client.join()


class TestFlood:
    def test_clients_beyond_the_limit_get_503_and_the_others_go_on(self) -> None:
        with MjpegServer(max_clients=2) as server:
            server.publish(0, numbered_frame(0))
            streams = [socket.create_connection((server.host, server.port), timeout=5.0)
                       for _ in range(2)]
            try:
                for sock in streams:
                    sock.sendall(b"GET /stream.mjpg HTTP/1.0\r\n\r\n")
                    assert sock.recv(12) == b"HTTP/1.0 200"
                assert eventually(lambda: server.stats().streaming == 2)
                with pytest.raises(HTTPError) as busy:
                    urlopen(server.snapshot_url, timeout=5.0)
                assert busy.value.code == 503
            finally:
                for sock in streams:
                    sock.close()
            k = 0

            def freed() -> bool:  # a stream notices its client left when it next writes
                nonlocal k
                k += 1
                server.publish(k, numbered_frame(k))
                return server.stats().streaming == 0

            assert eventually(freed)
            assert snapshot(server).shape[:2] == (120, 160)
