"""The web app: the page, its WebSocket and the key image files, on Starlette.

Routes:

* ``GET /``: the page (``static/index.html``); ``/static/...``: its modules and style;
* ``GET /api/vehicles/{system}/memory/{thumbnails|images}/{key}.png``: a key image file
  fetched from the robot over MAVLink FTP (cached by the station loop);
* ``GET /api/vehicles/{system}/teaching/{key}.png``: the thumbnail of a key image of the
  path being taught, over MAVLink FTP (not cached);
* ``GET /api/vehicles/{system}/camera.mjpg`` (``?matches=1``): the robot's camera, relayed
  (``ground.web.camera_proxy``); ``GET /api/vehicles/{system}/camera-matches.json``: the
  matches of its newest frame, with the key image's points;
* ``POST /api/vehicles/{system}/goto-photo``: a photo as the goal;
* ``GET /api/logs``: the ground log's files (``--log``); ``GET /api/logs/{name}``: one,
  downloaded (``ground.web.log_files``);
* ``WS /ws``: live data and the page's requests (``ground.web.requests``).

On the WebSocket the server sends JSON objects with a ``type``:

* ``hello`` (first): this connection's number ``client``, the last update and the recent
  samples and notices of each vehicle, so plots start filled;
* ``update``: the station loop's (``ground.web.station_loop`` rule 3);
* ``reply``: ``{"type": "reply", "id": ..., "cmd": ..., "ok": true, ...}`` with the
  result's fields, or ``"ok": false, "error": "one line"``.

Rules:

1. A request the page got wrong, a vehicle that refuses or does not answer: a one-line
   ``error`` in the reply and a one-line warning in the log. A bug (any other exception):
   the same reply, its traceback in the log only. The server keeps running either way.
2. A WebSocket whose ``Origin`` is not this server's own is refused before it opens
   (another site's page cannot drive the robot through the operator's browser);
   clients that send no Origin (not browsers) are served.
3. A page that reads too slowly misses updates (at most :data:`MAX_QUEUED` wait for it)
   but never a reply.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import itertools
import json
import logging
import math
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.requests import HTTPConnection
from starlette.requests import Request as HttpRequest
from starlette.responses import FileResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket, WebSocketDisconnect

from ground.web.camera_proxy import CameraProxy, StreamUnavailableError, fetch_matches
from ground.web.log_files import list_logs, open_log
from ground.web.requests import parse_request, request_id_of
from ground.web.station_loop import StationLoop
from shared.errors import InputError, VmnavError
from shared.image_decode import check_image
from shared.image_header import ImageFormat

_log = logging.getLogger(__name__)

STATIC_DIR = Path(__file__).parent / "static"
#: Updates waiting for a slow page, at most (rule 3).
MAX_QUEUED = 100
#: Samples kept per vehicle for a page that connects (about a minute at 20 a second).
HISTORY_SAMPLES = 1200
#: Notices kept per vehicle for a page that connects.
HISTORY_NOTICES = 50
#: WebSocket close code of a refused origin (RFC 6455 policy violation).
POLICY_VIOLATION = 1008
#: A goal photo larger than this is refused before all of it is read, bytes.
MAX_PHOTO_BYTES = 16 << 20


class Hub:
    """The pages connected (rule 3), fed from the station loop's thread."""

    def __init__(self) -> None:
        self._loop: asyncio.AbstractEventLoop | None = None
        self._clients: dict[int, asyncio.Queue[dict[str, Any]]] = {}
        self._numbers = itertools.count(1)
        self._last: dict[str, Any] | None = None
        self._samples: dict[str, collections.deque[dict[str, Any]]] = {}
        self._notices: dict[str, collections.deque[str]] = {}

    def attach(self, loop: asyncio.AbstractEventLoop) -> None:
        """Deliver on ``loop`` (the server's) from now on."""
        self._loop = loop

    def publish_threadsafe(self, update: dict[str, Any]) -> None:
        """Hand ``update`` to every page; callable from any thread."""
        if self._loop is not None and not self._loop.is_closed():
            with contextlib.suppress(RuntimeError):  # the loop closed meanwhile: shutting down
                self._loop.call_soon_threadsafe(self._publish, update)

    def _publish(self, update: dict[str, Any]) -> None:
        self._last = update
        for system, samples in update["samples"].items():
            self._samples.setdefault(
                system, collections.deque(maxlen=HISTORY_SAMPLES)).extend(samples)
        for system, notices in update["notices"].items():
            self._notices.setdefault(
                system, collections.deque(maxlen=HISTORY_NOTICES)).extend(notices)
        for queue in self._clients.values():
            if queue.qsize() < MAX_QUEUED:
                queue.put_nowait(update)

    def connect(self) -> tuple[int, asyncio.Queue[dict[str, Any]]]:
        """A new page: its number, and its queue, which starts with the ``hello``."""
        number = next(self._numbers)
        queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
        queue.put_nowait({
            "type": "hello", "client": number, "last": self._last,
            "samples": {k: list(v) for k, v in self._samples.items()},
            "notices": {k: list(v) for k, v in self._notices.items()},
        })
        self._clients[number] = queue
        return number, queue

    def disconnect(self, number: int) -> None:
        self._clients.pop(number, None)


