"""Hostile input against a real ``vmnav sim serve``: its emulated Pioneer and its control endpoint.

One run (about 20 s on an idle machine, most of it the simulator's start):

1. Start ``vmnav sim serve --aria tcp:0 --control http:0`` as a child process.
2. **ARIA.** Connect our Pioneer driver's client (:class:`~robot.pioneer.client.PioneerClient`)
   over TCP, then write a seeded batch of :data:`ARIA_PACKETS` well-framed command
   packets with random IDs (every command but CLOSE, which ends a session by design,
   and IDs that are no command) and random arguments (ints over the whole sign-byte
   range, strings, raw bytes, none), then the issue's BATTEST 25.6 V packet, while the
   client keeps its link alive; it counts the SIPs of the next half second and reads
   the battery they report (25.5 V: BATTERY is one byte of decivolts; the driver
   prefers BATTERYX10, 25.6 V). Then a fresh client connects and counts the SIPs of
   one second: the server still serves when it gets at least five.
3. **Control endpoint.** Each request of :data:`BAD_REQUESTS` (cross-origin and
   ``text/plain`` POSTs, poses of 1e308, inf and NaN, bodies too long or too deep, a
   DNS-rebound ``Host``) must be refused with a 4xx and leave the robot's true pose
   alone. Then :data:`IDLE_CONNECTIONS` connections that send nothing are opened and
   held; meanwhile the server process's thread count (``/proc/PID/status``) is sampled
   and a legitimate ``GET /truth`` is timed :data:`PROBES` times.
4. SIGTERM; the server's exit code and its closing counts.

Figures are in SI units; ``targets_met`` holds when the server survived and still
served SIPs, every bad request was refused and moved nothing, the idle connections
added at most :data:`EXTRA_THREADS_MAX` threads, and every probe was answered within
:data:`PROBE_LATENCY_MAX_S`. Latencies are None when no probe was answered.
"""

from __future__ import annotations

import contextlib
import http.client
import json
import random
import re
import socket
import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from robot.pioneer.client import PioneerClient
from shared.aria import Command, encode_packet
from shared.byte_link import LinkClosedError
from shared.clock import WallClock
from sim.pioneer.links import StreamLink
from tools.harness.vmnav_process import VmnavProcess

ARIA_PACKETS = 2000
"""Random command packets in the hostile batch."""
BATTEST_25_6_V = bytes.fromhex("fafb06fa3b0001fa3c")
"""The issue's packet: BATTEST 256 decivolts, one more than the SIP's BATTERY byte holds."""
IDLE_CONNECTIONS = 300
PROBES = 10
EXTRA_THREADS_MAX = 2
"""Threads the idle connections may add to the server process (none expected)."""
PROBE_LATENCY_MAX_S = 1.0
SIPS_AFTER_MIN = 5
"""SIPs in the second after the batch that show the robot still serves (10 expected)."""
START_TIMEOUT_S = 60.0
"""A server that has not printed its ports by then counts as broken, s."""
_STEP_S = 0.01
_PACKETS_PER_STEP = 20

BAD_REQUESTS: tuple[tuple[str, str, dict[str, str], bytes], ...] = (
    ("cross_origin_text_plain", "/place",
     {"Content-Type": "text/plain;charset=UTF-8", "Origin": "http://evil.example"},
     b'{"pose_w": [3.0, 10.0, 0.5]}'),
    ("text_plain", "/place", {"Content-Type": "text/plain"}, b'{"pose_w": [3.0, 10.0, 0.5]}'),
    ("form", "/place", {"Content-Type": "application/x-www-form-urlencoded"}, b"pose_w=1"),
    ("origin_null", "/place", {"Content-Type": "application/json", "Origin": "null"},
     b'{"pose_w": [3.0, 10.0, 0.5]}'),
    ("rebound_host", "/place", {"Content-Type": "application/json", "Host": "evil.example"},
     b'{"pose_w": [3.0, 10.0, 0.5]}'),
    ("pose_1e308", "/place", {"Content-Type": "application/json"},
     b'{"pose_w": [1e308, 1e308, 0.0]}'),
    ("pose_inf", "/place", {"Content-Type": "application/json"}, b'{"pose_w": [1e400, 0, 0]}'),
    ("pose_nan", "/place", {"Content-Type": "application/json"}, b'{"pose_w": [NaN, 0, 0]}'),
    ("yaw_huge_int", "/place", {"Content-Type": "application/json"},
     b'{"pose_w": [3.0, 10.0, ' + b"9" * 400 + b"]}"),
    ("pose_strings", "/place", {"Content-Type": "application/json"},
     b'{"pose_w": ["3", "10", "0"]}'),
    ("deep_json", "/place", {"Content-Type": "application/json"}, b"[" * 2000 + b"]" * 2000),
    ("body_64_kb", "/place", {"Content-Type": "application/json"}, b" " * 65536),
)
"""(name, path, headers, body) of each hostile POST to the control endpoint."""


