"""``vmnav bench hostile``: the parts run in order and their JSON is gathered."""

from __future__ import annotations

import json

import pytest

from tools.bench.targets import check, targets_of
from tools.cli import main


def test_one_part_runs_and_its_targets_are_checked(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "hostile", "--parts", "signing"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["benchmark"] == "hostile" and "messages" not in result
    signing = result["signing"]
    assert signing["wrong_key_packets_sent"] > 0 and signing["wall_s"] > 0
    assert result["targets_met"] == signing["targets_met"]
    checks = [check(t, result) for t in targets_of("hostile") if t.figure.startswith("signing.")]
    assert len(checks) >= 5 and all(c.value is not None for c in checks)
    assert all(c.met for c in checks), [c for c in checks if not c.met]


def test_an_unknown_part_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "hostile", "--parts", "signing,nope"]) == 1
    err = capsys.readouterr().err
    assert "--parts: unknown part nope" in err and "Traceback" not in err
