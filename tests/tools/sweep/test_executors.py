"""The local pool: a worker that dies fails its task, and the pool goes on with a new one; an
abandoned pool (Ctrl-C, SIGTERM) does not wait for its running tasks, nor leave their own
processes behind."""

from __future__ import annotations

import multiprocessing
import os
import sys
import time
from concurrent.futures.process import BrokenProcessPool
from pathlib import Path

import pytest

from tools.sweep.executors import PoolExecutor


def test_a_dead_worker_fails_its_task_and_the_next_task_runs() -> None:
    pool = PoolExecutor(1)
    try:
        dead = pool.submit(os._exit, 3)  # the worker process exits at once, as if killed
        with pytest.raises(BrokenProcessPool):
            dead.result(timeout=120)
        pid = pool.submit(os.getpid).result(timeout=120)
        assert pid != os.getpid()
    finally:
        pool.close()


def sleep_in(started: Path, seconds: float) -> int:
    """A task that says it started, then sleeps; its process id."""
    started.touch()
    time.sleep(seconds)
    return os.getpid()


def test_an_abandoned_pool_stops_its_running_task(tmp_path) -> None:
    pool = PoolExecutor(1)
    try:
        worker = pool.submit(os.getpid).result(timeout=120)
        running = pool.submit(sleep_in, tmp_path / "started", 600.0)
        limit = time.monotonic() + 120
        while not (tmp_path / "started").exists() and time.monotonic() < limit:
            time.sleep(0.05)
    finally:
        began = time.monotonic()
        pool.close(abandon=True)
    assert time.monotonic() - began < 120  # not the task's 600 s
    with pytest.raises(BrokenProcessPool):
        running.result(timeout=0)
    with pytest.raises(ProcessLookupError):
        os.kill(worker, 0)


def sleep_with_a_child(started: Path, seconds: float) -> None:
    """A task that starts a process of its own (as a teach drives its routes), says so with
    the child's process id, then sleeps."""
    child = multiprocessing.get_context("spawn").Process(target=time.sleep, args=(seconds,))
    child.start()
    started.write_text(str(child.pid))
    time.sleep(seconds)


def ended(pid: int) -> bool:
    """The process is gone, or a zombie waiting for its new parent to reap it."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


def test_an_abandoned_pool_stops_the_processes_of_its_running_task(tmp_path) -> None:
    pool = PoolExecutor(1)
    started = tmp_path / "started"
    try:
        pool.submit(sleep_with_a_child, started, 600.0)
        limit = time.monotonic() + 120
        while not (started.exists() and started.read_text()) and time.monotonic() < limit:
            time.sleep(0.05)
    finally:
        pool.close(abandon=True)
    child = int(started.read_text())
    limit = time.monotonic() + 60
    while not ended(child) and time.monotonic() < limit:
        time.sleep(0.05)
    assert ended(child)


def test_ray_not_installed_says_how_to_install(monkeypatch, tmp_path, capsys) -> None:
    from tools.cli import main

    monkeypatch.setitem(sys.modules, "ray", None)  # what `import ray` meets without it
    (tmp_path / "plan.toml").write_text("[axes]\nseed = [1]\n")
    out = tmp_path / "out"
    assert main(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(out),
                 "--ray", "local"]) == 1
    err = capsys.readouterr().err
    assert err == ("vmnav sweep: error: --ray: Ray is not installed: pip install 'vmnav[ray]' "
                   "(or pip install 'ray>=2.40')\n")
    assert not out.exists()
