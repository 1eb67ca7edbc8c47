from __future__ import annotations

from pathlib import Path

import pytest

from shared.errors import CalibrationError, MemoryFormatError
from shared.json_file import parse_json


def test_parses_standard_json() -> None:
    data = parse_json(Path("a.json"), '{"x": [1, 2.5, null]}', CalibrationError)
    assert data == {"x": [1, 2.5, None]}


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ('{"x": 1', "not valid JSON (truncated?): Expecting ',' delimiter at line 1 column 8"),
        ('{"x": NaN}', "not valid JSON: NaN is not a JSON number"),
        ('{"x": -Infinity}', "not valid JSON: -Infinity is not a JSON number"),
    ],
)
def test_errors_name_the_file_and_use_the_callers_class(text: str, fragment: str) -> None:
    with pytest.raises(MemoryFormatError) as err:
        parse_json(Path("mem/manifest.json"), text, MemoryFormatError)
    assert str(err.value) == f"mem/manifest.json: {fragment}"


@pytest.mark.parametrize(
    ("text", "fragment"),
    [
        ("[" * 100_000 + "]" * 100_000, "arrays and objects nest more than 32 deep"),
        ('{"distance_m": 1' + "0" * 400 + "}", "integer 100000000000...(401 characters) is "
                                               "outside [-2^63, 2^63)"),
        ('{"t_ns": 9223372036854775808}',
         "integer 9223372036854775808 is outside [-2^63, 2^63)"),
        ('{"x": -1e400}', "number -1e400 is too large for a float"),
        (b'{"x": "\xff"}', "not UTF-8 text (byte 7)"),
    ],
)
def test_hostile_json_gives_one_line_errors(text: str | bytes, fragment: str) -> None:
    """Each of these raised RecursionError, or parsed into values (int 10**400, inf) that
    overflow the first float conversion downstream."""
    with pytest.raises(MemoryFormatError) as err:
        parse_json(Path("mem/manifest.json"), text, MemoryFormatError)
    assert str(err.value) == f"mem/manifest.json: not valid JSON: {fragment}"


def test_limits_keep_what_is_inside_them() -> None:
    deep = "[" * 32 + "]" * 32
    assert parse_json(Path("a.json"), deep, CalibrationError) is not None
    text = '{"s": "[[[[{{{{\\"[[[[", "n": [-9223372036854775808, 9223372036854775807, 1e308]}'
    assert parse_json(Path("a.json"), text.encode(), CalibrationError) == {
        "s": '[[[[{{{{"[[[[', "n": [-(2**63), 2**63 - 1, 1e308]}
    with pytest.raises(CalibrationError, match="nest more than 3 deep"):
        parse_json(Path("a.json"), "[[[[]]]]", CalibrationError, max_depth=3)


def test_wider_integers_when_asked() -> None:
    """Log messages carry 128-bit random generator states."""
    text = f"[{2**128 - 1}, {-(2**128)}]"
    assert parse_json(Path("a.mcap"), text, CalibrationError, int_bits=128) == [
        2**128 - 1, -(2**128)]
    with pytest.raises(CalibrationError, match=r"is outside \[-2\^128, 2\^128\)"):
        parse_json(Path("a.mcap"), f"[{2**128}]", CalibrationError, int_bits=128)