def measure(seed: int = 0) -> dict[str, object]:
    """Run the benchmark once (see the module docstring); its figures as JSON-ready data.

    Args:
        seed: seeds the hostile ARIA batch.
    """
    with tempfile.TemporaryDirectory(prefix="vmnav-hostile-sim-") as folder:
        server = VmnavProcess(["sim", "serve", "--aria", "tcp:0", "--control", "http:0",
                               "--duration", "600"], Path(folder) / "serve.out", 10.0)
        try:
            aria_port, control_url = _wait_for_ports(server)
            aria = _aria_figures(aria_port, seed)
            control = _control_figures(control_url, server.process.pid)
            alive = server.process.poll() is None
        finally:
            code = server.stop()
        closing = server.output()
    counts = re.search(r"(\d+) refused, \d+ bad checksums, (\d+) handler errors", closing)
    result: dict[str, object] = {
        "seed": seed,
        **aria,
        "aria_server_alive_after_batch": alive,
        "aria_commands_refused": int(counts.group(1)) if counts else None,
        "aria_handler_errors": int(counts.group(2)) if counts else None,
        **control,
        "server_exit_code": code,
    }
    result["targets_met"] = bool(
        alive and code == 0
        and aria["aria_sips_in_1_s_after_batch"] >= SIPS_AFTER_MIN  # type: ignore[operator]
        and control["control_bad_requests_refused"] == control["control_bad_requests"]
        and control["control_truth_moved_by_bad_requests"] is False
        and control["control_extra_threads_with_idle_max"] <= EXTRA_THREADS_MAX  # type: ignore[operator]
        and control["control_probes_answered"] == PROBES
        and control["control_probe_latency_max_s"] <= PROBE_LATENCY_MAX_S  # type: ignore[operator]
    )
    return result


def _wait_for_ports(server: VmnavProcess) -> tuple[int, str]:
    """The ARIA port and the control URL the server printed."""
    limit = time.monotonic() + START_TIMEOUT_S
    while time.monotonic() < limit:
        out = server.output()
        aria = re.search(r"ARIA on tcp 127\.0\.0\.1:(\d+)", out)
        control = re.search(r"control on (http://\S+)", out)
        if aria and control:
            return int(aria.group(1)), control.group(1)
        if server.process.poll() is not None:
            break
        time.sleep(0.05)
    raise RuntimeError(f"vmnav sim serve did not start: {server.last_line()}")


# -- ARIA -------------------------------------------------------------------------------


class _AriaClient:
    """Our driver's sans-I/O client on a TCP socket, serviced by :meth:`service`."""

    def __init__(self, port: int) -> None:
        sock = socket.create_connection(("127.0.0.1", port), timeout=5.0)
        self.link = StreamLink.from_socket(sock, f"tcp:127.0.0.1:{port}")
        self.client = PioneerClient()
        self.clock = WallClock()
        self.client.start(self.clock.now_ns())
        self.sips = 0

    def service(self) -> None:
        """Read, run the timers, write; count SIPs."""
        now = self.clock.now_ns()
        self.client.receive_data(self.link.read_available(), now)
        deadline = self.client.get_timer()
        if deadline is not None and now >= deadline:
            self.client.handle_timer(now)
        self.link.write(self.client.data_to_send())
        while self.client.next_event() is not None:
            pass
        self.sips = self.client.counters.sips

    def run_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.service()
            time.sleep(_STEP_S)

    def connect(self) -> bool:
        """Service until the robot takes commands; whether it did within the patience."""
        end = time.monotonic() + 20.0
        while time.monotonic() < end and not self.client.accepts_commands:
            self.service()
            time.sleep(_STEP_S)
        return self.client.accepts_commands

    def close(self) -> None:
        self.link.close()


def _hostile_batch(seed: int) -> list[bytes]:
    """:data:`ARIA_PACKETS` random command packets, then the BATTEST one."""
    rng = random.Random(seed)
    ids = [int(c) for c in Command if c is not Command.CLOSE]
    ids += [i for i in range(256) if i not in {int(c) for c in Command}]
    packets = []
    for _ in range(ARIA_PACKETS):
        kind = rng.random()
        if kind < 0.6:
            value = rng.randint(-0xFFFF, 0xFFFF)
            arg = bytes((0x3B if value >= 0 else 0x1B,)) + abs(value).to_bytes(2, "little")
        elif kind < 0.7:
            arg = b""
        elif kind < 0.85:
            text = rng.randbytes(rng.randint(0, 40))
            arg = bytes((0x2B, len(text))) + text
        else:
            arg = rng.randbytes(rng.randint(1, 60))
        packets.append(encode_packet(rng.choice(ids), arg))
    return [*packets, BATTEST_25_6_V]


