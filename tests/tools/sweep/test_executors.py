"""The local pool: a worker that dies fails its task, and the pool goes on with a new one."""

from __future__ import annotations

import os
import sys
from concurrent.futures.process import BrokenProcessPool

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
