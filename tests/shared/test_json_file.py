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
