"""The robot's camera in the web app: found through the camera protocol of a real vehicle
endpoint, relayed from a real MJPEG server; a vehicle without a camera, a stream that is off
and a flood of viewers are one line each."""

from __future__ import annotations

import http.client
import http.server
import json
import threading
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import urlsplit

import cv2
import numpy as np
import pytest

from ground.web.camera_proxy import MAX_VIEWERS
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import WallClock
from shared.mavlink.camera import VideoStream
from shared.mjpeg_server import MjpegServer
from tests.ground.web.conftest import Page, RunningWeb, wait_for
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import make_vehicle
from tests.sim.camera_stream import frame_number, numbered_frame


@pytest.fixture
def camera() -> Iterator[MjpegServer]:
    """The robot's MJPEG server, publishing numbered frames until the test ends."""
    with MjpegServer(width_px=80) as server:
        stop = threading.Event()

        def publish() -> None:
            k = 0
            while not stop.wait(0.05):
                server.publish(k, numbered_frame(k), np.array([[80.0, 60.0]]),
                               key_xy=np.array([[70.0, 50.0]]), key_id=3)
                k += 1

        thread = threading.Thread(target=publish)
        thread.start()
        try:
            yield server
        finally:
            stop.set()
            thread.join()


@pytest.fixture
def vehicle(tmp_path: Path, app: FakeApp, camera: MjpegServer) -> Iterator[UdpVehicle]:
    """System 1 with a camera component advertising ``camera``'s stream."""
    stream = VideoStream(camera.stream_url, 80, 60, 20.0)
    with make_vehicle(tmp_path, app, WallClock(), video=stream) as udp_vehicle:
        udp_vehicle.start_thread()
        yield udp_vehicle


def open_stream(web: RunningWeb, query: str = "") -> http.client.HTTPResponse:
    url = urlsplit(web.url)
    conn = http.client.HTTPConnection(url.hostname, url.port, timeout=60)
    conn.request("GET", f"/api/vehicles/1/camera.mjpg{query}")
    return conn.getresponse()


def read_part(response: http.client.HTTPResponse) -> bytes:
    """One JPEG of a multipart stream."""
    boundary = response.headers.get_content_type() and response.headers.get_param("boundary")
    assert response.readline().strip() == f"--{boundary}".encode()
    length = 0
    while (line := response.readline()) not in (b"\r\n", b""):
        name, _, value = line.decode().partition(":")
        if name.lower() == "content-length":
            length = int(value)
    body = response.read(length)
    response.readline()
    return body


def test_the_page_finds_the_stream_and_the_frames_come_through(web: RunningWeb,
                                                             page: Page,
                                                             camera: MjpegServer) -> None:
    page.update_where(lambda u: u["vehicles"], "the vehicle heard")
    reply = page.ask("camera")
    assert reply["ok"], reply
    assert reply["camera"] == {"uri": camera.stream_url, "width": 80, "height": 60,
                               "rate_hz": 20.0, "name": "fisheye",
                               "url": "/api/vehicles/1/camera.mjpg"}
    response = open_stream(web, "?matches=1")
    try:
        assert response.status == 200
        assert response.headers.get_content_type() == "multipart/x-mixed-replace"
        numbers = []
        for _ in range(3):
            image = cv2.imdecode(np.frombuffer(read_part(response), np.uint8), cv2.IMREAD_COLOR)
            assert image.shape == (60, 80, 3)
            numbers.append(frame_number(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)))
        assert len(set(numbers)) == 3  # new frames, not the same one again
        assert image[30, 35:46].max(axis=0)[1] > image[30, 35:46].max(axis=0)[0] + 30  # a point
    finally:
        response.close()
    wait_for(lambda: web.server.station_loop is not None
             and page_viewers(web) == 0, "the relay closed with the page")


def get(web: RunningWeb, path: str) -> tuple[int, dict]:
    url = urlsplit(web.url)
    conn = http.client.HTTPConnection(url.hostname, url.port, timeout=60)
    try:
        conn.request("GET", path)
        response = conn.getresponse()
        return response.status, json.loads(response.read())
    finally:
        conn.close()


