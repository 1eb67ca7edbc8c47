"""Issue 15, items 6 and 7, measured on the real thing: a MAVLink flood and hostile FTP peers.

:func:`measure` runs two parts, about ``seconds`` + 40 s on an idle machine (the robot's
start, the flood, 65,025 FTP peers; three times that on a loaded one):

1. **Flood.** ``vmnav robot`` (a child process, listening on a loopback port, signed with
   a fresh key, its field log on) drives the simulator's emulated Pioneer and reads its
   camera (:class:`tools.harness.hil_rig.SimSide`, in this process); our
   :class:`~ground.station.GroundStation`, with the key, talks to it. Once the robot
   answers, ``flooders`` child processes (this module run as ``python -m
   tools.bench.hostile_traffic --flood PORT``) send the robot's port datagrams as fast
   as they can for ``seconds``: random bytes, valid unsigned packets and packets
   signed with a wrong key (system 66, so that what the robot logs from them can be
   told from the station's). Figures: the robot's HEARTBEAT rate at the station and
   the station's at the robot (the HEARTBEATs the robot's field log accepted in the
   window), whether the robot declared the ground lost (its STATUSTEXT), the
   datagrams sent, and the bytes the field log holds because of rejected traffic
   (the JSON of MAVLink messages logged from system 66, and the rejection counts'
   lines).
2. **FTP.** Our :class:`~shared.mavlink.ftp.vehicle.FtpServer` over the robot's
   :class:`~robot.vehicle.ftp_memory.MemoryFileSystem`: 65,025 distinct sender ids
   (every system 1..255 x component 1..255) each open a file and burst-read it; how
   much this process's resident memory grew, then the reply packets that one request
   gets: from a stranger aimed at another peer's session, and from the owner (a burst).

Targets (issue 15, "Numbers"): >= 0.9 Hz of HEARTBEATs both ways, no false failsafe,
< 1 MB of log from rejected traffic, an FTP cache < 10 MB, one reply to a stranger's
request.
"""

from __future__ import annotations

import argparse
import itertools
import os
import select
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import numpy as np

from ground.station import GroundStation
from robot.vehicle.ftp_memory import MemoryFileSystem
from shared.clock import NS_PER_S, WallClock
from shared.config import FtpConfig
from shared.logs import topics
from shared.logs.messages import encode_json
from shared.logs.reader import read_messages
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.ftp.payload import FtpPayload, Opcode
from shared.mavlink.ftp.vehicle import FtpServer
from shared.mavlink.signing import configure_signing, key_from_passphrase
from tools.harness.hil_rig import Hil, SimSide
from tools.harness.vmnav_process import VmnavProcess

#: Default flood length, s (the issue's).
FLOOD_S = 20.0
#: The flooders' MAVLink system id (the station is 255).
FLOODER_SYSTEM = 66
#: Distinct datagrams each flooder cycles through.
FLOOD_VARIETY = 1024
#: How long a flooder may take to start, s.
FLOODER_START_S = 60.0
#: The issue's number of FTP peers: every system id x component id 1..255.
FTP_PEERS = 255 * 255
#: Targets (issue 15).
MIN_HEARTBEAT_HZ = 0.9
MAX_REJECTED_LOG_MB = 1.0
MAX_FTP_CACHE_MB = 10.0
_MB = 1e6


def flood_datagrams(seed: int, count: int = FLOOD_VARIETY) -> list[bytes]:
    """``count`` hostile datagrams: a third random bytes (10..60), a third valid unsigned
    HEARTBEAT / COMMAND_LONG / MANUAL_CONTROL of :data:`FLOODER_SYSTEM`, a third the same
    signed with a wrong key."""
    rng = np.random.default_rng(seed)
    unsigned = make_codec(FLOODER_SYSTEM, 1)
    wrong_key = make_codec(FLOODER_SYSTEM, 1)
    configure_signing(wrong_key, key_from_passphrase("not the key"), 3, 1 << 40)
    messages = (mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS,
                                                  mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 4, 3),
                mavlink.MAVLink_command_long_message(1, 1, mavlink.MAV_CMD_COMPONENT_ARM_DISARM,
                                                     0, 1, 0, 0, 0, 0, 0, 0),
                mavlink.MAVLink_manual_control_message(1, 1000, 0, 0, 0, 0))
    out = []
    for i in range(count):
        kind = i % 3
        if kind == 0:
            out.append(rng.integers(0, 256, int(rng.integers(10, 61)), dtype=np.uint8).tobytes())
        else:
            out.append((unsigned if kind == 1 else wrong_key).pack(messages[i % len(messages)]))
    return out


