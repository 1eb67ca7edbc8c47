"""Opening or creating a memory to add paths to (shared/memory/folder.py): every check before
any work, and nothing written."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import numpy as np
import pytest

from shared.calibration import camera_to_dict
from shared.camera_model import CameraModel
from shared.errors import InputError, MemoryFormatError
from shared.memory import open_or_create, write_memory
from tests.shared.memory.builders import (
    folder_bytes,
    loop_memory,
    memory_without_manifest,
    small_camera,
)

ROOT = os.geteuid() == 0


class TestNewMemory:
    @pytest.mark.parametrize("camera", [None, small_camera()])
    def test_a_missing_folder_starts_an_empty_memory_and_is_not_created(
        self, tmp_path: Path, camera: CameraModel | None
    ) -> None:
        folder = tmp_path / "new" / "memory"
        memory = open_or_create(folder, camera)
        assert (memory.keyframes, memory.paths, memory.junctions) == ({}, {}, ())
        expected = CameraModel.default() if camera is None else camera
        assert camera_to_dict(memory.camera) == camera_to_dict(expected)
        assert not (tmp_path / "new").exists()

    def test_empty_sub_folders_are_no_files(self, tmp_path: Path) -> None:
        (tmp_path / "images").mkdir()
        memory = open_or_create(tmp_path, None)
        assert memory.keyframes == {}


class TestStoredMemory:
    def test_is_read_with_its_own_camera_when_none_is_given(
        self, tmp_path: Path, rng: np.random.Generator
    ) -> None:
        stored = loop_memory(rng)
        write_memory(tmp_path, stored)
        memory = open_or_create(tmp_path, None)
        assert memory.keyframes.keys() == stored.keyframes.keys()
        assert camera_to_dict(memory.camera) == camera_to_dict(stored.camera)
        assert memory.junctions == stored.junctions

    def test_is_read_when_given_its_camera(self, tmp_path: Path, rng: np.random.Generator) -> None:
        write_memory(tmp_path, loop_memory(rng))
        assert len(open_or_create(tmp_path, small_camera()).paths) == 2

    def test_another_camera_is_refused(self, tmp_path: Path, rng: np.random.Generator) -> None:
        write_memory(tmp_path, loop_memory(rng))
        before = folder_bytes(tmp_path)
        other = dataclasses.replace(small_camera(), fov_deg=180.0)
        with pytest.raises(InputError, match="holds a memory taught with another camera") as e:
            open_or_create(tmp_path, other)
        assert e.value.where == str(tmp_path)
        assert folder_bytes(tmp_path) == before

    def test_a_manifest_that_does_not_load_is_refused(self, tmp_path: Path) -> None:
        (tmp_path / "manifest.json").write_text("{")
        with pytest.raises(MemoryFormatError, match=r"manifest\.json"):
            open_or_create(tmp_path, None)


class TestRefusedFolders:
    @pytest.mark.parametrize("camera", [None, CameraModel.default()])
    def test_files_without_a_manifest_are_refused_and_kept(
        self, tmp_path: Path, rng: np.random.Generator, camera: CameraModel | None
    ) -> None:
        before = memory_without_manifest(tmp_path / "memory", rng)
        with pytest.raises(MemoryFormatError) as e:
            open_or_create(tmp_path / "memory", camera)
        assert str(e.value) == (f"memory {tmp_path / 'memory'}: manifest.json missing but the "
                                "folder holds 21 files; restore it or point --memory to an "
                                "empty folder")
        assert folder_bytes(tmp_path / "memory") == before

    def test_a_file(self, tmp_path: Path) -> None:
        (tmp_path / "file").write_text("x")
        with pytest.raises(InputError, match="file: is not a folder"):
            open_or_create(tmp_path / "file", None)

    def test_a_folder_under_a_file(self, tmp_path: Path) -> None:
        (tmp_path / "file").write_text("x")
        with pytest.raises(InputError, match="cannot create the memory folder: Not a directory"):
            open_or_create(tmp_path / "file" / "a" / "memory", None)

    @pytest.mark.skipif(ROOT, reason="root writes anywhere")
    def test_a_read_only_folder(self, tmp_path: Path) -> None:
        (tmp_path / "locked").mkdir(mode=0o500)
        with pytest.raises(InputError, match="locked: the memory folder is not writable"):
            open_or_create(tmp_path / "locked", None)

    @pytest.mark.skipif(ROOT, reason="root writes anywhere")
    def test_a_folder_that_cannot_be_created(self, tmp_path: Path) -> None:
        (tmp_path / "locked").mkdir(mode=0o500)
        with pytest.raises(InputError, match="cannot create the memory folder: Permission denied"):
            open_or_create(tmp_path / "locked" / "memory", None)
