"""The signing key file: raw, hex and passphrase keys, and the one-line errors."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from shared.errors import InputError
from shared.key_file import read_key_file
from shared.mavlink.signing import key_from_passphrase

KEY = key_from_passphrase("vmnavsecret")


class TestKeyFile:
    def test_raw_32_bytes(self, tmp_path: Path) -> None:
        (tmp_path / "key").write_bytes(KEY)
        assert read_key_file(tmp_path / "key") == KEY

    def test_hex(self, tmp_path: Path) -> None:
        (tmp_path / "key").write_text(KEY.hex().upper() + "\n")
        assert read_key_file(tmp_path / "key") == KEY

    def test_passphrase_like_mavproxy(self, tmp_path: Path) -> None:
        (tmp_path / "key").write_text("vmnavsecret\n")
        assert read_key_file(tmp_path / "key") == hashlib.sha256(b"vmnavsecret").digest() == KEY

    @pytest.mark.parametrize("content, problem", [
        (b"", "signing key file is empty"),
        (b"  \n", "signing key file is empty"),
        (b"short\n", "signing passphrase is 5 characters, at least 8 needed"),
        (bytes(range(128, 159)), "holds 31 bytes that are not text"),
        (b"tab\tinside the passphrase", "holds 25 bytes that are not text"),
    ])
    def test_bad_content(self, tmp_path: Path, content: bytes, problem: str) -> None:
        (tmp_path / "key").write_bytes(content)
        with pytest.raises(InputError, match=problem) as e:
            read_key_file(tmp_path / "key")
        assert e.value.where == str(tmp_path / "key") and "\n" not in str(e.value)

    def test_missing(self, tmp_path: Path) -> None:
        with pytest.raises(InputError, match="signing key file not found"):
            read_key_file(tmp_path / "nope")

    def test_unreadable(self, tmp_path: Path) -> None:
        with pytest.raises(InputError, match="cannot read signing key file: Is a directory"):
            read_key_file(tmp_path)