def test_the_matches_of_the_newest_frame_come_through_with_the_key_images(
        web: RunningWeb, page: Page, camera: MjpegServer) -> None:
    page.update_where(lambda u: u["vehicles"], "the vehicle heard")
    status, body = get(web, "/api/vehicles/1/camera-matches.json")
    assert status == 200, body
    assert body["key"] == 3 and body["size"] == [160, 120]
    assert body["frame_xy"] == [[80.0, 60.0]] and body["key_xy"] == [[70.0, 50.0]]


class Garbage(http.server.BaseHTTPRequestHandler):
    """A robot's server that answers anything with HTML."""

    def do_GET(self) -> None:
        self.send_response(200)
        self.end_headers()
        self.wfile.write(b"<html>not the matches</html>")

    def log_message(self, *args: object) -> None:
        pass


class TestMatchesNotJson:
    @pytest.fixture
    def robot(self) -> Iterator[http.server.ThreadingHTTPServer]:
        with http.server.ThreadingHTTPServer(("127.0.0.1", 0), Garbage) as server:
            thread = threading.Thread(target=server.serve_forever)
            thread.start()
            yield server
            server.shutdown()
            thread.join()

    @pytest.fixture
    def vehicle(self, tmp_path: Path, app: FakeApp,
                robot: http.server.ThreadingHTTPServer) -> Iterator[UdpVehicle]:
        port = robot.server_address[1]
        stream = VideoStream(f"http://127.0.0.1:{port}/stream.mjpg", 80, 60, 5.0)
        with make_vehicle(tmp_path, app, WallClock(), video=stream) as udp_vehicle:
            udp_vehicle.start_thread()
            yield udp_vehicle

    def test_is_one_line_and_the_server_goes_on(self, web: RunningWeb, page: Page,
                                                robot: http.server.ThreadingHTTPServer) -> None:
        page.update_where(lambda u: u["vehicles"], "the vehicle heard")
        status, body = get(web, "/api/vehicles/1/camera-matches.json")
        assert status == 502
        assert body["error"] == (f"camera matches http://127.0.0.1:{robot.server_address[1]}"
                                 "/matches.json: not a JSON object (Expecting value: line 1 "
                                 "column 1 (char 0))")
        assert page.ask("hold")["ok"]


def page_viewers(web: RunningWeb) -> int:
    proxy = web.server._server.config.app.app.state.camera_proxy  # type: ignore[attr-defined]
    return int(proxy.viewers)


def test_a_stream_that_is_off_is_one_line_and_asked_again(web: RunningWeb, page: Page,
                                                           camera: MjpegServer) -> None:
    page.update_where(lambda u: u["vehicles"], "the vehicle heard")
    camera.close()  # the robot's server is gone, its camera still advertises it
    response = open_stream(web)
    body = json.loads(response.read())
    assert response.status == 502
    assert body["error"].startswith(f"camera stream {camera.stream_url}: cannot connect")
    assert "\n" not in body["error"]
    assert page.ask("hold")["ok"]  # the server goes on


def test_a_flood_of_viewers_is_refused_beyond_the_limit(web: RunningWeb, page: Page) -> None:
    page.update_where(lambda u: u["vehicles"], "the vehicle heard")
    open_ = [open_stream(web) for _ in range(MAX_VIEWERS)]
    try:
        assert all(r.status == 200 for r in open_)
        extra = open_stream(web)
        assert extra.status == 503
        assert "camera views open already" in json.loads(extra.read())["error"]
    finally:
        for response in open_:
            response.close()


class TestWithoutCamera:
    @pytest.fixture
    def vehicle(self, tmp_path: Path, app: FakeApp) -> Iterator[UdpVehicle]:
        with make_vehicle(tmp_path, app, WallClock()) as udp_vehicle:
            udp_vehicle.start_thread()
            yield udp_vehicle

    def test_the_page_and_the_route_say_so_in_one_line(self, web: RunningWeb,
                                                       page: Page) -> None:
        page.update_where(lambda u: u["vehicles"], "the vehicle heard")
        reply = page.ask("camera")
        assert reply["ok"] is False
        assert reply["error"].startswith("vehicle 1 has no camera stream")
        response = open_stream(web)
        assert response.status == 502
        assert json.loads(response.read())["error"] == reply["error"]
