"""Who may use the web app (``ground.web.access``) and the ground logs it serves
(``ground.web.log_files``): each refusal, over real HTTP and WebSocket connections."""

from __future__ import annotations

import base64
import http.client
import json
import os
import urllib.parse
from collections.abc import Iterator
from pathlib import Path

import pytest
from websockets.exceptions import InvalidStatus

from ground.station import GroundStation
from ground.web.access import read_token_file
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import WallClock
from shared.errors import InputError
from tests.ground.web.conftest import Page, RunningWeb
from tests.robot.vehicle.fake_app import FakeApp
from tests.robot.vehicle.harness import UNIX_OFFSET_NS, make_vehicle

TOKEN = "t0ken-for-the-tests_0123456789"


def fetch(url: str, method: str = "GET", headers: dict[str, str] | None = None,
          body: bytes | None = None) -> tuple[int, dict[str, str], bytes]:
    """One request (no redirect followed): status, headers (lower-case names), body."""
    parts = urllib.parse.urlsplit(url)
    connection = http.client.HTTPConnection(parts.hostname, parts.port, timeout=60)
    try:
        connection.request(method, parts.path + (f"?{parts.query}" if parts.query else ""),
                           body=body, headers=headers or {})
        response = connection.getresponse()
        return (response.status, {k.lower(): v for k, v in response.getheaders()},
                response.read())
    finally:
        connection.close()


@pytest.fixture
def guarded(vehicle: UdpVehicle, tmp_path: Path) -> Iterator[RunningWeb]:
    """The app with a token, and a ground log folder."""
    station = GroundStation.open(f"udpout:127.0.0.1:{vehicle.link.local_port}", WallClock())
    running = RunningWeb(station, token=TOKEN, log_dir=tmp_path / "logs")
    try:
        yield running
    finally:
        running.close()


def test_without_a_token_only_loopback_names_are_served(web: RunningWeb) -> None:
    assert fetch(web.url)[0] == 200
    port = urllib.parse.urlsplit(web.url).port
    for host in (f"localhost:{port}", f"[::1]:{port}"):
        assert fetch(web.url + "static/main.js", headers={"Host": host})[0] == 200
    # A site whose name points at 127.0.0.1 (DNS rebinding) is not this machine.
    status, _, body = fetch(web.url, headers={"Host": f"evil.example:{port}"})
    assert status == 403 and json.loads(body)["error"] == (
        f"Host 'evil.example:{port}' is not this machine (without a token the app serves "
        "loopback names only)")
    upgrade = {"Upgrade": "websocket", "Connection": "Upgrade", "Sec-WebSocket-Version": "13",
               "Sec-WebSocket-Key": base64.b64encode(bytes(16)).decode()}
    assert fetch(web.url + "ws", headers={**upgrade, "Host": f"127.0.0.1:{port}"})[0] == 101
    status, _, _ = fetch(web.url + "ws", headers={**upgrade, "Host": f"evil.example:{port}",
                                                  "Origin": f"http://evil.example:{port}"})
    assert status == 403


def test_with_a_token_every_request_and_websocket_carries_it(guarded: RunningWeb) -> None:
    url, ws_url = guarded.url, guarded.ws_url
    for path in ("", "static/main.js", "api/logs", "api/vehicles/1/memory/thumbnails/1.png"):
        status, _, body = fetch(url + path)
        assert status == 401 and json.loads(body)["error"].startswith(
            "no valid access token"), path
    assert fetch(url + "?token=wrong-token-0123456789")[0] == 401
    assert fetch(url, headers={"Cookie": "vmnav_token=wrong-token-0123456789"})[0] == 401
    # The URL printed: the cookie is set and the token leaves the address.
    status, headers, _ = fetch(url + "?token=" + TOKEN)
    assert status == 303 and headers["location"] == "/"
    assert headers["set-cookie"] == f"vmnav_token={TOKEN}; Path=/; HttpOnly; SameSite=Strict"
    # ... to this site only: a path of two slashes is not another host.
    status, headers, _ = fetch(url + "/evil.example/x?token=" + TOKEN)
    assert status == 303 and headers["location"] == "/evil.example/x"
    cookie = {"Cookie": f"vmnav_token={TOKEN}"}
    assert fetch(url, headers=cookie)[0] == 200
    assert fetch(url + "api/logs", headers={"Authorization": f"Bearer {TOKEN}"})[0] == 200
    with pytest.raises(InvalidStatus):
        Page(ws_url)  # no token
    with pytest.raises(InvalidStatus):  # the token, but another site's page
        Page(ws_url, origin="http://evil.example", headers=cookie)
    Page(ws_url, origin=url.rstrip("/"), headers=cookie).close()
    # Commands from another site's page are refused even with the token.
    status, _, body = fetch(url + "api/vehicles/1/goto-photo", "POST", body=b"\x89PNG",
                            headers={**cookie, "Origin": "http://evil.example"})
    assert status == 403 and json.loads(body) == {"error": "a goal photo from another "
                                                            "site's page"}