def same_origin(connection: HTTPConnection) -> bool:
    """Whether the WebSocket's (or request's) ``Origin`` is this server, or absent (rule 2)."""
    origin = connection.headers.get("origin")
    host = connection.headers.get("host")
    return origin is None or origin in (f"http://{host}", f"https://{host}")


async def _answer(station_loop: StationLoop, text: str, client: int) -> dict[str, Any]:
    """The reply to one request (rule 1)."""
    try:
        request = parse_request(text)
    except InputError as e:
        _log.warning("page %d: request refused: %s", client, e)
        return {"type": "reply", "id": request_id_of(text), "ok": False, "error": str(e)}
    reply: dict[str, Any] = {"type": "reply", "id": request.request_id, "cmd": request.command}
    try:
        result = await asyncio.wrap_future(station_loop.request(request, client))
    except VmnavError as e:
        _log.warning("page %d: %s: %s", client, request.command, e)
        return {**reply, "ok": False, "error": str(e)}
    except Exception as e:
        _log.exception("page %d: %s failed", client, request.command)
        return {**reply, "ok": False, "error": f"internal error: {type(e).__name__}: {e}"}
    return {**reply, "ok": True, **result}


def _finite(value: Any) -> Any:
    """``value`` with every NaN or infinity inside it replaced by None."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def encode(message: dict[str, Any]) -> str:
    """``message`` as JSON the browser parses: NaN and infinities (which JSON lacks, and a
    vehicle may send, e.g. as a parameter's value) become ``null``."""
    try:
        return json.dumps(message, allow_nan=False)
    except ValueError:
        return json.dumps(_finite(message), allow_nan=False)


async def _send_all(websocket: WebSocket, queue: asyncio.Queue[dict[str, Any]]) -> None:
    while True:
        message = await queue.get()
        await websocket.send_text(encode(message))


async def _websocket(websocket: WebSocket) -> None:
    station_loop: StationLoop = websocket.app.state.station_loop
    hub: Hub = websocket.app.state.hub
    if not same_origin(websocket):
        _log.warning("WebSocket from origin %r refused (not %r)",
                     websocket.headers.get("origin"), websocket.headers.get("host"))
        await websocket.close(code=POLICY_VIOLATION)
        return
    await websocket.accept()
    client, queue = hub.connect()
    sender = asyncio.create_task(_send_all(websocket, queue))
    answering: set[asyncio.Task[None]] = set()

    async def answer(text: str) -> None:
        queue.put_nowait(await _answer(station_loop, text, client))

    try:
        while True:
            message = await websocket.receive()
            if message["type"] == "websocket.disconnect":
                break
            text = message.get("text")
            if text is None:
                text = "(binary)"  # refused by parse_request as not JSON
            task = asyncio.create_task(answer(text))
            answering.add(task)
            task.add_done_callback(answering.discard)
    except WebSocketDisconnect:
        pass
    finally:
        hub.disconnect(client)
        station_loop.disconnected(client)  # stops the robot if this page drove it
        sender.cancel()
        for task in answering:
            task.cancel()


async def _index(request: HttpRequest) -> Response:
    return FileResponse(STATIC_DIR / "index.html", headers={"Cache-Control": "no-cache"})


async def _memory_file(request: HttpRequest) -> Response:
    station_loop: StationLoop = request.app.state.station_loop
    system, kind, key = (request.path_params["system"], request.path_params.get("kind"),
                         request.path_params["key"])
    try:
        if kind is None:  # the path being taught: its ids are freed if it is dropped
            data = await asyncio.wrap_future(station_loop.teaching_file(system, key))
            return Response(data, media_type="image/png", headers={"Cache-Control": "no-store"})
        data = await asyncio.wrap_future(station_loop.memory_file(system, kind, key))
    except VmnavError as e:
        _log.warning("key image %s/%d of vehicle %d: %s", kind or "teaching", key, system, e)
        # 400: the page asked for something that cannot be; 502: the robot refused or failed.
        return JSONResponse({"error": str(e)}, status_code=400 if isinstance(e, InputError)
                            else 502)
    return Response(data, media_type="image/png",
                    headers={"Cache-Control": "private, max-age=86400, immutable"})


async def _camera(request: HttpRequest) -> Response:
    """The camera's stream, or (``camera-matches.json``) its newest frame's matches."""
    station_loop: StationLoop = request.app.state.station_loop
    proxy: CameraProxy = request.app.state.camera_proxy
    system = request.path_params["system"]
    try:
        stream = await asyncio.wrap_future(station_loop.video_stream(system))
        if request.url.path.endswith(".json"):
            return await fetch_matches(stream)
        return await proxy.relay(system, stream, request.query_params.get("matches") == "1")
    except VmnavError as e:
        _log.warning("camera of vehicle %d: %s", system, e)
        return JSONResponse({"error": str(e)}, status_code=400 if isinstance(e, InputError)
                            else 502)
    except StreamUnavailableError as e:
        _log.warning("camera of vehicle %d: %s", system, e)
        station_loop.forget_video_stream(system)
        return JSONResponse({"error": str(e)}, status_code=502)


async def _goto_photo(request: HttpRequest) -> Response:
    """``POST /api/vehicles/SYS/goto-photo`` with a PNG or JPEG body: upload it and send the
    vehicle where it was taken; the answer names the key image found (or why not)."""
    station_loop: StationLoop = request.app.state.station_loop
    system = request.path_params["system"]
    if not same_origin(request):
        return JSONResponse({"error": "a goal photo from another site's page"}, status_code=403)
    declared = int(request.headers.get("content-length") or 0)
    if declared > MAX_PHOTO_BYTES:
        return JSONResponse({"error": f"photo: {declared} bytes, at most {MAX_PHOTO_BYTES}"},
                            status_code=413)
    body = bytearray()
    async for chunk in request.stream():
        body += chunk
        if len(body) > MAX_PHOTO_BYTES:
            return JSONResponse({"error": f"photo: more than {MAX_PHOTO_BYTES} bytes"},
                                status_code=413)
    try:
        header = check_image(bytes(body), "photo")
        found = await asyncio.wrap_future(station_loop.goto_photo(
            system, bytes(body), ".png" if header.format is ImageFormat.PNG else ".jpg"))
    except VmnavError as e:
        _log.warning("goal photo for vehicle %d: %s", system, e)
        return JSONResponse({"error": str(e)}, status_code=400 if isinstance(e, InputError)
                            else 502)
    return JSONResponse({"photo_id": found.photo_id, "keyframe_id": found.keyframe_id,
                         "said": found.said})


async def _logs(request: HttpRequest) -> Response:
    """The ground log's files, newest first (``{"dir": null}`` without ``--log``)."""
    log_dir: Path | None = request.app.state.log_dir
    if log_dir is None:
        return JSONResponse({"dir": None, "files": []})
    files = await asyncio.to_thread(list_logs, log_dir)
    return JSONResponse({"dir": str(log_dir), "files": [
        {"name": f.name, "bytes": f.size_bytes, "modified_unix_s": f.modified_unix_s}
        for f in files]})


async def _log_file(request: HttpRequest) -> Response:
    """One of the ground log's files, as a download."""
    log_dir: Path | None = request.app.state.log_dir
    name = request.path_params["name"]
    if log_dir is None:
        return JSONResponse({"error": "no ground log: start with --log DIR"}, status_code=404)
    try:
        size, chunks = await asyncio.to_thread(open_log, log_dir, name)
    except InputError as e:
        _log.warning("log download: %s", e)
        return JSONResponse({"error": str(e)}, status_code=404)
    return StreamingResponse(chunks, media_type="application/octet-stream", headers={
        "Content-Length": str(size), "Content-Disposition": f'attachment; filename="{name}"',
        "Cache-Control": "no-store"})


def build_app(station_loop: StationLoop, hub: Hub, log_dir: Path | None = None) -> Starlette:
    """The app around a (not yet started) station loop: the loop runs while the app does;
    ``log_dir``: the ground log's folder the page lists (None: no log)."""

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        hub.attach(asyncio.get_running_loop())
        station_loop.start()
        try:
            yield
        finally:
            station_loop.stop()

    app = Starlette(routes=[
        Route("/", _index),
        Mount("/static", StaticFiles(directory=STATIC_DIR), name="static"),
        Route("/api/vehicles/{system:int}/memory/{kind}/{key:int}.png", _memory_file),
        Route("/api/vehicles/{system:int}/teaching/{key:int}.png", _memory_file),
        Route("/api/vehicles/{system:int}/camera.mjpg", _camera),
        Route("/api/vehicles/{system:int}/camera-matches.json", _camera),
        Route("/api/vehicles/{system:int}/goto-photo", _goto_photo, methods=["POST"]),
        Route("/api/logs", _logs),
        Route("/api/logs/{name}", _log_file),
        WebSocketRoute("/ws", _websocket),
    ], lifespan=lifespan)
    app.state.log_dir = log_dir
    app.state.station_loop = station_loop
    app.state.hub = hub
    app.state.camera_proxy = CameraProxy()
    return app
