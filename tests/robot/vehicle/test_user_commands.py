"""The user commands' parameter encodings and the uploaded-photo lookup."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from robot.vehicle.ftp_memory import MemoryFileSystem
from robot.vehicle.user_commands import find_photo
from shared.mavlink.commands.user import NAME_BYTES, name_from_params, params_from_name
from shared.mavlink.dialect import to_float32

PRINTABLE = st.text(st.characters(min_codepoint=0x20, max_codepoint=0x7E), max_size=NAME_BYTES)


@given(PRINTABLE)
def test_names_survive_float32_params(name: str) -> None:
    params = params_from_name(name)
    assert len(params) == 7
    assert name_from_params([to_float32(p) for p in params]) == name


def test_nan_params_are_an_empty_name() -> None:
    assert name_from_params([math.nan] * 7) == ""


@pytest.mark.parametrize("params", [
    [1.5] + [0.0] * 6,  # not an integer
    [-1.0] + [0.0] * 6,
    [2.0**24] + [0.0] * 6,  # more than 3 bytes
    [0.0, float(int.from_bytes(b"abc", "big"))] + [0.0] * 5,  # a NUL before the text
    [float(int.from_bytes(b"a\tb", "big"))] + [0.0] * 6,  # not printable
    [math.inf] + [0.0] * 6,
])
def test_malformed_name_params(params: list[float]) -> None:
    assert name_from_params(params) is None


@pytest.mark.parametrize("name", ["x" * (NAME_BYTES + 1), "caf\u00e9", "tab\there"])
def test_names_that_cannot_be_sent(name: str) -> None:
    with pytest.raises(ValueError, match="printable ASCII"):
        params_from_name(name)


def test_find_photo(tmp_path: Path) -> None:
    fs = MemoryFileSystem(tmp_path / "memory", tmp_path / "upload")
    (tmp_path / "upload" / "12.jpeg").write_bytes(b"j")
    (tmp_path / "upload" / "123.png").write_bytes(b"p")
    (tmp_path / "upload" / "4").mkdir()
    assert find_photo(fs, 12.0) == tmp_path / "upload" / "12.jpeg"
    assert find_photo(fs, 123) == tmp_path / "upload" / "123.png"
    assert find_photo(fs, 4) == "want one uploaded /upload/4.<ext>, found none"
    assert find_photo(fs, 0) == "photo id 0 is not an integer in 1..16777216"
    assert find_photo(fs, math.nan).startswith("photo id nan")
