"""``vmnav bench link``: goal dispatch latency, and one ground station's CPU for a fleet.

Everything runs on loopback UDP with the real parts: this process is the ground
station (:class:`~ground.station.GroundStation`, listening on an ephemeral port,
tracking vehicles in its :class:`~ground.fleet.Fleet`); the vehicles are real
:class:`~robot.vehicle.endpoint.VehicleEndpoint` s, system ids 1..N, spread over
one or more vehicles processes (``tools.bench.link_vehicles``), each vehicle streaming
its default telemetry from its own socket and I/O thread. Their application comes
from an :data:`~tools.bench.link_vehicles.AppFactory` (today the
:class:`~tools.bench.link_load.LinkLoadApp` load generator).

Phases:

1. Wait until the station has heard every vehicle.
2. Dispatch: ``dispatches`` times, upload a one-goal mission (a random key image)
   to vehicle 1 with :meth:`GroundStation.upload_goals` and time it from the call to
   the final MISSION_ACK; a random pause of up to two vehicle service periods
   between uploads keeps them from locking to the vehicle's I/O rhythm. The other
   vehicles stream all the while.
3. Start a long mission on every vehicle (upload + MISSION_START) and wait until
   each reports FOLLOWING, so every telemetry stream runs (NAV_CONTROLLER_OUTPUT and
   the servo state only flow while following).
4. Window: the station services the link for ``window_s``; its process CPU time
   (this process only: the vehicles run elsewhere) over the wall time is the figure,
   and every message received is counted per vehicle and type.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import time
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ground.fleet import VehicleState
from ground.station import GroundError, GroundStation
from robot.vehicle.telemetry import default_periods_ns
from shared.clock import NS_PER_S, WallClock
from shared.config import MavlinkConfig
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.goal import Goal
from tools.bench.link_load import make_load_app
from tools.bench.link_vehicles import AppFactory, VehicleProcesses, factory_name
from tools.bench.targets import target_summary

#: How long to wait for every vehicle to be heard, or to report FOLLOWING, s.
WAIT_S = 10.0


@dataclass(frozen=True, slots=True)
class LinkBenchPlan:
    """What ``vmnav bench link`` runs.

    Attributes:
        vehicles: simulated vehicles, system ids 1..N (1..254).
        window_s: the measured window with every vehicle following, s.
        dispatches: timed goal uploads to vehicle 1.
        vehicle_processes: processes the vehicles are spread over.
        key_images: key image ids 0..K-1 each vehicle knows (goals are drawn from them).
        seed: of the dispatched goals and the pauses between them.
    """

    vehicles: int = 20
    window_s: float = 10.0
    dispatches: int = 200
    vehicle_processes: int = 2
    key_images: int = 100
    seed: int = 0


def bench_link(plan: LinkBenchPlan, app_factory: AppFactory = make_load_app) -> dict[str, Any]:
    """Run the phases of the module docstring.

    Args:
        plan: sizes.
        app_factory: makes each vehicle's application in the vehicles processes (a
            module-level function, :func:`tools.bench.link_vehicles.factory_name`).

    Returns:
        JSON-ready figures: ``dispatch_ack_ms_p50/p95/max``,
        ``ground_cpu_fraction_<N>_vehicles``, messages per vehicle, and the targets.

    Raises:
        GroundError: a vehicle was not heard, refused a mission, or did not start
            following.
        RuntimeError: a vehicles process failed to start (its traceback is on stderr).
    """
    clock = WallClock()  # real time: the figures are wall and CPU time
    ids = list(range(1, plan.vehicles + 1))
    keys = list(range(plan.key_images))
    rng = random.Random(plan.seed)
    with GroundStation.open("udpin:127.0.0.1:0", clock) as station, \
            VehicleProcesses(ids, plan.vehicle_processes, station.link.local_port,
                             plan.key_images, app_factory):
        _wait(station, lambda: len(station.fleet.vehicles) >= plan.vehicles,
              lambda: f"heard {len(station.fleet.vehicles)} of {plan.vehicles} vehicles")
        dispatch_ms = _dispatch(station, ids[0], plan.dispatches, keys, rng)
        for system_id in ids:
            _aim(station, system_id)
            station.upload_goals([Goal(keys[-1])])
            station.start_mission()
        _wait(station, lambda: _following(station) == plan.vehicles,
              lambda: f"{_following(station)} of {plan.vehicles} vehicles following")
        counts: dict[int, Counter[str]] = {system_id: Counter() for system_id in ids}

        def count(vehicle: VehicleState, msg: Any) -> None:
            counts[vehicle.system_id][msg.get_type()] += 1

        station.listeners.append(count)
        cpu0_ns, wall0_ns = time.process_time_ns(), clock.now_ns()
        station.run_until(lambda: False, round(plan.window_s * NS_PER_S))
        cpu_ns, wall_ns = time.process_time_ns() - cpu0_ns, clock.now_ns() - wall0_ns
        station.listeners.pop()
        tracked, following = len(station.fleet.vehicles), _following(station)
    per_vehicle = {system_id: sum(c.values()) for system_id, c in counts.items()}
    by_type: Counter[str] = Counter()
    for c in counts.values():
        by_type.update(c)
    figures: dict[str, Any] = {
        "vehicles": plan.vehicles, "vehicle_processes": min(plan.vehicle_processes, plan.vehicles),
        "app_factory": factory_name(app_factory),
        "dispatches": len(dispatch_ms),
        "dispatch_ack_ms_p50": round(float(np.percentile(dispatch_ms, 50)), 3),
        "dispatch_ack_ms_p95": round(float(np.percentile(dispatch_ms, 95)), 3),
        "dispatch_ack_ms_max": round(max(dispatch_ms), 3),
        "window_s": round(wall_ns / NS_PER_S, 3),
        f"ground_cpu_fraction_{plan.vehicles}_vehicles": round(cpu_ns / wall_ns, 4),
        "ground_cpu_s": round(cpu_ns / NS_PER_S, 3),
        "messages_received": sum(per_vehicle.values()),
        "messages_per_vehicle_expected": round(expected_message_rate() * wall_ns / NS_PER_S, 1),
        "messages_per_vehicle_min": min(per_vehicle.values()),
        "messages_per_vehicle": {str(k): v for k, v in per_vehicle.items()},
        "messages_by_type": dict(sorted(by_type.items())),
        "vehicles_tracked": tracked,
        "vehicles_following_at_end": following,
    }
    return {**figures, **target_summary("link", figures)}


def expected_message_rate(config: MavlinkConfig | None = None) -> float:
    """Messages per second a following vehicle streams by default: HEARTBEAT plus every
    stream of :func:`robot.vehicle.telemetry.default_periods_ns`."""
    config = config if config is not None else MavlinkConfig()
    periods = [config.heartbeat_period_ns, *default_periods_ns(config).values()]
    return sum(NS_PER_S / period for period in periods)


def _wait(station: GroundStation, done: Callable[[], bool], progress: Callable[[], str]) -> None:
    if not station.run_until(done, round(WAIT_S * NS_PER_S)):
        raise GroundError(f"link bench: {progress()} after {WAIT_S:g} s")


def _aim(station: GroundStation, system_id: int) -> None:
    """Point the station's clients at vehicle ``system_id`` (already heard)."""
    station.system_id = system_id
    station.wait_vehicle(WAIT_S)


