"""Rigs for MAVLink over streams in real time: the vehicle on an address with its own
thread, and two ptys joined as a pair of SiK radios joins two serial ports."""

from __future__ import annotations

import dataclasses
import os
import select
import threading
import tty
from pathlib import Path

from robot.config import VmnavConfig
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import SigningSetup, VehicleFiles
from robot.vehicle.vehicle_io import VehicleIo
from robot.vehicle.vehicle_link import open_vehicle_transport, vehicle_on
from shared.clock import NS_PER_S, WallClock
from tests.robot.vehicle.fake_app import FakeApp

#: Unix time minus the wall clock's reading used for signing in these tests, ns.
UNIX_OFFSET_NS = 1_750_000_000 * NS_PER_S


def start_vehicle(root: Path, app: FakeApp, url: str, *, key: bytes | None = None,
                  gcs_timeout_s: float = 5.0) -> VehicleIo:
    """System 1 on ``url`` (FakeApp), serviced by its own thread."""
    config = VmnavConfig()
    config = dataclasses.replace(config, mavlink=dataclasses.replace(
        config.mavlink, gcs_timeout_ns=round(gcs_timeout_s * NS_PER_S)))
    files = VehicleFiles(root / "memory", root / "upload", root / "params.json")
    signing = SigningSetup(key, UNIX_OFFSET_NS) if key is not None else None
    endpoint = VehicleEndpoint(app, config, files, signing=signing)
    vehicle = vehicle_on(open_vehicle_transport(url), endpoint, WallClock())
    vehicle.start_thread()
    return vehicle


class Radios:
    """Two ptys joined by a relay thread: what one end writes, the other reads.

    The robot's end is reached through a symlink (``robot_path``), so that it can be
    unplugged (its pty closed, the link removed) and plugged in again (a new pty).
    """

    def __init__(self, root: Path) -> None:
        self.robot_path = root / "robot-radio"
        self._lock = threading.Lock()
        self._robot = self._new_pty(self.robot_path)
        self._ground = self._new_pty(root / "ground-radio")
        self.ground_path = root / "ground-radio"
        self._inject = b""
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._relay, daemon=True)
        self._thread.start()

    @staticmethod
    def _new_pty(link: Path) -> tuple[int, int]:
        master, slave = os.openpty()
        tty.setraw(slave)
        os.set_blocking(master, False)
        link.unlink(missing_ok=True)
        link.symlink_to(os.ttyname(slave))
        return master, slave

    def inject_to_robot(self, data: bytes) -> None:
        """Bytes the robot's radio adds to what it delivers (RADIO_STATUS)."""
        with self._lock:
            self._inject += data

    def unplug_robot(self) -> None:
        with self._lock:
            for fd in self._robot:
                os.close(fd)
            self._robot = (-1, -1)
            self.robot_path.unlink()

    def plug_robot(self) -> None:
        with self._lock:
            self._robot = self._new_pty(self.robot_path)

    def _relay(self) -> None:
        while not self._stop.is_set():
            with self._lock:  # unplugging waits at most one select
                robot, ground = self._robot[0], self._ground[0]
                if self._inject and robot >= 0:
                    os.write(robot, self._inject)
                    self._inject = b""
                fds = [fd for fd in (robot, ground) if fd >= 0]
                for source in select.select(fds, [], [], 0.01)[0]:
                    target = ground if source == robot else robot
                    try:
                        data = os.read(source, 4096)
                        if target >= 0:
                            os.write(target, data)
                    except OSError:
                        pass  # a full buffer on the other side: lost, as on a radio link

    def close(self) -> None:
        self._stop.set()
        self._thread.join()
        for fd in (*self._robot, *self._ground):
            if fd >= 0:
                os.close(fd)
