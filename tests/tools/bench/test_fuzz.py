"""``vmnav bench fuzz`` (tools/bench/fuzz.py): the runner's verdicts, its inputs, a small run.

The runner is checked on a scripted target whose input's first byte says what the input
does (return, refuse, raise, hang, kill its process, allocate past the memory limit), so
the expected counts are known exactly.
"""

from __future__ import annotations

import json
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from shared.errors import InputError
from tools.bench import fuzz
from tools.bench.fuzz import REPORT_BYTES, TARGET_NAMES, fuzz_input, fuzz_target
from tools.bench.fuzz_targets import FACTORIES
from tools.bench.run_all import QUICK_ARGS
from tools.bench.targets import check, targets_of
from tools.cli import build_parser, main

RETURN, REFUSE, RAISE, HANG, DIE, ALLOCATE = range(6)
#: A hang's time limit: far above a scripted input's microseconds, even on a loaded machine.
TIME_LIMIT_S = 2.0


class Scripted:
    """A fuzz target doing what its input's first byte says (module docstring)."""

    allowed: tuple[type[BaseException], ...] = (InputError,)

    def __init__(self, work: Path) -> None:
        self.work = work

    def generate(self, rng: np.random.Generator) -> bytes:
        action = int(rng.choice(6, p=[0.4, 0.25, 0.2, 0.05, 0.05, 0.05]))
        return bytes((action,)) + rng.bytes(int(rng.integers(0, 200)))

    def run(self, data: bytes) -> None:
        action = data[0]
        if action == REFUSE:
            raise InputError("input", "refused")
        if action == RAISE:
            raise ValueError(f"boom {len(data)}")
        if action == HANG:
            time.sleep(600)
        if action == DIE:
            os.kill(os.getpid(), signal.SIGKILL)
        if action == ALLOCATE:
            bytearray(1 << 30)


def test_crashes_hangs_deaths_and_bombs_are_counted_and_reported(
        monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setitem(FACTORIES, "scripted", Scripted)
    inputs = 40
    data = [fuzz_input("scripted", 3, i, tmp_path) for i in range(inputs)]
    actions = [d[0] for d in data]
    assert set(actions) == set(range(6))  # seed 3 exercises every action

    report = fuzz_target("scripted", inputs, seed=3, time_limit_s=TIME_LIMIT_S,
                         memory_limit_mb=256)

    crashing = [i for i, a in enumerate(actions) if a in (RAISE, DIE, ALLOCATE)]
    hanging = [i for i, a in enumerate(actions) if a == HANG]
    assert report.crashes == len(crashing)
    assert report.hangs == len(hanging)
    assert report.worker_starts == 1 + len(hanging) + actions.count(DIE)
    assert [h["index"] for h in report.hang_inputs] == hanging
    assert report.hang_inputs[0]["input_hex"] == data[hanging[0]][:REPORT_BYTES].hex()
    assert report.max_input_ms >= TIME_LIMIT_S * 1e3
    here = f"at {Path(__file__).relative_to(Path.cwd())}:"
    kinds = {kind.partition(":")[0] if here in kind else kind: n
             for kind, n in report.crash_kinds.items()}
    assert kinds == {"worker died": actions.count(DIE),
                     f"MemoryError {here[:-1]}": actions.count(ALLOCATE),
                     f"ValueError {here[:-1]}": actions.count(RAISE)}
    first = report.first_crashes[0]
    assert first["index"] == crashing[0]
    assert first["input_hex"] == data[crashing[0]][:REPORT_BYTES].hex()
    assert first["input_len"] == len(data[crashing[0]])


def test_inputs_are_a_function_of_seed_target_and_index(tmp_path: Path) -> None:
    for name in ("aria_robot", "aria_host", "mavlink_signed", "memory"):
        again = fuzz_input(name, 7, 11, tmp_path / f"{name}-b")
        assert fuzz_input(name, 7, 11, tmp_path / f"{name}-a") == again
        assert fuzz_input(name, 7, 12, tmp_path / f"{name}-c") != again


def test_a_small_run_prints_every_target_it_was_given(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "fuzz", "--inputs", "50", "--targets", "aria_host,mcap_info"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert list(result["targets"]) == ["aria_host", "mcap_info"]
    host = result["targets"]["aria_host"]
    assert (host["inputs"], host["crashes"], host["hangs"]) == (50, 0, 0)
    assert result["crashes_total"] == sum(t["crashes"] for t in result["targets"].values())
    assert [c.met for c in map(lambda t: check(t, result), targets_of("fuzz"))
            if ".aria_host." in c.target.figure] == [True, True]


@pytest.mark.parametrize(("argv", "message"), [
    (["--targets", "aria_host,nope"], "--targets: unknown target nope"),
    (["--inputs", "0"], "--inputs: must be >= 1, got 0"),
    (["--time-limit-s", "0"], "--time-limit-s: must be > 0"),
])
def test_bad_arguments_are_one_line(argv: list[str], message: str,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "fuzz", *argv]) == 1
    assert message in capsys.readouterr().err


def test_every_target_is_registered_with_its_targets_and_a_quick_size() -> None:
    assert tuple(FACTORIES) == TARGET_NAMES
    figures = {t.figure for t in targets_of("fuzz")}
    assert figures == {f"targets.{name}.{kind}" for name in TARGET_NAMES
                       for kind in ("crashes", "hangs")}
    build_parser().parse_args(["bench", "fuzz", *QUICK_ARGS["fuzz"]])


class SlowToBuild(Scripted):
    """A target whose setup never ends."""

    def __init__(self, work: Path) -> None:
        time.sleep(600)


class BrokenGenerator(Scripted):
    """A target whose input generator fails: a bug of the bench."""

    def generate(self, rng: np.random.Generator) -> bytes:
        raise KeyError("no such mutation")


def test_a_bench_bug_fails_the_run_instead_of_counting_as_a_crash(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(FACTORIES, "slow", SlowToBuild)
    monkeypatch.setitem(FACTORIES, "broken", BrokenGenerator)
    monkeypatch.setattr(fuzz, "SETUP_LIMIT_S", 0.5)
    with pytest.raises(RuntimeError, match="fuzz target slow: the worker's setup took over"):
        fuzz_target("slow", 3, seed=0, time_limit_s=TIME_LIMIT_S, memory_limit_mb=256)
    with pytest.raises(RuntimeError, match=r"(?s)making input 0 failed.*no such mutation"):
        fuzz_target("broken", 3, seed=0, time_limit_s=TIME_LIMIT_S, memory_limit_mb=256)
