"""Vehicles processes for ``vmnav bench link``: many MAVLink vehicles in one process.

Each vehicle is a real :class:`~robot.vehicle.endpoint.VehicleEndpoint` (default
config but its system id) on a :class:`~robot.vehicle.udp_vehicle.UdpVehicle`
sending to the ground station at ``udpout:127.0.0.1:PORT``, with its own I/O thread
and its files in a temporary folder. Its application comes from an
:data:`AppFactory`, named ``module:function`` so that a fresh interpreter can import
it (``tools.bench.link_load:make_load_app`` today; the robot runtime later).

Process protocol (``python -m tools.bench.link_vehicles --ground-port P --system-ids 1 3
--key-images 100 --app-factory MODULE:FUNCTION``): the process prints ``ready`` on
stdout once every vehicle runs, then serves until its stdin ends (the parent closed
it, or died), closes the vehicles and exits 0. A failure prints its traceback on
stderr and exits 1. It ignores Ctrl-C: the parent decides when it stops.
:class:`VehicleProcesses` is the parent's side.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import importlib
import select
import signal
import subprocess
import sys
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from robot.config import VmnavConfig
from robot.vehicle.app_port import VehicleApp
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import VehicleFiles
from robot.vehicle.udp_vehicle import UdpVehicle
from shared.clock import Clock, WallClock
from shared.mavlink.camera import VideoStream

#: How long a vehicles process may take to start its vehicles, s.
READY_TIMEOUT_S = 60.0
#: How long a vehicles process may take to stop, s.
STOP_TIMEOUT_S = 10.0
_READY = "ready"


@dataclass(frozen=True, slots=True)
class AppContext:
    """What an :data:`AppFactory` gets to build one vehicle's application.

    Attributes:
        system_id: the vehicle's MAVLink system id.
        key_images: key image ids a goal may name.
        folder: a private folder for the vehicle's files (its memory, uploads and
            parameters live in ``memory/``, ``upload/`` and ``params.json`` there).
        clock: the vehicle's clock.
    """

    system_id: int
    key_images: tuple[int, ...]
    folder: Path
    clock: Clock


#: Builds the application of one vehicle; a module-level function (see
#: :func:`factory_name`).
AppFactory = Callable[[AppContext], VehicleApp]


def factory_name(factory: AppFactory) -> str:
    """``module:function`` of ``factory``, for :func:`load_factory` in another process.

    Raises:
        ValueError: ``factory`` is not a module-level function (a lambda, a closure).
    """
    name = f"{factory.__module__}:{factory.__qualname__}"
    if "<" in factory.__qualname__:
        raise ValueError(f"app factory {name} is not a module-level function")
    return name


def load_factory(name: str) -> AppFactory:
    """The factory called ``module:function``.

    Raises:
        ValueError: not of that form; ImportError/AttributeError: no such module or function.
    """
    module, sep, function = name.partition(":")
    if not sep or not module or not function:
        raise ValueError(f"app factory {name!r} is not MODULE:FUNCTION")
    factory: AppFactory = getattr(importlib.import_module(module), function)
    return factory


def serve_vehicles(system_ids: Sequence[int], ground_port: int, key_images: Sequence[int],
                   app_factory: AppFactory, until_stopped: Callable[[], None],
                   video: VideoStream | None = None) -> None:
    """Run one vehicle per system id (module docstring) until ``until_stopped()``
    returns; then close them all. ``video``: a stream each one's camera component
    advertises (``vmnav bench web``'s camera); None: no camera."""
    with tempfile.TemporaryDirectory(prefix="vmnav-link-vehicles-") as tmp:
        vehicles: list[UdpVehicle] = []
        try:
            clock = WallClock()
            base = VmnavConfig()
            for system_id in system_ids:
                folder = Path(tmp) / f"vehicle{system_id}"
                (folder / "memory").mkdir(parents=True)
                app = app_factory(AppContext(system_id, tuple(key_images), folder, clock))
                config = dataclasses.replace(
                    base, mavlink=dataclasses.replace(base.mavlink, system_id=system_id))
                files = VehicleFiles(folder / "memory", folder / "upload", folder / "params.json")
                vehicle = UdpVehicle.open(f"udpout:127.0.0.1:{ground_port}",
                                          VehicleEndpoint(app, config, files, video=video),
                                          clock)
                vehicles.append(vehicle)
                vehicle.start_thread()
            until_stopped()
        finally:
            for vehicle in vehicles:
                vehicle.close()


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of a vehicles process (module docstring)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    parser = argparse.ArgumentParser(prog="python -m tools.bench.link_vehicles",
                                     description="MAVLink vehicles for vmnav bench link")
    parser.add_argument("--ground-port", type=int, required=True)
    parser.add_argument("--system-ids", type=int, nargs="+", required=True)
    parser.add_argument("--key-images", type=int, required=True)
    parser.add_argument("--app-factory", required=True)
    args = parser.parse_args(argv)

    def until_stopped() -> None:
        print(_READY, flush=True)
        sys.stdin.read()

    serve_vehicles(args.system_ids, args.ground_port, range(args.key_images),
                   load_factory(args.app_factory), until_stopped)
    return 0


class VehicleProcesses:
    """Vehicles processes, each ready on entry, all stopped on exit (the parent's side).

    Args:
        system_ids: the vehicles, spread round-robin over the processes.
        processes: how many processes (at most one per vehicle).
        ground_port: the ground station's UDP port on 127.0.0.1.
        key_images: each vehicle knows key images ``0..key_images-1``.
        app_factory: a module-level function (:func:`factory_name`).

    Raises (on entry):
        RuntimeError: a process exited or was not ready within :data:`READY_TIMEOUT_S`.
    """

    def __init__(self, system_ids: Sequence[int], processes: int, ground_port: int,
                 key_images: int, app_factory: AppFactory) -> None:
        count = min(processes, len(system_ids))
        self._commands = [
            [sys.executable, "-m", "tools.bench.link_vehicles", "--ground-port", str(ground_port),
             "--system-ids", *map(str, system_ids[part::count]),
             "--key-images", str(key_images), "--app-factory", factory_name(app_factory)]
            for part in range(count)]
        self._children: list[subprocess.Popen[str]] = []

    def __enter__(self) -> VehicleProcesses:
        try:
            for command in self._commands:
                self._children.append(subprocess.Popen(
                    command, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True))
            for child in self._children:
                assert child.stdout is not None
                ready = select.select([child.stdout], [], [], READY_TIMEOUT_S)[0]
                line = child.stdout.readline() if ready else ""
                if line.strip() != _READY:
                    what = (f"exited with code {child.wait(STOP_TIMEOUT_S)}" if ready
                            else f"was not ready after {READY_TIMEOUT_S:g} s")
                    raise RuntimeError(f"vehicles process {child.pid} {what} "
                                       "(its stderr says why)")
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        for child in self._children:
            assert child.stdin is not None
            with contextlib.suppress(BrokenPipeError):  # it died already
                child.stdin.close()
        for child in self._children:
            try:
                child.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                child.kill()
                child.wait()
            assert child.stdout is not None
            child.stdout.close()


if __name__ == "__main__":
    sys.exit(main())
