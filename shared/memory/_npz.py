"""Reading an ``.npz`` archive whose every size is checked before anything is inflated.

``np.load`` trusts the file: it allocates the shape an ``.npy`` header declares (a 622 KB
archive can ask for gigabytes), and lets zipfile raise NotImplementedError on an entry it
cannot read. Here, in this order, nothing being allocated beyond the archive's bytes until
the last step:

1. the zip directory: only the expected ``<name>.npy`` entries, each once, stored or
   deflated (what ``np.savez`` and ``np.savez_compressed`` write), not encrypted, and the
   sum of their declared uncompressed sizes within the caller's limit;
2. each entry's ``.npy`` header, read by numpy's own reader (``read_magic``,
   ``read_array_header_1_0/2_0``) from the first inflated bytes: the dtype and the shape
   against the caller's spec and limits, and the entry's declared size against the
   header's (zipfile stops inflating at the declared size and checks the CRC);
3. the array's bytes, exactly as many as the header declares.
"""

from __future__ import annotations

import io
import math
import zipfile
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from pathlib import Path
from tokenize import TokenError
from typing import IO, Any

import numpy as np
import numpy.typing as npt

from shared.errors import MemoryFormatError, ShapeError, check_shape

_NPY_MAGIC = b"\x93NUMPY"
_ZIP_METHODS = frozenset({zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED})
_HEADER_READERS = {(1, 0): np.lib.format.read_array_header_1_0,
                   (2, 0): np.lib.format.read_array_header_2_0}


@dataclass(frozen=True)
class ArraySpec:
    """What one array of the archive must be.

    Attributes:
        dtype: its exact dtype (native byte order), e.g. ``np.dtype(np.float64)``.
        shape: its shape, ``None`` for an axis of any length (as :func:`check_shape`).
        max_shape: the longest each axis may be, e.g. ``(width * height, 2)``.
    """

    dtype: np.dtype[Any]
    shape: tuple[int | None, ...]
    max_shape: tuple[int, ...]


def read_npz(
    path: Path,
    data: bytes,
    specs: Mapping[str, ArraySpec],
    required: Collection[str],
    max_bytes: int,
) -> dict[str, npt.NDArray[Any]]:
    """The arrays of the ``.npz`` archive ``data`` read from ``path``, checked as the
    module docstring says.

    Args:
        path: the file, for the messages.
        data: its bytes.
        specs: every array the archive may hold, by name (without ``.npy``).
        required: the names it must hold.
        max_bytes: the most the entries may declare, uncompressed, together, bytes.

    Returns:
        The arrays by name, read-only views of freshly inflated buffers.

    Raises:
        MemoryFormatError: naming ``path`` and the first problem found.
    """
    if data.startswith(_NPY_MAGIC):
        raise MemoryFormatError(path, "expected an .npz archive, got a single .npy array")
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            entries = _check_directory(path, archive.infolist(), specs, required, max_bytes)
            return {name: _read_entry(path, archive, info, name, specs[name])
                    for name, info in entries.items()}
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as e:
        raise MemoryFormatError(path, f"not a valid .npz archive (truncated?): {e}") from None
    except NotImplementedError as e:  # zipfile: a version, method or flag it cannot read
        raise MemoryFormatError(path, f"unsupported zip archive: {e}") from None


def _check_directory(
    path: Path,
    infos: list[zipfile.ZipInfo],
    specs: Mapping[str, ArraySpec],
    required: Collection[str],
    max_bytes: int,
) -> dict[str, zipfile.ZipInfo]:
    names = [info.filename.removesuffix(".npy") for info in infos]
    optional = [name for name in specs if name not in required]
    if (len(set(names)) != len(names) or not set(required) <= set(names) <= set(specs)
            or any(not info.filename.endswith(".npy") for info in infos)):
        raise MemoryFormatError(
            path, f"expected arrays {list(required)} (and optionally {optional}), got "
            f"{sorted(names)}")
    for info in infos:
        if info.compress_type not in _ZIP_METHODS:
            raise MemoryFormatError(
                path, f"{info.filename}: zip compression method {info.compress_type} is not "
                "supported (only stored or deflated)")
        if info.flag_bits & 0x1:
            raise MemoryFormatError(path, f"{info.filename}: encrypted (refused)")
    declared = sum(info.file_size for info in infos)
    if declared > max_bytes:
        raise MemoryFormatError(
            path, f"its arrays declare {declared} bytes uncompressed, more than the "
            f"{max_bytes} bytes allowed")
    return dict(zip(names, infos, strict=True))


def _read_entry(
    path: Path, archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str, spec: ArraySpec
) -> npt.NDArray[Any]:
    with archive.open(info) as member:
        shape, fortran_order, dtype = _read_header(path, member, name)
        _check_header(path, name, shape, dtype, spec)
        n_bytes = math.prod(shape) * dtype.itemsize
        header_bytes = member.tell()
        if info.file_size != header_bytes + n_bytes:
            raise MemoryFormatError(
                path, f"{name}: the zip entry declares {info.file_size} bytes, its .npy "
                f"header {header_bytes + n_bytes} (a {shape} {dtype.name} array)")
        payload = member.read(n_bytes + 1)  # one more: inflate to the end, check the CRC
    if len(payload) != n_bytes:
        raise MemoryFormatError(path, f"{name}: holds {len(payload)} bytes of data, its "
                                f"header declares {n_bytes}")
    return np.frombuffer(payload, dtype=dtype).reshape(shape, order="F" if fortran_order else "C")


def _read_header(path: Path, member: IO[bytes], name: str) -> tuple[tuple[int, ...], bool,
                                                                    np.dtype[Any]]:
    try:
        version = np.lib.format.read_magic(member)
        reader = _HEADER_READERS.get(version)
        if reader is None:
            raise ValueError(f".npy format version {version[0]}.{version[1]} is not supported")
        shape, fortran_order, dtype = reader(member)
    except (SyntaxError, TokenError):  # numpy parses the header's text as Python
        raise MemoryFormatError(path, f"{name}: its .npy header does not parse") from None
    except ValueError as e:
        problem = "holds pickled objects (refused)" if "pickle" in str(e) else str(e)
        raise MemoryFormatError(path, f"{name}: {problem}") from None
    return shape, fortran_order, dtype


def _check_header(
    path: Path, name: str, shape: tuple[int, ...], dtype: np.dtype[Any], spec: ArraySpec
) -> None:
    if dtype.hasobject:
        raise MemoryFormatError(path, f"{name}: holds pickled objects (refused)")
    try:
        check_shape(name, shape, spec.shape)
    except ShapeError as e:
        raise MemoryFormatError(path, str(e)) from None
    if dtype != spec.dtype:  # the same name in the other byte order shows as e.g. >f8
        got = dtype.str if dtype.name == spec.dtype.name else dtype.name
        raise MemoryFormatError(path, f"{name}: expected dtype {spec.dtype.name}, got {got}")
    for axis, (length, longest) in enumerate(zip(shape, spec.max_shape, strict=True)):
        if not 0 <= length <= longest:
            raise MemoryFormatError(
                path, f"{name}: shape {shape} has {length} along axis {axis}, more than the "
                f"{longest} allowed")
