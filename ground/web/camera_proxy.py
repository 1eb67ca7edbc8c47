"""The robot's camera in the page: ``GET /api/vehicles/{system}/camera.mjpg`` relays the MJPEG
stream the vehicle advertises through the MAVLink camera protocol.

Why relay rather than link: the page stays on one origin (the station's), so it needs no
route to the robot's network, and an access token the app may require one day covers the
camera too; the station opens only the ``http://`` URI its vehicle advertised, never one
the page names.

Rules:

1. The stream is found by the station loop (``StationLoop.video_stream``: the camera
   protocol, kept per vehicle). The relay connects to it within :data:`CONNECT_TIMEOUT_S`
   and checks that it answers ``200``, before the page gets any byte: a vehicle without a
   camera, a stream that is off or refuses is a one-line JSON error (``{"error": ...}``,
   400 for a vehicle not heard, 502 otherwise), and the stream is asked of the camera
   again next time.
2. Then the bytes pass through as they come (``?matches=1`` is passed on). A robot silent
   for :data:`READ_TIMEOUT_S` or gone ends the relay (one warning line); a page that goes
   away closes the robot's connection; a page that stops reading stops the relay reading,
   so the robot's server drops it after its own timeout (``shared.mjpeg_server`` rule 4).
3. At most :data:`MAX_VIEWERS` relays at once (each costs a connection to the robot);
   more get 503 at once.
4. The matches of the newest frame (``GET .../camera-matches.json``): the ``/matches.json``
   beside the advertised stream on the robot's server (``shared.mjpeg_server`` rule 3),
   fetched once per request like the stream's head (rule 1), at most
   :data:`MAX_MATCHES_BYTES`, and checked to be a JSON object before the page gets it.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import AsyncIterator
from urllib.parse import urlsplit

from starlette.responses import JSONResponse, Response, StreamingResponse

from shared.mavlink.camera import VideoStream
from shared.mjpeg_server import matches_url

_log = logging.getLogger(__name__)

#: How long the robot's camera server has to accept and answer, s.
CONNECT_TIMEOUT_S = 5.0
#: A stream silent this long is over (the robot's frames come at 5 Hz by default), s.
READ_TIMEOUT_S = 10.0
#: Relays at once (rule 3).
MAX_VIEWERS = 8
#: The largest matches document taken from the robot (rule 4), bytes.
MAX_MATCHES_BYTES = 1 << 20
_CHUNK = 64 * 1024
_HEADER_LINES = 50


class StreamUnavailableError(Exception):
    """The stream did not open (rule 1); the message is one line."""


class CameraProxy:
    """The relays of one app (module rules)."""

    def __init__(self, max_viewers: int = MAX_VIEWERS) -> None:
        self.max_viewers = max_viewers
        self.viewers = 0
        """Relays streaming now."""

    async def relay(self, system_id: int, stream: VideoStream, matches: bool) -> Response:
        """The page's response for ``stream`` of vehicle ``system_id``.

        Raises:
            StreamUnavailableError: it did not open (rule 1).
        """
        if self.viewers >= self.max_viewers:
            return JSONResponse({"error": f"{self.max_viewers} camera views open already; "
                                          "close one"}, status_code=503)
        reader, writer, content_type = await _open_stream(stream, matches)
        self.viewers += 1  # before the response starts: counted however it ends
        return StreamingResponse(self._body(system_id, stream, reader, writer),
                                 media_type=content_type,
                                 headers={"Cache-Control": "no-cache, no-store"})

    async def _body(self, system_id: int, stream: VideoStream, reader: asyncio.StreamReader,
                    writer: asyncio.StreamWriter) -> AsyncIterator[bytes]:
        try:
            while chunk := await asyncio.wait_for(reader.read(_CHUNK), READ_TIMEOUT_S):
                yield chunk
            _log.warning("vehicle %d's camera %s ended its stream", system_id, stream.uri)
        except (OSError, TimeoutError) as e:
            why = f"silent for {READ_TIMEOUT_S:g} s" if isinstance(e, TimeoutError) else e
            _log.warning("vehicle %d's camera %s: %s", system_id, stream.uri, why)
        finally:
            self.viewers -= 1
            writer.close()


async def fetch_matches(stream: VideoStream) -> Response:
    """The newest frame's matches of ``stream``'s server, for the page (rule 4).

    Raises:
        StreamUnavailableError: the server did not answer with a JSON object.
    """
    uri = matches_url(stream.uri)
    reader, writer, _ = await _open(uri, "camera matches")
    try:
        body = await asyncio.wait_for(reader.read(MAX_MATCHES_BYTES + 1), READ_TIMEOUT_S)
        while len(body) <= MAX_MATCHES_BYTES and (more := await asyncio.wait_for(
                reader.read(MAX_MATCHES_BYTES + 1 - len(body)), READ_TIMEOUT_S)):
            body += more
    except (OSError, TimeoutError) as e:
        raise StreamUnavailableError(f"camera matches {uri}: "
                                     f"{'no answer' if isinstance(e, TimeoutError) else e}") \
            from None
    finally:
        writer.close()
    if len(body) > MAX_MATCHES_BYTES:
        raise StreamUnavailableError(f"camera matches {uri}: more than {MAX_MATCHES_BYTES} bytes")
    try:
        if not isinstance(json.loads(body), dict):
            raise ValueError("not an object")
    except ValueError as e:
        raise StreamUnavailableError(f"camera matches {uri}: not a JSON object ({e})") from None
    return Response(body, media_type="application/json",
                    headers={"Cache-Control": "no-cache, no-store"})


async def _open_stream(stream: VideoStream, matches: bool) \
        -> tuple[asyncio.StreamReader, asyncio.StreamWriter, str]:
    """The stream, with the matched points drawn if ``matches`` (rule 1)."""
    return await _open(stream.uri + ("?matches=1" if matches else ""), "camera stream")


async def _open(uri: str, what: str) -> tuple[asyncio.StreamReader, asyncio.StreamWriter, str]:
    """Connect to ``uri``, ask, check the status and read the headers (rule 1)."""
    url = urlsplit(uri)
    where = f"{what} {uri}"
    if url.scheme != "http" or not url.hostname:
        raise StreamUnavailableError(f"{where}: not an http:// URI")
    try:
        reader, writer = await asyncio.wait_for(
            asyncio.open_connection(url.hostname, url.port or 80), CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as e:
        raise StreamUnavailableError(f"{where}: cannot connect: "
                                     f"{'timed out' if isinstance(e, TimeoutError) else e}") \
            from None
    try:
        path = (url.path or "/") + (f"?{url.query}" if url.query else "")
        writer.write(f"GET {path} HTTP/1.0\r\nHost: {url.netloc}\r\n\r\n".encode("ascii"))
        status = await asyncio.wait_for(reader.readline(), CONNECT_TIMEOUT_S)
        fields = status.split()
        if len(fields) < 2 or not fields[0].startswith(b"HTTP/1.") or fields[1] != b"200":
            text = status.decode("ascii", "replace").strip() or "nothing"
            raise StreamUnavailableError(f"{where} answered {text[:80]!r}")
        content_type = "multipart/x-mixed-replace"
        for _ in range(_HEADER_LINES):
            line = await asyncio.wait_for(reader.readline(), CONNECT_TIMEOUT_S)
            if line in (b"\r\n", b"\n", b""):
                break
            name, _, value = line.decode("latin-1").partition(":")
            if name.strip().lower() == "content-type":
                content_type = value.strip()
        else:
            raise StreamUnavailableError(f"{where}: more than {_HEADER_LINES} header lines")
    except (OSError, TimeoutError, StreamUnavailableError) as e:
        writer.close()
        if isinstance(e, StreamUnavailableError):
            raise
        why = "no answer" if isinstance(e, TimeoutError) else str(e)
        raise StreamUnavailableError(f"{where}: {why}") from None
    return reader, writer, content_type
