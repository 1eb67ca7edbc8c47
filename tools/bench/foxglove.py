"""The live topics' cost on the robot's loop (``vmnav bench foxglove``, issue 18).

A loop paced by the wall clock at a camera's rate hands each frame (800x600 grey:
:func:`tools.bench.log.synthetic_frames`) and a following mission cycle (150 matched
corners) to a :class:`robot.foxglove_bridge.FoxgloveBridge`, as the robot process does,
in three phases: no viewer; a viewer subscribed to every topic and reading
(:mod:`tools.harness.foxglove_client`, in a thread of this process); and a viewer
subscribed that never reads (a stalled link: the server drops its oldest messages).
Per phase: the loop's time in the bridge's calls per frame (p50, p99, max, microseconds;
rule 1 of :mod:`robot.foxglove_bridge` says the loop never waits), the process's CPU per
wall second (the bridge's thread, the SDK's server, and in the reading phase the viewer's
decoding too), and what the viewer received per second. ``no_bridge`` times the same
calls on an object that does nothing: what the timing itself costs, a frame after a sleep.
"""

from __future__ import annotations

import argparse
import json
import statistics
import threading
import time
from typing import Any

import numpy as np

from robot.config import FoxgloveConfig
from robot.control_law import Twist
from robot.follower import FollowStep
from robot.foxglove_bridge import CHANNELS, FoxgloveBridge
from robot.mission import MissionState
from robot.mission_run import CycleRecord
from robot.vehicle.app_port import VehicleTelemetry
from shared.clock import NS_PER_S, WallClock
from shared.config import CameraMountConfig
from shared.errors import InputError
from shared.interfaces import BaseState
from shared.logs import topics
from shared.mavlink.modes import Mode
from tools.bench.log import synthetic_frames
from tools.harness.foxglove_client import FoxgloveClient, Message, by_topic

#: Matched corners of each cycle (the field log bench's count).
CORNERS = 150
PHASES = ("no_viewer", "viewer", "stalled_viewer")


class _NoBridge:
    """The bridge's loop-side calls, doing nothing (the timing's own cost)."""

    def cycle(self, *args: object) -> None:
        """Nothing."""

    def offer(self, *args: object) -> None:
        """Nothing."""


def cycle_record(t_ns: int, i: int, rng: np.random.Generator) -> CycleRecord:
    """A following cycle at ``t_ns``, its numbers moving with ``i``."""
    base = BaseState((0.01 * i, 0.0, 0.001 * i), 0.01 * i, False, False, 12.5, True)
    follow = FollowStep(t_ns=t_ns, target_index=1, twist=Twist(0.25, -0.01 * (i % 10)),
                        vision=None, corners_xy=rng.uniform(0, 600, (CORNERS, 2)),
                        y_m=0.001 * (i % 50), theta_rad=-0.0005 * (i % 50), s_m=-0.3,
                        switch=None, lost=None)
    return CycleRecord(t_ns=t_ns, state=MissionState.FOLLOWING, base=base, follow=follow,
                       localization=None, route=(4, 5, 6), compute_ns=30_000_000)


def run_loop(bridge: FoxgloveBridge | _NoBridge, seconds: float, rate_hz: float,
             rng: np.random.Generator) -> dict[str, Any]:
    """Feed the bridge for ``seconds`` at ``rate_hz``; the loop's cost per frame and CPU."""
    frames = synthetic_frames(8, rng)
    clock = WallClock()
    period_ns = round(NS_PER_S / rate_hz)
    costs_ns: list[int] = []
    start_ns = deadline_ns = clock.now_ns()
    cpu_start_s = time.process_time()
    i = 0
    while clock.now_ns() - start_ns < seconds * NS_PER_S:
        t_ns = clock.now_ns()
        record = cycle_record(t_ns, i, rng)
        image = frames[i % len(frames)]
        telemetry = VehicleTelemetry(mode=Mode.AUTO, odom_pose=record.base.odom_pose,
                                     velocity=(0.25, -0.01 * (i % 10)))
        started = time.perf_counter_ns()
        bridge.cycle(record, image, (4, 6))  # what the runtime's step and the loop call
        bridge.offer(t_ns, image, telemetry)
        costs_ns.append(time.perf_counter_ns() - started)
        i += 1
        deadline_ns += period_ns
        clock.sleep_until_ns(deadline_ns)
    wall_s = (clock.now_ns() - start_ns) / NS_PER_S
    costs_us = sorted(c / 1e3 for c in costs_ns)
    return {"frames": i, "loop_us_p50": round(statistics.median(costs_us), 1),
            "loop_us_p99": round(costs_us[int(0.99 * (len(costs_us) - 1))], 1),
            "loop_us_max": round(costs_us[-1], 1),
            "process_cpu_core_fraction": round((time.process_time() - cpu_start_s) / wall_s, 3),
            "wall_s": round(wall_s, 2)}


def phase(name: str, args: argparse.Namespace, rng: np.random.Generator) -> dict[str, Any]:
    """One phase (module docstring) on a bridge of its own."""
    with FoxgloveBridge("127.0.0.1", 0, FoxgloveConfig(), CameraMountConfig(),
                        unix_offset_ns=0, where="bench") as bridge:
        if name == "no_viewer":
            return run_loop(bridge, args.seconds, args.rate_hz, rng)
        with FoxgloveClient(bridge.url) as viewer:
            viewer.subscribe(CHANNELS)
            if name == "stalled_viewer":
                return {**run_loop(bridge, args.seconds, args.rate_hz, rng),
                        "queue_dropped": bridge.dropped}
            received: list[Message] = []
            stop = threading.Event()
            reader = threading.Thread(target=viewer.receive_until, daemon=True, args=(
                lambda _: stop.is_set(), args.seconds + 60.0, received))
            reader.start()
            result = run_loop(bridge, args.seconds, args.rate_hz, rng)
            stop.set()
            reader.join(10.0)
        per_s = {topic: round(len(by_topic(received, topic)) / result["wall_s"], 1)
                 for topic in (topics.CAMERA_IMAGE, topics.SERVO_STATE, topics.TF)}
        return {**result, "received_per_s": per_s, "queue_dropped": bridge.dropped}


def run(args: argparse.Namespace) -> int:
    """Run the three phases; print their JSON."""
    if not (args.seconds > 0 and 1 <= args.rate_hz <= 200):
        raise InputError("--seconds/--rate-hz", f"need seconds > 0 and a rate of 1-200 Hz, got "
                                                f"{args.seconds} s, {args.rate_hz} Hz")
    rng = np.random.default_rng(0)
    result = {"rate_hz": args.rate_hz, "frame_shape": [600, 800],
              "image_rate_hz": NS_PER_S / FoxgloveConfig().frame_period_ns,
              "no_bridge": run_loop(_NoBridge(), args.seconds, args.rate_hz, rng),
              "phases": {name: phase(name, args, rng) for name in PHASES}}
    result["loop_us_p99_worst"] = max(p["loop_us_p99"] for p in result["phases"].values())
    print(json.dumps(result, indent=2))
    return 0
