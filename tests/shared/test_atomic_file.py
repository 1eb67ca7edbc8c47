from __future__ import annotations

import os
from pathlib import Path

import pytest

from shared.atomic_file import write_bytes_atomic, write_text_atomic
from shared.errors import InputError


def test_replaces_content_and_leaves_no_temp_files(tmp_path: Path) -> None:
    path = tmp_path / "a.json"
    write_text_atomic(path, "old")
    write_text_atomic(path, "new")
    assert path.read_text() == "new"
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]


def test_new_files_are_world_readable_and_replacements_keep_their_mode(tmp_path: Path) -> None:
    path = tmp_path / "a.json"
    write_text_atomic(path, "one")
    assert path.stat().st_mode & 0o777 == 0o644
    path.chmod(0o600)
    write_text_atomic(path, "two")
    assert path.stat().st_mode & 0o777 == 0o600


def test_missing_folder_is_a_one_line_input_error(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot write"):
        write_bytes_atomic(tmp_path / "missing" / "a.bin", b"x")


def test_failed_write_keeps_old_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "a.txt"
    write_text_atomic(path, "precious")

    def full_disk(src: str, dst: str) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", full_disk)
    with pytest.raises(InputError, match="No space left on device"):
        write_text_atomic(path, "new")
    assert path.read_text() == "precious"
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]