def run_flooder(port: int, seconds: float, seed: int) -> int:
    """Print ``ready``, then send :func:`flood_datagrams` to 127.0.0.1:``port`` as fast as
    possible for ``seconds``; the number of datagrams the kernel took."""
    datagrams = flood_datagrams(seed)
    print("ready", flush=True)
    sent = 0
    end = time.monotonic() + seconds
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        target = ("127.0.0.1", port)
        for batch in itertools.count():
            if time.monotonic() >= end:
                break
            for data in datagrams[(batch * 64) % len(datagrams):][:64]:
                try:
                    sock.sendto(data, target)
                    sent += 1
                except OSError:  # loopback buffer full: a flood loses datagrams too
                    pass
    return sent


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@contextmanager
def _flooders(port: int, seconds: float, seed: int,
              count: int) -> Iterator[list[subprocess.Popen[str]]]:
    """``count`` flooder processes aimed at ``port`` (starting: :func:`_ready` says when they
    flood); killed on exit if still running."""
    with ExitStack() as stack:
        procs = []
        for n in range(count):
            proc = subprocess.Popen(
                [sys.executable, "-m", "tools.bench.hostile_traffic", "--flood", str(port),
                 "--seconds", str(seconds), "--seed", str(seed + n)],
                stdout=subprocess.PIPE, text=True)
            stack.callback(proc.kill)
            procs.append(proc)
        yield procs


def _ready(procs: list[subprocess.Popen[str]], started: set[int]) -> bool:
    """Whether every flooder printed ``ready`` (the pids of those that did go in
    ``started``), without blocking.

    Raises:
        RuntimeError: a flooder ended before it was ready.
    """
    for proc in procs:
        if proc.pid in started:
            continue
        assert proc.stdout is not None
        if select.select([proc.stdout], [], [], 0)[0]:
            if proc.stdout.readline().strip() != "ready":
                raise RuntimeError(f"flooder {proc.args} did not start")
            started.add(proc.pid)
    return len(started) == len(procs)


def _rejected_log_bytes(files: list[Path]) -> int:
    """Bytes of JSON the field log holds because of rejected traffic: MAVLink logged from
    :data:`FLOODER_SYSTEM` (raw and decoded) and the rejection counts' lines."""
    rejected, flooded = 0, set()
    messages = [m for path in files for m in read_messages(path)]
    for m in messages:
        if (m.topic == topics.MAVLINK_RAW and m.data["direction"] == "in"
                and m.data["sysid"] == FLOODER_SYSTEM):
            rejected += len(encode_json(m.data))
            flooded.add((m.clock_ns, m.data["name"]))
        elif m.topic == topics.LOG and m.data["name"] == "robot.vehicle":
            rejected += len(encode_json(m.data))
    return rejected + sum(len(encode_json(m.data)) for m in messages
                          if m.topic.startswith("/mavlink/in/")
                          and (m.clock_ns, m.topic.rsplit("/", 1)[1]) in flooded)


def _heartbeats_in(files: list[Path], t0_ns: int, t1_ns: int) -> int:
    return sum(1 for path in files for m in read_messages(path, [topics.MAVLINK_RAW])
               if m.data["direction"] == "in" and m.data["name"] == "HEARTBEAT"
               and m.data["sysid"] == 255 and t0_ns <= m.clock_ns <= t1_ns)


def measure_flood(seed: int, seconds: float, flooders: int) -> dict[str, float | bool]:
    """Part 1 (module docstring)."""
    clock = WallClock()
    with tempfile.TemporaryDirectory(prefix="vmnav-hostile-") as tmp:
        folder = Path(tmp)
        key = np.random.default_rng(seed).integers(0, 256, 32, dtype=np.uint8).tobytes()
        (folder / "key").write_bytes(key)
        port = _free_port()
        with ExitStack() as stack:
            sim = stack.enter_context(SimSide(Path("lab"), seed=seed + 1))
            station = stack.enter_context(GroundStation.open(
                f"udpout:127.0.0.1:{port}", clock, key=key,
                unix_offset_ns=time.time_ns() - clock.now_ns()))
            argv = ["robot", "--aria", sim.aria_url, "--camera", sim.camera.stream_url,
                    "--mavlink", f"udpin:127.0.0.1:{port}", "--key", str(folder / "key"),
                    "--memory", str(folder / "memory"), "--state", str(folder / "state"),
                    "--log", str(folder / "logs")]
            robot = VmnavProcess(argv, folder / "robot.out", 15.0)
            stack.callback(robot.stop)
            hil = Hil(sim, station, robot, folder)
            hil.wait_robot()
            beats: list[int] = []
            station.listeners.append(lambda vehicle, msg: beats.append(clock.now_ns())
                                     if msg.get_type() == "HEARTBEAT" else None)
            notices_before = len(hil.notices())
            with _flooders(port, seconds, seed, flooders) as procs:
                started: set[int] = set()  # the station beats on while they start
                if not station.run_until(lambda: _ready(procs, started),
                                         round(FLOODER_START_S * NS_PER_S)):
                    raise RuntimeError(f"flooders not ready in {FLOODER_START_S} s")
                station.service()  # what came while they started is before the window
                t0_ns = clock.now_ns()
                station.run_until(lambda: False, round(seconds * NS_PER_S))
                t1_ns = clock.now_ns()
                sent = sum(int(p.communicate(timeout=FLOODER_START_S)[0]) for p in procs)
            station.run_until(lambda: False, NS_PER_S)  # the robot's last words on the flood
            lost = [n for n in hil.notices()[notices_before:] if "GCS heartbeat lost" in n]
            robot.stop()
            files = sorted((folder / "logs").glob("robot-*.mcap"))
            rejected_bytes = _rejected_log_bytes(files)
            robot_beats = _heartbeats_in(files, t0_ns, t1_ns)
        window_s = (t1_ns - t0_ns) / NS_PER_S
        station_hz = sum(1 for t in beats if t0_ns <= t <= t1_ns) / window_s
        return {
            "flood_s": round(window_s, 2),
            "flooders": flooders,
            "flood_datagrams_per_s": round(sent / window_s),
            "heartbeat_hz_at_station": round(station_hz, 3),
            "heartbeat_hz_at_robot": round(robot_beats / window_s, 3),
            "false_gcs_failsafe": bool(lost),
            "log_growth_rejected_mb": round(rejected_bytes / _MB, 4),
        }


