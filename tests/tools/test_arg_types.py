from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest

from tools.cli import main
from tools.harness.arg_types import COUNT, POSITIVE, SEED, SYSTEM_ID, integer, number

FRACTION = number(0.0, 1.0)


class TestInteger:
    def test_in_range_values_parse(self) -> None:
        assert COUNT("0") == 0
        assert SEED("123456789012") == 123456789012
        assert SYSTEM_ID("255") == 255
        assert integer(-2, 2)("-2") == -2

    @pytest.mark.parametrize(("parse", "text", "wanted"), [
        (COUNT, "-3", "an integer >= 0"),
        (SEED, "-1", "an integer >= 0"),
        (SYSTEM_ID, "0", "an integer in [1, 255]"),
        (SYSTEM_ID, "256", "an integer in [1, 255]"),
        (COUNT, "2.5", "an integer >= 0"),
        (COUNT, "ten", "an integer >= 0"),
        (COUNT, "0x10", "an integer >= 0"),
    ])
    def test_out_of_range_or_not_an_integer_is_refused(self, parse, text: str,
                                                      wanted: str) -> None:
        message = re.escape(f"must be {wanted}, got '{text}'")
        with pytest.raises(argparse.ArgumentTypeError, match=message):
            parse(text)


class TestNumber:
    def test_in_range_values_parse(self) -> None:
        assert POSITIVE("1e-3") == pytest.approx(1e-3)
        assert FRACTION("1") == 1.0
        assert number()("-1e9") == -1e9

    @pytest.mark.parametrize(("parse", "text", "wanted"), [
        (number(), "nan", "a finite number"),
        (number(), "inf", "a finite number"),
        (number(), "-inf", "a finite number"),
        (POSITIVE, "0", "a finite number > 0"),
        (POSITIVE, "-1", "a finite number > 0"),
        (FRACTION, "1.5", "a finite number >= 0 and <= 1"),
        (FRACTION, "-0.1", "a finite number >= 0 and <= 1"),
        (number(), "one", "a finite number"),
    ])
    def test_out_of_range_or_not_finite_is_refused(self, parse, text: str, wanted: str) -> None:
        message = re.escape(f"must be {wanted}, got '{text}'")
        with pytest.raises(argparse.ArgumentTypeError, match=message):
            parse(text)


@pytest.mark.parametrize(("argv", "message"), [
    (["demo", "--seed", "-1"], "argument --seed: must be an integer >= 0, got '-1'"),
    (["demo", "--people", "-3"], "argument --people: must be an integer >= 0, got '-3'"),
    (["sim", "snapshot", "--out", "OUT", "--x", "nan"],
     "argument --x: must be a finite number, got 'nan'"),
    (["sim", "snapshot", "--out", "OUT", "--yaw", "inf"],
     "argument --yaw: must be a finite number, got 'inf'"),
    (["bench", "sim", "--frames", "0"], "argument --frames: must be an integer >= 1, got '0'"),
    (["ground", "--system", "0", "status"],
     "argument --system: must be an integer in [1, 255], got '0'"),
])
def test_a_bad_number_on_the_command_line_is_one_usage_error(
        argv: list[str], message: str, tmp_path: Path,
        capsys: pytest.CaptureFixture[str]) -> None:
    argv = [str(tmp_path / "out") if a == "OUT" else a for a in argv]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"error: {message} (see vmnav " in err
    assert "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_a_negative_seed_in_a_config_file_is_refused_naming_the_file(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    config = tmp_path / "vmnav.toml"
    config.write_text("[sim]\nseed = -1\n")
    code = main(["sim", "snapshot", "--config", str(config), "--out", str(tmp_path / "out")])
    assert code == 1
    assert capsys.readouterr().err.strip() == (
        f"vmnav sim: error: {config}: sim: seed must be >= 0, got -1")
    assert not (tmp_path / "out").exists()
