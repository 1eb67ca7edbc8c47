"""The signing key file: raw, hex and passphrase keys, and the one-line errors."""

from __future__ import annotations

import hashlib
import stat
from pathlib import Path

import pytest

from shared.errors import InputError
from shared.key_file import create_key_file, read_key_file
from shared.mavlink.signing import NEW_PASSPHRASE_CHARS, key_from_passphrase

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


class TestCreateKeyFile:
    def test_a_new_key_is_a_passphrase_mavproxy_can_take_mode_0600(self, tmp_path: Path) -> None:
        path = tmp_path / "vmnav.key"
        create_key_file(path)
        passphrase = path.read_text(encoding="ascii")
        assert passphrase.endswith("\n") and passphrase[:-1].isalnum()
        assert len(passphrase) == NEW_PASSPHRASE_CHARS + 1
        assert read_key_file(path) == key_from_passphrase(passphrase.strip())
        assert stat.S_IMODE(path.stat().st_mode) == 0o600
        assert [p.name for p in tmp_path.iterdir()] == ["vmnav.key"]  # no temporary left
        create_key_file(tmp_path / "other.key")
        assert read_key_file(tmp_path / "other.key") != read_key_file(path)

    def test_never_replaces_a_file(self, tmp_path: Path) -> None:
        path = tmp_path / "vmnav.key"
        path.write_bytes(KEY)
        with pytest.raises(InputError, match="exists: a new key never replaces one"):
            create_key_file(path)
        assert path.read_bytes() == KEY
        (tmp_path / "link").symlink_to(tmp_path / "dangling")
        with pytest.raises(InputError, match="exists"):
            create_key_file(tmp_path / "link")
        assert not (tmp_path / "dangling").exists()
        assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "vmnav.key"]

    def test_missing_folders_are_made_for_the_owner_only(self, tmp_path: Path) -> None:
        path = tmp_path / "home" / "vmnav" / "vmnav.key"  # `keygen ~/vmnav/vmnav.key`
        create_key_file(path)
        assert stat.S_IMODE(path.parent.stat().st_mode) == 0o700
        assert stat.S_IMODE(path.stat().st_mode) == 0o600

    def test_a_folder_that_cannot_be_made_is_one_line(self, tmp_path: Path) -> None:
        (tmp_path / "file").write_bytes(b"")
        with pytest.raises(InputError, match=r"cannot create key file: .*/file is not a folder"):
            create_key_file(tmp_path / "file" / "vmnav.key")
