"""A Foxglove WebSocket protocol client, written from the protocol's spec (foxglove/ws-protocol,
docs/spec.md) on the ``websockets`` package, independent of the SDK that serves: for the
tests and ``vmnav bench foxglove``. ``serverInfo`` and ``advertise`` in, ``subscribe`` out,
binary ``MessageData`` (opcode 0x01: subscription id u32, log time u64, payload;
little-endian) in; JSON channels only (what :mod:`robot.foxglove_bridge` serves).

The SDK's server (foxglove-sdk 0.30) speaks the protocol under the subprotocol name
``foxglove.sdk.v1`` only: it answers ``foxglove.websocket.v1``, the name of the same
protocol before, with HTTP 400.
"""

from __future__ import annotations

import contextlib
import json
import struct
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from websockets.sync.client import ClientConnection, connect
from websockets.typing import Subprotocol

SUBPROTOCOL = Subprotocol("foxglove.sdk.v1")
MESSAGE_DATA = 0x01
#: :meth:`FoxgloveClient.receive_until` asks its ``done`` at least this often, s.
POLL_S = 0.1
_HEADER = struct.Struct("<BIQ")


@dataclass(frozen=True)
class Message:
    """One message received: its topic, log time (ns), JSON, and the JSON Schema its channel
    advertised."""

    topic: str
    log_time_ns: int
    data: dict[str, Any]
    schema: dict[str, Any]


class FoxgloveClient:
    """Connected to ``url``; the server's info and its advertised channels by topic."""

    def __init__(self, url: str, timeout_s: float = 10.0) -> None:
        self._stack = contextlib.ExitStack()
        self.ws: ClientConnection = self._stack.enter_context(connect(
            url, subprotocols=[SUBPROTOCOL], open_timeout=timeout_s, max_size=None))
        self.server_info = self._json()
        if self.server_info.get("op") != "serverInfo":
            raise ValueError(f"expected serverInfo first, got {self.server_info}")
        self.channels: dict[str, dict[str, Any]] = {}
        self._subscriptions: dict[int, str] = {}

    def close(self) -> None:
        self._stack.close()

    def __enter__(self) -> FoxgloveClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _json(self, timeout_s: float = 10.0) -> dict[str, Any]:
        frame = self.ws.recv(timeout_s)
        if not isinstance(frame, str):
            raise ValueError(f"expected a JSON operation, got {len(frame)} bytes")
        return dict(json.loads(frame))

    def _take(self, frame: str | bytes) -> Message | None:
        """A message of a subscription, or None after taking an operation."""
        if isinstance(frame, str):
            operation = json.loads(frame)
            if operation["op"] == "advertise":
                for channel in operation["channels"]:
                    self.channels[channel["topic"]] = channel
            return None
        opcode, subscription, log_time_ns = _HEADER.unpack_from(frame)
        if opcode != MESSAGE_DATA:
            return None
        topic = self._subscriptions[subscription]
        channel = self.channels[topic]
        if (channel["encoding"], channel["schemaEncoding"]) != ("json", "jsonschema"):
            raise ValueError(f"{topic}: not a JSON channel: {channel['encoding']}")
        return Message(topic, log_time_ns, json.loads(frame[_HEADER.size:]),
                       json.loads(channel["schema"]))

    def subscribe(self, topics: Iterable[str], timeout_s: float = 10.0) -> None:
        """Wait until ``topics`` are advertised, then subscribe to them.

        Raises:
            TimeoutError: not all advertised within ``timeout_s``.
        """
        wanted = set(topics)
        limit = time.monotonic() + timeout_s
        while not wanted <= set(self.channels):
            if time.monotonic() >= limit:
                raise TimeoutError(f"not advertised in {timeout_s} s: "
                                   f"{sorted(wanted - set(self.channels))}")
            self._take(self.ws.recv(max(0.0, limit - time.monotonic())))
        first = len(self._subscriptions)
        subscriptions = [{"id": first + i, "channelId": self.channels[topic]["id"]}
                         for i, topic in enumerate(sorted(wanted))]
        self._subscriptions.update({s["id"]: topic for s, topic in
                                    zip(subscriptions, sorted(wanted), strict=True)})
        self.ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))

    def receive_until(self, done: Callable[[list[Message]], bool], timeout_s: float = 20.0,
                      into: list[Message] | None = None) -> list[Message]:
        """Every message received until ``done(messages so far)``, which is asked before
        each message and at least every :data:`POLL_S` (it may feed the server).

        Args:
            done: when to stop.
            timeout_s: fail after this long.
            into: the list the messages are appended to as they come (another thread
                may read it); None: a new one.

        Raises:
            TimeoutError: not done within ``timeout_s``.
        """
        received: list[Message] = [] if into is None else into
        limit = time.monotonic() + timeout_s
        while not done(received):
            left = limit - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"not done in {timeout_s} s: {len(received)} messages, "
                                   f"topics {sorted({m.topic for m in received})}")
            try:  # done() is asked again at least every POLL_S
                message = self._take(self.ws.recv(min(left, POLL_S)))
            except TimeoutError:
                continue
            if message is not None:
                received.append(message)
        return received


def by_topic(received: list[Message], topic: str) -> list[Message]:
    """The messages of ``topic``, in order."""
    return [m for m in received if m.topic == topic]
