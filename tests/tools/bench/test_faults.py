"""Issue 8's faults on the hardware-in-the-loop rig, each case once (``vmnav bench faults``
repeats them): the cases live in ``tools/harness/fault_cases.py`` and
``tools/harness/fault_garbage.py``, the rig in ``tools/harness/hil_rig.py``. The route is
the session's ``east_a`` (tests/conftest.py); each case builds its own rig (``vmnav robot``
as a subprocess) on a copy of its memory, 3 to 22 s each."""

from __future__ import annotations

import json

import pytest

from tools.bench.faults import CASES, run_case
from tools.cli import main


@pytest.mark.slow
@pytest.mark.parametrize("name", list(CASES))
def test_fault_case(name, east_a_taught, tmp_path) -> None:
    run_case(name, east_a_taught, tmp_path / name)


@pytest.mark.slow
def test_bench_counts_the_runs_of_each_case(tmp_path, capsys) -> None:
    code = main(["bench", "faults", "--cases", "garbage_aria_server", "--repeat", "2",
                 "--out", str(tmp_path)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    result = json.loads(captured.out)
    assert list(result) == ["garbage_aria_server"]
    assert {k: v for k, v in result["garbage_aria_server"].items() if k != "wall_s_max"} == {
        "passed": 2, "runs": 2, "failures": []}
    assert captured.err.count("garbage_aria_server run ") == 2
    assert (tmp_path / "garbage_aria_server-2").is_dir()  # --out keeps every run


@pytest.mark.parametrize("args, message", [
    (["--repeat", "0"], "--repeat: must be >= 1, got 0"),
    (["--cases", "aria_link_cut,nothing"], "--cases: unknown case nothing (known: aria_link_cut"),
])
def test_bad_arguments_are_one_line(args, message, capsys) -> None:
    assert main(["bench", "faults", *args]) == 1
    assert message in capsys.readouterr().err