def _rss_bytes() -> int:
    """This process's resident memory now, bytes (Linux)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def measure_ftp(seed: int, peers: int = FTP_PEERS) -> dict[str, float]:
    """Part 2 (module docstring)."""
    with tempfile.TemporaryDirectory(prefix="vmnav-hostile-ftp-") as tmp:
        fs = MemoryFileSystem(Path(tmp) / "memory", Path(tmp) / "upload")
        data = np.random.default_rng(seed).integers(0, 256, 20_000, dtype=np.uint8).tobytes()
        (fs.upload_dir / "photo.png").write_bytes(data)
        path = b"/upload/photo.png"
        server = FtpServer(fs, FtpConfig(session_timeout_ns=1))  # a peer's session ends
        open_ro = FtpPayload(1, 7, Opcode.OPEN_FILE_RO, len(path), data=path).to_bytes()
        burst = FtpPayload(2, 7, Opcode.BURST_READ_FILE, 239).to_bytes()
        base = _rss_bytes()
        for n in range(peers):
            peer = (n // 255 + 1, n % 255 + 1)
            server.handle(open_ro, 2 * n, peer)
            server.handle(burst, 2 * n, peer)
        cache_bytes = _rss_bytes() - base
        owner, stranger, now_ns = (255, 190), (66, 66), 2 * peers
        server.handle(open_ro, now_ns, owner)
        aimed = (burst, FtpPayload(3, 7, Opcode.READ_FILE, 239).to_bytes(),
                 FtpPayload(4, 7, Opcode.TERMINATE_SESSION).to_bytes())
        stranger_replies = max(len(server.handle(request, now_ns, stranger))
                               for request in aimed)
        owner_replies = len(server.handle(burst, now_ns, owner))
        server.close()
    return {"ftp_peers": peers, "ftp_cache_mb": round(cache_bytes / _MB, 3),
            "ftp_replies_per_stranger_request": stranger_replies,
            "ftp_replies_per_owner_burst": owner_replies}


def measure(seed: int = 0, seconds: float = FLOOD_S, flooders: int = 1) -> dict[str, object]:
    """Both parts (module docstring): about ``seconds`` + 40 s on an idle machine.

    Targets met: >= :data:`MIN_HEARTBEAT_HZ` both ways, no false failsafe, under
    :data:`MAX_REJECTED_LOG_MB` of log from rejected traffic and
    :data:`MAX_FTP_CACHE_MB` of FTP cache, one reply to a stranger's request.

    Args:
        seed: the flood's bytes, the key, the simulation and the FTP file.
        seconds: how long the flood lasts, s.
        flooders: processes flooding at once.

    Returns:
        The figures (JSON-able) and ``targets_met``.
    """
    flood = measure_flood(seed, seconds, flooders)
    ftp = measure_ftp(seed)
    met = (flood["heartbeat_hz_at_station"] >= MIN_HEARTBEAT_HZ
           and flood["heartbeat_hz_at_robot"] >= MIN_HEARTBEAT_HZ
           and not flood["false_gcs_failsafe"]
           and flood["log_growth_rejected_mb"] < MAX_REJECTED_LOG_MB
           and ftp["ftp_cache_mb"] < MAX_FTP_CACHE_MB
           and ftp["ftp_replies_per_stranger_request"] == 1)
    return {**flood, **ftp, "targets_met": bool(met)}


def main(argv: list[str] | None = None) -> int:
    """The flooder process: ``--flood PORT --seconds S --seed N``; prints what it sent."""
    parser = argparse.ArgumentParser(prog="python -m tools.bench.hostile_traffic")
    parser.add_argument("--flood", type=int, required=True, metavar="PORT")
    parser.add_argument("--seconds", type=float, default=FLOOD_S)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    print(run_flooder(args.flood, args.seconds, args.seed), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
