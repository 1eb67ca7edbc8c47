"""A tiny sweep end to end on real processes: the lab's 2.5 m route ``east_a`` taught by the
sweep, three cases repeating it of which one crashes (a start 40 m off the route, outside
the lab); stopped after its first case (``--cases 1``), then resumed; the same cases on a
local Ray, on the memory the pool taught, give the same figures as on the pool."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from concurrent.futures import Future
from pathlib import Path

import pytest

from tools.cli import main
from tools.harness.short_routes import write_short_routes_world
from tools.sweep.plan import read_plan
from tools.sweep.results import FIGURES, TIMING, read_rows
from tools.sweep.runner import run_sweep

ROOT = Path(__file__).resolve().parents[3]


def write_plan(folder: Path, world: Path, offsets: list[float]) -> Path:
    """``east_a`` of the short routes' world, goal 4 (two key images past the start), one
    seed, ``offsets``."""
    path = folder / "plan.toml"
    path.write_text(f'[sweep]\nroutes = ["east_a"]\ngoal = 4\n\n[axes]\n'
                    f'world = ["{world}"]\nseed = [1]\nstart_offset_m = {offsets}\n')
    return path


@pytest.fixture(scope="module")
def interrupted_sweep(tmp_path_factory) -> tuple[Path, str, str, str]:
    """The sweep run as a process for its first case only (``--cases 1``: stopped there, as
    an interrupted sweep is), then resumed in another process. Returns (its folder, the
    results' text after the first case, the resumed run's stderr, stdout)."""
    folder = tmp_path_factory.mktemp("sweep")
    plan = write_plan(folder, write_short_routes_world(folder), [0.3, 0.2, 40.0])
    out = folder / "out"
    command = [sys.executable, "-m", "tools.cli", "sweep", "run", str(plan), "--out", str(out),
               "--workers", "1"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    one = subprocess.run([*command, "--cases", "1"], cwd=folder, env=env, capture_output=True,
                         text=True, timeout=300, check=False)
    assert one.returncode == 0, one.stderr
    before = (out / "results.csv").read_text()
    resumed = subprocess.run(  # resumed: a fresh process, as after a crash or Ctrl-C
        command, cwd=folder, env=env, capture_output=True, text=True, timeout=300, check=False)
    assert resumed.returncode == 0, resumed.stderr
    return out, before, resumed.stderr, resumed.stdout


@pytest.mark.slow
def test_an_interrupted_sweep_resumes_where_it_stopped(interrupted_sweep, tmp_path) -> None:
    out, before, err, summary = interrupted_sweep
    (tmp_path / "before.csv").write_text(before)
    assert len(read_rows(tmp_path / "before.csv")) == 1  # --cases 1
    assert (out / "results.csv").read_text().startswith(before)
    assert "3 cases, 1 done before" in err
    rows = read_rows(out / "results.csv")
    assert len(rows) == len({row["case_id"] for row in rows}) == 3
    assert "3 cases: 2 reached the goal, 0 did not, 1 crashed" in summary
    ok = [row for row in rows if row["status"] == "ok"]
    assert all(row["goal_key_image"] == 4 and row["worker_peak_rss_mb"] < 1500 for row in ok)
    # judged by the simulator's truth: nobody about, nothing in the way, always localized
    assert all((row["contacts_moving"], row["contacts_still"], row["obstacle_waits"]) == (0, 0, 0)
               and 0.0 <= row["blind_max_m"] < 1.0 for row in ok)
    assert all(row["code_version"].startswith("vmnav ") for row in rows)


@pytest.mark.slow
def test_a_crashing_case_is_a_row_with_its_traceback(interrupted_sweep) -> None:
    out, _, err, _ = interrupted_sweep
    (crashed,) = [row for row in read_rows(out / "results.csv") if row["status"] == "crashed"]
    assert crashed["start_offset_m"] == 40.0 and crashed["reached_goal"] is None
    assert crashed["error"].startswith("Traceback (most recent call last)")
    assert "--start-offset 40.0" in crashed["options"]
    assert f"{crashed['case_id']} start_offset_m=40.0: crashed (" in err


@pytest.mark.slow
def test_ray_gives_the_pool_s_figures(interrupted_sweep, tmp_path, capsys, monkeypatch) -> None:
    """Two cases as Ray tasks (a local Ray of 2 CPUs), on the memory the pool's sweep
    taught (copied: a folder holding only memories is a sweep's to start): each case's
    figures are those its pool process gave, the wall-clock ones aside. Run from the pool
    sweep's folder (so the world file has the same name and the cases the same ids), the
    plan elsewhere; Ray's workers run in folders of their own (they are given absolute
    paths)."""
    pool_out, _, _, _ = interrupted_sweep
    monkeypatch.chdir(pool_out.parent)
    plan = write_plan(tmp_path, pool_out.parent / "lab_short.toml", [0.3, 0.2])
    shutil.copytree(pool_out / "memories", tmp_path / "out" / "memories")
    assert main(["sweep", "run", str(plan), "--out", str(tmp_path / "out"),
                 "--ray", "local", "--workers", "2"]) == 0
    assert "2 cases: 2 reached the goal" in capsys.readouterr().out
    on_pool = {row["case_id"]: row for row in read_rows(pool_out / "results.csv")}
    on_ray = read_rows(tmp_path / "out" / "results.csv")
    assert len(on_ray) == 2
    for row in on_ray:
        for key in FIGURES:
            if key not in TIMING:
                assert row[key] == on_pool[row["case_id"]][key], key


class RecordingExecutor:
    """Runs nothing: each task succeeds at once; the order tasks were submitted in."""

    description = "recording"
    workers = 1
    render_threads = None

    def __init__(self) -> None:
        self.submitted: list[str] = []

    def teach_processes(self, memories: int) -> None:
        return None

    def submit(self, fn, *args) -> Future:
        self.submitted.append(fn.__name__)
        future: Future = Future()
        future.set_result({"status": "ok", "teach_wall_time_s": 0.0})
        return future

    def close(self, abandon: bool = False) -> None:
        pass


def test_a_memory_s_cases_run_before_the_next_memory_is_taught(tmp_path) -> None:
    """Rows come as the sweep goes: with one task at a time, each memory's teach is
    followed by its cases, not every teach first."""
    (tmp_path / "plan.toml").write_text("[axes]\nseed = [1, 2]\nlaw = ['paper', 'paper+ff']\n")
    cases = read_plan(tmp_path / "plan.toml").cases()
    executor = RecordingExecutor()
    rows = run_sweep(cases, lambda case: tmp_path / case.memory_name, executor, None, "test")
    assert [row["status"] for row in rows] == ["ok"] * 4
    assert executor.submitted == ["teach_task", "case_task", "case_task"] * 2
