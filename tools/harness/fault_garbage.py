"""Issue 8's garbage at every boundary: fault cases (:data:`tools.bench.faults.CASES`).

The ARIA cases run the robot's :class:`~robot.pioneer.driver.PioneerDriver` in this
process against the simulator side over TCP, so that both ends' counters can be read;
the MAVLink, memory and frame cases run ``vmnav robot``. Random bytes come from
generators seeded per case: every run sends the same garbage.
"""

from __future__ import annotations

import shutil
import socket
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from robot.config import PioneerDriverConfig, TeleopConfig
from robot.pioneer.driver import PioneerDriver
from robot.pioneer.status import LinkState
from shared.clock import NS_PER_S, WallClock
from shared.mavlink.dialect import mavlink
from shared.mavlink.modes import Mode
from tools.harness.fault_cases import (
    DRIVEN_BEFORE_FAULT_M,
    GOAL_TOLERANCE_M,
    HOLD_AFTER_NS,
    REACH_S,
)
from tools.harness.hil_rig import FaultCaseError, SimSide, Taught, expect, open_hil, wait_until

#: What the ARIA cases drive at, m/s.
DRIVE_M_S = 0.2
#: Driver connect limit, s.
CONNECT_S = 10.0
#: The command watchdog of :func:`driving_driver`, which commands once: longer than a case, ns.
ONE_COMMAND_NS = 600 * NS_PER_S
#: Undecodable frames sent to the robot: 2 s of the simulator's 15 frames/s.
BAD_FRAMES = 30


def random_bytes(rng: np.random.Generator, count: int) -> bytes:
    """``count`` uniformly random bytes."""
    return rng.integers(0, 256, count, dtype=np.uint8).tobytes()


def driving_driver(side: SimSide) -> PioneerDriver:
    """A driver on ``side``'s ARIA port, connected and driving at :data:`DRIVE_M_S`.

    It drives on one command (no control loop repeats it), so its command watchdog is
    set past any case's length.

    Raises:
        FaultCaseError: it did not connect within :data:`CONNECT_S`.
    """
    config = PioneerDriverConfig(url=side.aria_url, command_timeout_ns=ONE_COMMAND_NS)
    driver = PioneerDriver.from_config(config, WallClock())
    driver.start_thread()
    if not driver.wait_connected(round(CONNECT_S * NS_PER_S)):
        link = driver.status().link
        driver.close()
        raise FaultCaseError(f"the driver did not connect to {side.aria_url}: {link.value}")
    driver.command(DRIVE_M_S, 0.0)
    return driver


def garbage_aria_server(taught: Taught, folder: Path) -> None:
    """A TCP client sends 64 KiB of random bytes to the emulated Pioneer and leaves; the
    robot's driver then connects and drives; a second client sending garbage meanwhile is
    refused and the driver's session goes on untouched."""
    rng = np.random.default_rng(81)
    with SimSide(taught.world_file) as side:
        port = int(side.aria_url.rpartition(":")[2])
        with socket.create_connection(("127.0.0.1", port), timeout=5.0) as client:
            client.sendall(random_bytes(rng, 64 * 1024))
            wait_until(lambda: side.emulator.stats.skipped_bytes > 0, 5.0,
                       "the emulator reading the garbage")
        with driving_driver(side) as driver:
            with socket.create_connection(("127.0.0.1", port), timeout=5.0) as intruder:
                intruder.sendall(random_bytes(rng, 4096))
                wait_until(lambda: side.server.refused_clients == 1, 5.0,
                           "the server refusing a second client")
            wait_until(lambda: side.truth.moved_m() > 0.2, 5.0, "driving 0.2 m")
            counters = driver.counters()
            expect(counters.connects == 1 and counters.link_losses == 0,
                   f"the driver's session was disturbed: {counters}")
        stats = side.emulator.stats
        expect(side.running, "the simulation loop died")
    expect(stats.skipped_bytes > 60_000,
           f"the emulator skipped only {stats.skipped_bytes} garbage bytes")


def garbage_aria_client(taught: Taught, folder: Path) -> None:
    """The emulated Pioneer's end sends random bytes to the driver: 2 KiB before the
    handshake, then five bursts of 2 KiB while it drives; the driver resyncs on the
    packets between, keeps its session (or reconnects) and the robot keeps driving."""
    rng = np.random.default_rng(82)
    with SimSide(taught.world_file) as side:
        side.server.inject(random_bytes(rng, 2048))  # waits for the driver's SYNC0
        with driving_driver(side) as driver:
            clock = WallClock()
            for _ in range(5):
                side.server.inject(random_bytes(rng, 2048))
                clock.sleep_until_ns(clock.now_ns() + 300_000_000)
            sips = driver.counters().sips
            wait_until(lambda: driver.counters().sips >= sips + 5, 2.0, "5 SIPs after the noise")
            counters = driver.counters()
            expect(counters.skipped_bytes + counters.bad_checksums > 10_000,
                   f"the driver saw little of the garbage: {counters}")
            expect(driver.status().link is LinkState.CONNECTED,
                   f"the driver is {driver.status().link.value} after the garbage")
            now_ns = side.now_ns
            speed, _ = side.truth.motion(now_ns - 300_000_000, now_ns)
            expect(speed > DRIVE_M_S / 2, f"the robot slowed to {speed:.3f} m/s")
        expect(side.running, "the simulation loop died")