def _aria_figures(port: int, seed: int) -> dict[str, object]:
    host = _AriaClient(port)
    try:
        connected = host.connect()
        batch = _hostile_batch(seed)
        started = time.monotonic()
        lost = False
        for k in range(0, len(batch), _PACKETS_PER_STEP):
            try:
                host.link.write(b"".join(batch[k:k + _PACKETS_PER_STEP]))
                host.service()
            except LinkClosedError:
                lost = True
                break
            time.sleep(_STEP_S)
        batch_s = time.monotonic() - started
        before = host.sips
        if not lost:
            try:
                host.run_for(0.5)
            except LinkClosedError:
                lost = True
        sips_same_link = host.sips - before
        battery_v = host.client.status.battery_v
    finally:
        host.close()
    reconnected, sips_after = _fresh_client_sips(port)
    return {
        "aria_connected_before_batch": connected,
        "aria_packets_sent": len(batch),
        "aria_batch_s": round(batch_s, 3),
        "aria_link_closed_after_batch": lost,
        "aria_sips_in_0_5_s_after_batch_same_link": sips_same_link,
        "aria_battery_v_after_battest": battery_v,
        "aria_reconnected_after_batch": reconnected,
        "aria_sips_in_1_s_after_batch": sips_after,
    }


def _fresh_client_sips(port: int) -> tuple[bool, int]:
    """(whether a new client connects, the SIPs it gets in its first second)."""
    try:
        fresh = _AriaClient(port)
    except OSError:  # nobody listens any more: the server is gone
        return False, 0
    try:
        reconnected = fresh.connect()
        before = fresh.sips
        fresh.run_for(1.0)
        return reconnected, fresh.sips - before
    except LinkClosedError:
        return False, 0
    finally:
        fresh.close()


# -- the control endpoint -------------------------------------------------------------------


def _http(url: str, method: str, path: str, headers: dict[str, str] | None = None,
          body: bytes | None = None) -> tuple[int, dict[str, Any]]:
    """One request; (status, JSON reply) or (0, {}) when the connection broke."""
    host, port = url.removeprefix("http://").rsplit(":", 1)
    conn = http.client.HTTPConnection(host, int(port), timeout=10.0)
    try:
        conn.putrequest(method, path, skip_host="Host" in (headers or {}))
        for name, value in (headers or {}).items():
            conn.putheader(name, value)
        if body is not None:
            conn.putheader("Content-Length", str(len(body)))
        conn.endheaders()
        if body is not None:
            with contextlib.suppress(OSError):  # refused unread: the reply may be waiting
                conn.send(body)
        reply = conn.getresponse()
        data = reply.read()
        return reply.status, json.loads(data) if data else {}
    except (OSError, http.client.HTTPException, ValueError):
        return 0, {}
    finally:
        conn.close()


def _threads(pid: int) -> int:
    """The process's thread count, from ``/proc/PID/status``; -1 once it is gone."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return -1
    found = re.search(r"^Threads:\s+(\d+)", status, re.MULTILINE)
    return int(found.group(1)) if found else -1


def _open_idle(port: int, count: int) -> list[socket.socket]:
    """Up to ``count`` connections that will send nothing (fewer if refused)."""
    idle = []
    with contextlib.suppress(OSError):
        for _ in range(count):
            idle.append(socket.create_connection(("127.0.0.1", port), timeout=5.0))
    return idle


def _control_figures(url: str, pid: int) -> dict[str, object]:
    _, before = _http(url, "GET", "/truth")
    refused: dict[str, int] = {}
    for name, path, headers, body in BAD_REQUESTS:
        status, _ = _http(url, "POST", path, headers, body)
        refused[name] = status
    _, after = _http(url, "GET", "/truth")
    moved = before.get("pose_w") != after.get("pose_w")
    threads_before = _threads(pid)
    port = int(url.rsplit(":", 1)[1])
    idle = _open_idle(port, IDLE_CONNECTIONS)
    latencies, threads = [], [threads_before]
    try:
        time.sleep(0.5)  # the accept loop has taken them all
        for _ in range(PROBES):
            threads.append(_threads(pid))
            start = time.perf_counter()
            status, _ = _http(url, "GET", "/truth")
            if status == 200:
                latencies.append(time.perf_counter() - start)
            threads.append(_threads(pid))
            time.sleep(0.05)
    finally:
        for conn in idle:
            conn.close()
    return {
        "control_bad_requests": len(BAD_REQUESTS),
        "control_bad_requests_refused": sum(400 <= s < 500 for s in refused.values()),
        "control_bad_request_status": refused,
        "control_truth_moved_by_bad_requests": moved,
        "control_idle_connections": len(idle),
        "control_threads_before_idle": threads_before,
        "control_threads_with_idle_max": max(threads),
        "control_extra_threads_with_idle_max": max(threads) - threads_before,
        "control_probes": PROBES,
        "control_probes_answered": len(latencies),
        "control_probe_latency_median_s": (round(statistics.median(latencies), 4)
                                           if latencies else None),
        "control_probe_latency_max_s": round(max(latencies), 4) if latencies else None,
    }
