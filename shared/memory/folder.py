"""Opening a memory folder to add paths to: the memory it holds, or a new one.

Every command that writes a memory (``vmnav teach``, ``vmnav memory build``, ``vmnav
demo``, ``vmnav robot``, the benchmarks' cached memories) opens its folder with
:func:`open_or_create` before any work, so that none writes into a folder holding files
it did not write, nor adds paths taken with another camera.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path
from typing import TYPE_CHECKING

from shared.errors import InputError

if TYPE_CHECKING:
    from shared.camera_model import CameraModel
    from shared.memory.graph import VisualMemory


def open_or_create(folder: Path, camera: CameraModel | None) -> VisualMemory:
    """The memory in ``folder`` to add to, or a new, empty one; checked before any work.

    Nothing is written: a missing ``folder`` is only checked to be creatable
    (:func:`shared.memory.write_memory` creates it).

    Args:
        folder: the memory's folder.
        camera: the camera the new key images are taken with. A stored memory must have
            been taught with it; a new memory gets it. None: a stored memory keeps its own
            camera, a new memory gets :meth:`~shared.camera_model.CameraModel.default`.

    Raises:
        InputError: ``folder`` is not a folder, cannot be created or is not writable, or
            ``camera`` is given and the stored memory was taught with another.
        MemoryFormatError: the stored memory does not load, or ``folder`` holds files but
            no manifest (a new memory would be written over files it did not write).
    """
    from shared.calibration import camera_to_dict
    from shared.camera_model import CameraModel
    from shared.memory.graph import VisualMemory
    from shared.memory.store import MANIFEST_NAME, check_no_orphans, read_memory

    _check_writable(folder)
    check_no_orphans(folder)
    if not (folder / MANIFEST_NAME).exists():
        return VisualMemory(CameraModel.default() if camera is None else camera)
    memory = read_memory(folder)
    if camera is not None and camera_to_dict(memory.camera) != camera_to_dict(camera):
        raise InputError(folder, "holds a memory taught with another camera than the one given")
    return memory


def _check_writable(folder: Path) -> None:
    """Raise :class:`InputError` unless ``folder`` is a writable folder or can be made one."""
    if folder.exists():
        if not folder.is_dir():
            raise InputError(folder, "is not a folder")
        if not os.access(folder, os.W_OK | os.X_OK):
            raise InputError(folder, "the memory folder is not writable")
        return
    ancestor = next(p for p in folder.absolute().parents if p.exists())
    problem = (errno.ENOTDIR if not ancestor.is_dir()
               else None if os.access(ancestor, os.W_OK | os.X_OK) else errno.EACCES)
    if problem is not None:
        raise InputError(folder, f"cannot create the memory folder: {os.strerror(problem)}")