def garbage_mavlink(taught: Taught, folder: Path) -> None:
    """20 real packets with a payload byte flipped, then 300 random datagrams, reach the
    robot's MAVLink endpoint from another socket: the robot counts them in SYS_STATUS
    ``errors_comm`` and the ground station's link keeps working."""
    rng = np.random.default_rng(83)
    with open_hil(taught, folder) as hil:
        peer = hil.vehicle.peer
        if peer is None:
            raise FaultCaseError("the robot's UDP address is unknown")
        request = hil.station.codec.pack(mavlink.MAVLink_command_long_message(
            hil.vehicle.system_id, 1, mavlink.MAV_CMD_DO_SET_MODE, 0,
            mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, int(Mode.MANUAL), 0, 0, 0, 0, 0))
        flipped = request[:-3] + bytes([request[-3] ^ 0xFF]) + request[-2:]
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as stranger:
            for _ in range(20):
                stranger.sendto(flipped, peer)
            for _ in range(300):
                stranger.sendto(random_bytes(rng, int(rng.integers(1, 400))), peer)

        def errors_comm() -> int:
            status = hil.vehicle.telemetry.get("SYS_STATUS")
            return -1 if status is None else int(status.errors_comm)

        expect(hil.station.run_until(lambda: errors_comm() >= 20, 5 * NS_PER_S),
               f"SYS_STATUS errors_comm {errors_comm()}: the 20 corrupt packets uncounted")
        expect(hil.vehicle.mode is Mode.HOLD, f"mode {hil.vehicle.mode_name} after the garbage")
        hil.station.set_mode(Mode.MANUAL)
        hil.station.set_mode(Mode.HOLD)
        hil.run_until(lambda: hil.vehicle.mode is Mode.HOLD, 3.0, "HOLD in the HEARTBEAT")
        expect(hil.robot.process.poll() is None, f"vmnav robot ended: {hil.robot.last_line()}")


def corrupt_memory(taught: Taught, folder: Path) -> None:
    """``vmnav robot`` starts on a memory with a damaged file (manifest cut short or
    deleted, a key image or a feature file overwritten) or a damaged parameter file: it
    exits 1 with one line naming the file, and no stored file changes."""
    rng = np.random.default_rng(84)
    damages: list[tuple[str, Callable[[bytes], bytes | None]]] = [  # None: deleted
        ("memory/manifest.json", lambda data: data[: len(data) // 2]),
        ("memory/images/3.png", lambda data: random_bytes(rng, len(data))),
        ("memory/features/5.npz", lambda data: data[:100]),
        ("state/params.parm", lambda data: random_bytes(rng, 64)),
        ("memory/manifest.json", lambda data: None),
    ]
    with SimSide(taught.world_file) as side:
        for number, (name, damage) in enumerate(damages):
            case = folder / f"damage-{number}"
            shutil.copytree(taught.memory_dir, case / "memory")
            (case / "state").mkdir()
            target = case / name
            damaged = damage(target.read_bytes() if target.exists() else b"")
            if damaged is None:
                target.unlink()
            else:
                target.write_bytes(damaged)
            named = f"{target.parent}: {target.name} missing" if damaged is None else str(target)
            before = {p: p.read_bytes() for p in sorted(case.rglob("*")) if p.is_file()}
            argv = ["--aria", side.aria_url, "--camera", side.camera.stream_url, "--mavlink",
                    "udpout:127.0.0.1:9", "--memory", str(case / "memory"),
                    "--state", str(case / "state"), "--no-log"]
            done = subprocess.run([sys.executable, "-m", "tools.cli", "robot", *argv],
                                  capture_output=True, text=True, timeout=60)
            lines = done.stderr.strip().splitlines()
            last = lines[-1] if lines else ""
            expect(done.returncode == 1 and last.startswith("vmnav robot: error: ")
                   and named in last and "Traceback" not in done.stderr,
                   f"{name} damaged: exit {done.returncode}, last line {last!r}")
            after = {p: p.read_bytes() for p in sorted(case.rglob("*")) if p.is_file()}
            expect(after == before, f"{name} damaged: the robot changed "
                                    f"{sorted(str(p) for p in after.keys() ^ before.keys())}")


def bad_frames(taught: Taught, folder: Path) -> None:
    """:data:`BAD_FRAMES` undecodable frames mid-route: the camera source skips them (and
    reopens the stream after 5 in a row), the robot stops while no good frame comes, says
    so, and carries on to its goal."""
    goal = taught.keyframe_ids[4]
    with open_hil(taught, folder) as hil:
        hil.start_goal(goal, DRIVEN_BEFORE_FAULT_M)
        bad_ns, since = hil.sim.now_ns, len(hil.notices())
        hil.sim.camera.corrupt(BAD_FRAMES)
        hil.run_until(lambda: hil.notice("camera back", since) is not None, 15.0,
                      "the robot's 'camera back'")
        expect(hil.sim.camera.stats().corrupted == BAD_FRAMES,
               f"{hil.sim.camera.stats().corrupted} of {BAD_FRAMES} bad frames sent")
        bad_length_ns = BAD_FRAMES * hil.sim.sim.config.frame_period_ns
        hil.wait_sim(bad_ns + bad_length_ns)
        moving = hil.sim.truth.still(bad_ns + TeleopConfig().frame_timeout_ns + HOLD_AFTER_NS,
                                     bad_ns + bad_length_ns)
        expect(moving is None, f"the base did not hold without good frames: {moving}")
        expect(hil.notice("camera stalled: stopped", since) is not None,
               f"no 'camera stalled' notice: {hil.notices()}")
        hil.reach(taught, goal, REACH_S, GOAL_TOLERANCE_M)
        expect(hil.robot.process.poll() is None, f"vmnav robot ended: {hil.robot.last_line()}")

