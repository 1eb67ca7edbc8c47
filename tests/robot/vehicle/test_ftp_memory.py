"""The robot's FTP file system: a real visual memory, read-only, and the upload area."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import numpy as np
import pytest

from robot.vehicle.ftp_memory import MemoryFileSystem
from shared.clock import ManualClock
from shared.mavlink.ftp.gcs import Downloaded, FtpClient
from shared.mavlink.ftp.payload import DirEntry
from shared.mavlink.ftp.vehicle import FtpServer
from shared.memory.store import MANIFEST_NAME, read_memory, thumbnail_path, write_memory
from tests.shared.mavlink.test_ftp import Relay, run
from tests.shared.memory.builders import loop_memory


@pytest.fixture
def fs(tmp_path: Path, rng: np.random.Generator) -> MemoryFileSystem:
    """A loop memory written by the store, and the upload area beside it."""
    write_memory(tmp_path / "mem", loop_memory(rng))
    (tmp_path / "secret.txt").write_text("not served")
    return MemoryFileSystem(tmp_path / "mem", tmp_path / "upload", upload_limit_bytes=1000)


class TestReadOnlyMemory:
    def test_root_lists_the_two_areas(self, fs: MemoryFileSystem) -> None:
        assert fs.list_directory("/") == [DirEntry("memory", True), DirEntry("teaching", True),
                                          DirEntry("upload", True)]

    def test_teaching_serves_the_key_images_taken_from_ram(self, tmp_path: Path) -> None:
        taken: list[tuple[int, bytes]] = []
        fs = MemoryFileSystem(tmp_path / "mem", tmp_path / "upload", teaching=lambda: taken)
        assert fs.list_directory("/teaching") == []
        taken += [(7, b"\x89PNG seven"), (8, b"\x89PNG eight")]
        assert fs.list_directory("/teaching/") == [DirEntry("7.png", False, 10),
                                                   DirEntry("8.png", False, 10)]
        reader = fs.open_read("/teaching/8.png")
        assert (reader.size, reader.read(5, 100)) == (10, b"eight")
        for path in ("/teaching/9.png", "/teaching/8.png/x", "/teaching"):
            with pytest.raises(OSError):
                fs.open_read(path)
        with pytest.raises(PermissionError):
            fs.open_write("/teaching/9.png", exclusive=False)
        with pytest.raises(PermissionError):
            fs.remove("/teaching/8.png")

    def test_memory_shows_the_store_layout(self, fs: MemoryFileSystem) -> None:
        manifest_size = (fs.memory_dir / MANIFEST_NAME).stat().st_size
        assert fs.list_directory("/memory") == [
            DirEntry("features", True), DirEntry("images", True),
            DirEntry(MANIFEST_NAME, False, manifest_size), DirEntry("thumbnails", True)]
        ids = list(read_memory(fs.memory_dir).keyframes)
        thumbnails = fs.list_directory("/memory/thumbnails/")
        assert sorted(e.name for e in thumbnails) == sorted(f"{i}.png" for i in ids)

    def test_thumbnail_reads_back_over_ftp(self, fs: MemoryFileSystem) -> None:
        expected = thumbnail_path(fs.memory_dir, 5).read_bytes()
        client = FtpClient()
        client.get("/memory/thumbnails/5.png", 0)
        event = run(client, FtpServer(fs), Relay(loss=0.2, seed=9), ManualClock())
        assert event == Downloaded("/memory/thumbnails/5.png", expected)

    def test_reader_keeps_the_version_it_opened(self, fs: MemoryFileSystem) -> None:
        manifest = fs.memory_dir / MANIFEST_NAME
        before = manifest.read_bytes()
        reader = fs.open_read("/memory/manifest.json")
        tmp = fs.memory_dir / ".manifest.json.new.tmp"
        tmp.write_text("{}")
        os.replace(tmp, manifest)  # how the store replaces it
        assert reader.read(0, reader.size) == before
        reader.close()

    def test_hidden_temporary_files_are_neither_listed_nor_read(
            self, fs: MemoryFileSystem) -> None:
        (fs.memory_dir / ".manifest.json.abc.tmp").write_text("half")
        assert all(not e.name.startswith(".") for e in fs.list_directory("/memory"))
        with pytest.raises(PermissionError):
            fs.open_read("/memory/.manifest.json.abc.tmp")

    @pytest.mark.parametrize("path", ["/memory/../secret.txt", "..", "/memory/..\\x",
                                      "/memory/thumbnails/../../secret.txt",
                                      "/upload/../memory/manifest.json"])
    def test_dot_dot_is_refused(self, fs: MemoryFileSystem, path: str) -> None:
        with pytest.raises(PermissionError) as e:
            fs.open_read(path)
        assert e.value.errno == errno.EACCES

    def test_symlinks_are_refused_and_hidden(self, fs: MemoryFileSystem) -> None:
        (fs.memory_dir / "escape").symlink_to(fs.memory_dir.parent / "secret.txt")
        (fs.memory_dir / "escape_dir").symlink_to(fs.memory_dir.parent)
        with pytest.raises(PermissionError):
            fs.open_read("/memory/escape")
        with pytest.raises(PermissionError):
            fs.open_read("/memory/escape_dir/secret.txt")
        names = [e.name for e in fs.list_directory("/memory")]
        assert "escape" not in names and "escape_dir" not in names

    def test_a_symlinked_memory_directory_still_serves(self, fs: MemoryFileSystem,
                                                       tmp_path: Path) -> None:
        (tmp_path / "current").symlink_to(fs.memory_dir)
        linked = MemoryFileSystem(tmp_path / "current", fs.upload_dir)
        reader = linked.open_read("/memory/manifest.json")
        assert reader.read(0, 1) == b"{"
        reader.close()

    def test_not_found_and_not_a_file(self, fs: MemoryFileSystem) -> None:
        with pytest.raises(FileNotFoundError):
            fs.open_read("/memory/thumbnails/99.png")
        with pytest.raises(FileNotFoundError):
            fs.list_directory("/elsewhere")
        with pytest.raises(IsADirectoryError):
            fs.open_read("/memory/images")
        with pytest.raises(NotADirectoryError):
            fs.list_directory("/memory/manifest.json")

    @pytest.mark.parametrize("path", ["/memory/manifest.json", "/memory/new.png", "/x.png",
                                      "/upload/a/b.png", "/upload"])
    def test_writes_outside_upload_are_refused(self, fs: MemoryFileSystem, path: str) -> None:
        with pytest.raises(PermissionError):
            fs.open_write(path, exclusive=False)
        with pytest.raises(PermissionError):
            fs.remove(path)


class TestUpload:
    def test_out_of_order_writes_commit_atomically(self, fs: MemoryFileSystem) -> None:
        upload = fs.open_write("/upload/goal.png", exclusive=True)
        upload.write(5, b"world")
        upload.write(0, b"hello")
        assert os.listdir(fs.upload_dir) == []
        upload.commit()
        assert (fs.upload_dir / "goal.png").read_bytes() == b"helloworld"
        reader = fs.open_read("/upload/goal.png")
        assert reader.read(0, 100) == b"helloworld"
        reader.close()

    def test_a_hole_commits_nothing(self, fs: MemoryFileSystem) -> None:
        upload = fs.open_write("/upload/goal.png", exclusive=True)
        upload.write(0, b"abc")
        upload.write(5, b"def")
        with pytest.raises(OSError, match=r"no bytes 3\.\.4"):
            upload.commit()
        assert os.listdir(fs.upload_dir) == []

    def test_too_large_fails_for_good(self, fs: MemoryFileSystem) -> None:
        upload = fs.open_write("/upload/goal.png", exclusive=False)
        with pytest.raises(OSError) as e:
            upload.write(990, bytes(11))
        assert e.value.errno == errno.EFBIG
        upload.write(0, bytes(990))
        with pytest.raises(OSError, match="failed earlier"):
            upload.commit()
        assert os.listdir(fs.upload_dir) == []

    def test_the_area_quota_counts_files_and_uploads_in_progress(self, tmp_path: Path) -> None:
        fs = MemoryFileSystem(tmp_path / "mem", tmp_path / "upload", upload_limit_bytes=1000,
                              upload_total_bytes=2500)
        (fs.upload_dir / "old.png").write_bytes(bytes(1000))
        held = fs.open_write("/upload/a.png", exclusive=True)
        held.write(0, bytes(1000))
        late = fs.open_write("/upload/b.png", exclusive=True)
        late.write(0, bytes(500))
        with pytest.raises(OSError) as e:
            late.write(500, bytes(1))
        assert e.value.errno == errno.ENOSPC
        with pytest.raises(OSError, match="failed earlier"):
            late.commit()
        held.commit()
        replace = fs.open_write("/upload/old.png", exclusive=False)  # the old one not counted
        replace.write(0, bytes(500))
        replace.commit()
        assert sorted(os.listdir(fs.upload_dir)) == ["a.png", "old.png"]

    def test_exclusive_create_refuses_an_existing_file(self, fs: MemoryFileSystem) -> None:
        (fs.upload_dir / "goal.png").write_bytes(b"old")
        with pytest.raises(FileExistsError):
            fs.open_write("/upload/goal.png", exclusive=True).commit()
        replace = fs.open_write("/upload/goal.png", exclusive=False)
        replace.write(0, b"new")
        replace.commit()
        assert (fs.upload_dir / "goal.png").read_bytes() == b"new"

    def test_discard_and_remove(self, fs: MemoryFileSystem) -> None:
        upload = fs.open_write("/upload/goal.png", exclusive=True)
        upload.write(0, b"abc")
        upload.discard()
        assert os.listdir(fs.upload_dir) == []
        (fs.upload_dir / "old.png").write_bytes(b"x")
        fs.remove("/upload/old.png")
        assert os.listdir(fs.upload_dir) == []
        with pytest.raises(FileNotFoundError):
            fs.remove("/upload/old.png")