def test_the_ground_logs_are_listed_and_downloaded_and_nothing_else(
        guarded: RunningWeb, tmp_path: Path) -> None:
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "ground-0001.mcap").write_bytes(b"\x89MCAP0\r\n" + bytes(70_000))
    (logs / "ground-20250101-120000.tlog").write_bytes(b"tlog")
    os.utime(logs / "ground-20250101-120000.tlog", (1_700_000_000, 1_700_000_000))
    (logs / "notes.txt").write_text("not a log")
    (tmp_path / "secret").write_text("private")
    (logs / "ground-0002.mcap").symlink_to(tmp_path / "secret")
    auth = {"Authorization": f"Bearer {TOKEN}"}
    status, _, body = fetch(guarded.url + "api/logs", headers=auth)
    listing = json.loads(body)
    assert status == 200 and listing["dir"] == str(logs)
    assert [(f["name"], f["bytes"]) for f in listing["files"]] == [
        ("ground-0001.mcap", 70_008), ("ground-20250101-120000.tlog", 4)]
    assert listing["files"][1]["modified_unix_s"] == 1_700_000_000
    status, headers, body = fetch(guarded.url + "api/logs/ground-0001.mcap", headers=auth)
    assert status == 200 and body == (logs / "ground-0001.mcap").read_bytes()
    assert headers["content-disposition"] == 'attachment; filename="ground-0001.mcap"'
    for name in ("notes.txt", "ground-0002.mcap", "..%2Fsecret", "ground-0001.mcap%00",
                 "ground-0009.mcap", "..%2F..%2Fsecret", "%2E%2E"):
        status, _, body = fetch(guarded.url + "api/logs/" + name, headers=auth)
        assert status == 404 and "private" not in body.decode(), name


def test_a_token_file_is_read_or_refused_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "token"
    path.write_text(f"{TOKEN}\n")
    assert read_token_file(path) == TOKEN
    for bad in ("short", "has spaces in the middle of it", ""):
        path.write_text(bad)
        with pytest.raises(InputError, match="the token must be at least 16 characters"):
            read_token_file(path)
    with pytest.raises(InputError, match="cannot read the token"):
        read_token_file(tmp_path / "missing")


def test_the_signing_key_never_reaches_the_page(tmp_path: Path) -> None:
    key = bytes(range(100, 132))
    with make_vehicle(tmp_path, FakeApp(), WallClock(), key=key) as vehicle:
        vehicle.start_thread()
        station = GroundStation.open(f"udpout:127.0.0.1:{vehicle.link.local_port}",
                                     WallClock(), key=key, unix_offset_ns=UNIX_OFFSET_NS)
        running = RunningWeb(station)
        try:
            page = Page(running.ws_url)
            seen = [json.dumps(page.hello), json.dumps(page.ask("select")),
                    json.dumps(page.ask("params"))]
            page.update_where(lambda u: bool(u["vehicles"]), "the vehicle, signed")
            seen += [json.dumps(u) for u in page.updates]
            page.close()
            for path in ("", "static/main.js", "api/logs"):
                seen.append(fetch(running.url + path)[2].decode("latin-1"))
        finally:
            running.close()
    text = "\n".join(seen)
    assert '"params": {' in text  # the vehicle answered over the signed link
    for form in (key.hex(), key.hex().upper(), base64.b64encode(key).decode(),
                 key.decode("latin-1")):
        assert form not in text