def _following(station: GroundStation) -> int:
    """Vehicles whose last VISUAL_SERVO_STATUS says FOLLOWING."""
    return sum(1 for v in station.fleet.vehicles.values()
               if (msg := v.telemetry.get("VISUAL_SERVO_STATUS")) is not None
               and msg.state == mavlink.VTR_STATE_FOLLOWING)


def _dispatch(station: GroundStation, system_id: int, count: int, keys: Sequence[int],
              rng: random.Random) -> list[float]:
    """Upload ``count`` one-goal missions to ``system_id``; each one's time to its
    MISSION_ACK, ms (phase 2)."""
    _aim(station, system_id)
    pause_ns = 2 * MavlinkConfig().service_period_ns
    times_ms = []
    for _ in range(count):
        started_ns = station.clock.now_ns()
        station.upload_goals([Goal(rng.choice(keys))])
        times_ms.append((station.clock.now_ns() - started_ns) / 1e6)
        station.run_until(lambda: False, rng.randrange(pause_ns + 1))
    return times_ms


def run(args: argparse.Namespace) -> int:
    """Print the MAVLink link benchmark's JSON (``vmnav bench link``)."""
    from shared.errors import InputError

    if not 1 <= args.vehicles <= 254:
        raise InputError("--vehicles", f"must be in 1..254, got {args.vehicles}")
    if not args.window_s > 0:
        raise InputError("--window-s", f"must be > 0, got {args.window_s}")
    for name in ("dispatches", "vehicle_processes"):
        value = getattr(args, name)
        if value < 1:
            raise InputError(f"--{name.replace('_', '-')}", f"must be >= 1, got {value}")
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_link(LinkBenchPlan(
        vehicles=args.vehicles, window_s=args.window_s, dispatches=args.dispatches,
        vehicle_processes=args.vehicle_processes, seed=args.seed))
    print(json.dumps({"benchmark": "link", "load_average_at_start": load, **result}, indent=2))
    return 0
