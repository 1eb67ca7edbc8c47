"""Opening a memory folder to add paths to: the memory it holds, or a new one."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import InputError

if TYPE_CHECKING:
    from shared.camera_model import CameraModel
    from shared.memory.graph import VisualMemory


def open_memory(directory: Path, camera: CameraModel) -> VisualMemory:
    """The memory in ``directory`` to add to, or a new one; checked before any driving.

    Raises:
        InputError: ``directory`` is not a writable folder, or holds a memory taught
            with another camera.
        MemoryFormatError: the memory in ``directory`` does not load, or ``directory`` holds
            files but no manifest (a new memory would be written over them).
    """
    from shared.calibration import camera_to_dict
    from shared.memory import VisualMemory, read_memory
    from shared.memory.store import MANIFEST_NAME, check_no_orphans

    if directory.exists() and not directory.is_dir():
        raise InputError(directory, "is not a folder")
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(directory, f"cannot create the memory folder: {e.strerror}") from None
    if not os.access(directory, os.W_OK | os.X_OK):
        raise InputError(directory, "the memory folder is not writable")
    check_no_orphans(directory)
    if not (directory / MANIFEST_NAME).exists():
        return VisualMemory(camera)
    memory = read_memory(directory)
    if camera_to_dict(memory.camera) != camera_to_dict(camera):
        raise InputError(
            directory, "the memory was taught with another camera than the simulated one"
        )
    return memory
