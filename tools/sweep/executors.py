"""Where a sweep's tasks run: in this process, on a pool of local processes, or on Ray.

Each executor takes plain functions of picklable data (:mod:`tools.sweep.case`) and
gives back :class:`concurrent.futures.Future` objects, so the sweep's loop
(:mod:`tools.sweep.runner`) is the same for all three. Ray is an optional dependency
(``pip install 'vmnav[ray]'``), imported only when asked for; its tasks find the taught
memories in the sweep's folder, which on a cluster must be a folder every node sees at the
same path (docs/sweeps.md).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import socket
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Protocol

from shared.errors import InputError
from tools.harness.stop_signals import terminate_children
from tools.sweep.case import set_worker_threads

#: Ray's object store on a local cluster, bytes: the tasks pass options and rows only.
_RAY_OBJECT_STORE_BYTES = 200 * 1024**2


class Executor(Protocol):
    """Runs tasks; see the module docstring.

    Attributes:
        description: what it is, for the progress line (``pool of 2 processes``).
        workers: tasks that run at once.
        render_threads: each task's renderer threads when the task must set them (Ray),
            None when the worker was set up once (pool, this process).
    """

    description: str
    workers: int
    render_threads: int | None

    def teach_processes(self, memories: int) -> int | None:
        """Processes each of ``memories`` teaches may drive its routes in (None: one per
        CPU)."""
        ...

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future[Any]: ...

    def close(self, abandon: bool = False) -> None:
        """Stop; with ``abandon`` (Ctrl-C, SIGTERM) the tasks running are given up too,
        not awaited."""
        ...


def cpu_count() -> int:
    """The CPUs this process may use."""
    return len(os.sched_getaffinity(0))


class InlineExecutor:
    """Every task in this process, one after the other, as it is submitted."""

    def __init__(self) -> None:
        self.description = "this process"
        self.workers = 1
        self.render_threads: int | None = None
        set_worker_threads(cpu_count())

    def teach_processes(self, memories: int) -> int | None:
        """A process per CPU (the memories are taught one after the other)."""
        return None

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future[Any]:
        future: Future[Any] = Future()
        future.set_result(fn(*args))
        return future

    def close(self, abandon: bool = False) -> None:
        """Nothing to stop."""


class PoolExecutor:
    """``workers`` spawned processes of this machine, each rendering on its share of the CPUs.

    A worker that dies (killed, out of memory) breaks the pool: the tasks it held fail
    (:class:`~concurrent.futures.process.BrokenProcessPool`), and the next task submitted
    starts a new pool, so the sweep goes on.

    Raises:
        InputError: ``workers`` below 1.
    """

    def __init__(self, workers: int) -> None:
        if workers < 1:
            raise InputError("--workers", f"must be >= 1, got {workers}")
        self.description = f"pool of {workers} process{'es' if workers > 1 else ''}"
        self.workers = workers
        self.render_threads: int | None = None
        self._pool = self._start()

    def _start(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            self.workers, mp_context=multiprocessing.get_context("spawn"),
            initializer=_start_worker, initargs=(max(1, cpu_count() // self.workers),))

    def teach_processes(self, memories: int) -> int | None:
        """The workers shared out: fewer memories than workers each drive routes in
        several processes."""
        return max(1, self.workers // max(1, memories))

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future[Any]:
        try:
            return self._pool.submit(fn, *args)
        except BrokenProcessPool:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._start()
            return self._pool.submit(fn, *args)

    def close(self, abandon: bool = False) -> None:
        """Stop the processes (tasks not started are cancelled); with ``abandon``, terminate
        them first, so that a running task does not hold the sweep up for minutes (a SIGTERM
        reaches this process only, not the workers, as Ctrl-C in a terminal does)."""
        if abandon:
            terminate_children()  # the pool's are the only ones
        self._pool.shutdown(wait=True, cancel_futures=True)


def _start_worker(render_threads: int) -> None:
    """A pool worker's start: its threads (:func:`set_worker_threads`), and SIGTERM (the
    sweep abandoning its tasks, :meth:`PoolExecutor.close`) ending it with its own
    children: a teach running in it drives its routes in processes of its own
    (``tools.harness.teach``), which would otherwise run on for minutes, orphaned."""
    set_worker_threads(render_threads)
    signal.signal(signal.SIGTERM, _end_worker)


def _end_worker(signum: int, frame: object) -> None:
    terminate_children()
    os._exit(128 + signum)


def check_reachable(address: str) -> None:
    """Refuse at once a Ray address where nothing answers (Ray itself retries for minutes).

    Raises:
        InputError: not ``HOST:PORT`` or ``ray://HOST:PORT``, or no TCP connection in 5 s.
    """
    host, _, port = address.removeprefix("ray://").rpartition(":")
    if not host or not port.isdigit():
        raise InputError("--ray", f"{address!r} is not local, auto, HOST:PORT or "
                         "ray://HOST:PORT")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=5.0).close()
    except OSError as e:
        raise InputError("--ray", f"no Ray cluster answers at {address}: "
                         f"{e.strerror or e}") from None


class RayExecutor:
    """Tasks on Ray: ``local`` starts Ray on this machine with ``workers`` CPUs; ``auto``
    joins the cluster started here (``ray start``); anything else is a cluster's address.

    Raises:
        InputError: Ray is not installed (how to install it) or the cluster cannot be
            reached (where it tried).
    """

    def __init__(self, address: str, workers: int | None = None) -> None:
        try:
            import ray
        except ImportError:
            raise InputError("--ray", "Ray is not installed: pip install 'vmnav[ray]' (or "
                             "pip install 'ray>=2.40')") from None
        self._ray = ray
        local = address == "local"
        if address not in ("local", "auto"):
            check_reachable(address)
        options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
        if local:
            options.update(num_cpus=workers or cpu_count(),
                           object_store_memory=_RAY_OBJECT_STORE_BYTES)
        try:
            ray.init(address=None if local else address, **options)
        except Exception as e:  # Ray raises ConnectionError, RuntimeError, ValueError...
            ray.shutdown()
            where = "this machine" if local else repr(address)
            first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            raise InputError("--ray", f"cannot start or reach Ray at {where}: {first}") from None
        self.workers = max(1, round(ray.cluster_resources().get("CPU", 1)))
        self.description = f"Ray ({'local, ' if local else address + ', '}{self.workers} CPUs)"
        self.render_threads: int | None = 1
        self._remote: dict[Callable[..., Any], Any] = {}

    def teach_processes(self, memories: int) -> int | None:
        """One: Ray gives each task one CPU."""
        return 1

    def submit(self, fn: Callable[..., Any], *args: Any) -> Future[Any]:
        if fn not in self._remote:
            self._remote[fn] = self._ray.remote(num_cpus=1, max_retries=0)(fn)
        return self._remote[fn].remote(*args).future()  # type: ignore[no-any-return]

    def close(self, abandon: bool = False) -> None:
        """Disconnect (and stop a local Ray; a cluster ends the tasks of a driver that
        leaves)."""
        self._ray.shutdown()
