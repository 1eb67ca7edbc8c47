"""The demo's ground station: it dispatches the goal to the robot over loopback UDP.

``vmnav demo`` runs the robot as the field does, as a MAVLink vehicle
(:class:`robot.vehicle.endpoint.VehicleEndpoint` on
:class:`robot.vehicle.udp_vehicle.UdpVehicle`, its own I/O thread on the wall clock),
and a :class:`ground.station.GroundStation` in a thread of its own
(:class:`GroundDispatch`) does what an operator's ``vmnav ground goto KEY --wait``
does: wait for the vehicle's heartbeat, upload a one-goal mission, start it, and
follow it to MISSION_ITEM_REACHED or to a stop short of the goal. Its traffic goes to
the ground log (``OUT/logs/ground-NNNN.mcap`` and a ``.tlog``) when a folder is given.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass
from pathlib import Path

from ground.ground_log import GroundLog
from ground.station import GroundStation
from shared.clock import NS_PER_S, WallClock
from shared.config import LogConfig
from shared.errors import VmnavError
from shared.mavlink.mission.goal import Goal

#: How long the ground waits for the vehicle's first heartbeat, s.
VEHICLE_TIMEOUT_S = 10.0


@dataclass(frozen=True, slots=True)
class DispatchResult:
    """What the demo's ground station saw.

    Attributes:
        upload_ms: mission upload to the final MISSION_ACK, ms (None: no ACK).
        reached: True: MISSION_ITEM_REACHED of the goal; False: the run stopped short;
            None: no outcome (an error, or the demo ended first).
        error: why the dispatch failed, one line; None when it went through.
        notices: the vehicle's STATUSTEXTs, in order.
        log_files: the ground log's files (MCAP then tlog); empty without a log.
    """

    upload_ms: float | None
    reached: bool | None
    error: str | None
    notices: tuple[str, ...]
    log_files: tuple[Path, ...]


class GroundDispatch:
    """A ground station in a thread that sends one goal and follows it (module docstring).

    Args:
        url: the vehicle's address as a pymavlink connection string (``udpout:...``).
        goal_id: the goal key image.
        timeout_s: how long to follow the mission at most, s (wall time).
        log_dir: the ground log's folder; None: no log.
    """

    def __init__(self, url: str, goal_id: int, timeout_s: float,
                 log_dir: Path | None) -> None:
        self._url = url
        self._goal_id = goal_id
        self._timeout_s = timeout_s
        self._log_dir = log_dir
        self._stop = threading.Event()
        self._result: DispatchResult | None = None
        self._thread = threading.Thread(target=self._run, name="demo-ground", daemon=True)

    def start(self) -> None:
        """Start the station's thread."""
        self._thread.start()

    def finish(self, grace_s: float) -> DispatchResult:
        """Give the station ``grace_s`` to see the outcome, then stop it; what it saw."""
        self._thread.join(grace_s)
        self._stop.set()
        self._thread.join()
        assert self._result is not None
        return self._result

    def _run(self) -> None:
        clock = WallClock()
        upload_ms: float | None = None
        error: str | None = None
        station: GroundStation | None = None
        log: GroundLog | None = None
        try:
            unix_offset_ns = time.time_ns() - clock.now_ns()
            station = GroundStation.open(self._url, clock, unix_offset_ns=unix_offset_ns)
            if self._log_dir is not None:
                log = GroundLog(LogConfig(output_dir=str(self._log_dir)), clock, unix_offset_ns)
                station.packet_taps.append(log.record)
            station.wait_vehicle(VEHICLE_TIMEOUT_S)
            started = time.perf_counter()
            station.upload_goals([Goal(self._goal_id)])
            upload_ms = (time.perf_counter() - started) * 1e3
            station.start_mission()
            station.run_until(lambda: station.mission_outcome is not None or self._stop.is_set(),
                              round(self._timeout_s * NS_PER_S))
        except VmnavError as e:
            error = str(e)
        finally:
            files: tuple[Path, ...] = ()
            if log is not None:
                files = (*log.close().files, log.tlog.path)
            notices: tuple[str, ...] = ()
            if station is not None:
                vehicle = station.vehicle
                notices = () if vehicle is None else tuple(vehicle.notices)
                station.close()
            self._result = DispatchResult(
                upload_ms=upload_ms,
                reached=None if station is None else station.mission_outcome,
                error=error, notices=notices, log_files=files)
