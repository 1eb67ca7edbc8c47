"""Hostile memory folders (issue 15): one-line errors, nothing inflated before the checks.

Each case is crafted by :mod:`tools.bench.hostile_files` into a valid memory; before the
fix they gave RecursionError, OverflowError, MemoryError, NotImplementedError, or
inflated the npz bomb (the test measures the allocations with tracemalloc).
"""

from __future__ import annotations

import shutil
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shared.errors import MemoryFormatError
from shared.memory import read_memory
from shared.memory.store import MANIFEST_NAME, features_path
from tools.bench import hostile_files

CASES = {
    "deep_json_manifest": (hostile_files.deep_json_manifest, "nest more than 32 deep"),
    "huge_int_manifest": (hostile_files.huge_int_manifest, "is outside [-2^63, 2^63)"),
    "absurd_shape_npz": (hostile_files.absurd_shape_npz,
                         "pixels_xy: shape (1099511627776, 2) has 1099511627776 along axis 0, "
                         "more than the 480000 allowed"),
    "overflowing_shape_npz": (hostile_files.overflowing_shape_npz,
                              "more than the 480000 allowed"),
    "unparsable_npy_header": (hostile_files.unparsable_npy_header,
                              "pixels_xy: its .npy header does not parse"),
    "zip_version_npz": (hostile_files.zip_version_npz,
                        "unsupported zip archive: zip file version 6.4"),
    "zip_method_npz": (hostile_files.zip_method_npz,
                       "pixels_xy.npy: zip compression method 99 is not supported"),
    "npz_bomb": (lambda d: hostile_files.npz_bomb(d, mib=96),
                 "its arrays declare 100663744 bytes uncompressed, more than the 67108864"),
}
MAX_TRACED_BYTES = 16 * 2**20
"""What loading any of them may allocate (the valid key image read first included)."""


@pytest.fixture(scope="module")
def valid(tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("valid") / "memory"
    hostile_files.write_valid_memory(directory, seed=0)
    return directory


@pytest.mark.parametrize("case", CASES)
def test_hostile_memory_gives_one_line_without_allocating(
    valid: Path, tmp_path: Path, case: str
) -> None:
    damage, fragment = CASES[case]
    directory = tmp_path / "memory"
    shutil.copytree(valid, directory)
    damage(directory)
    before = {p: p.read_bytes() for p in directory.rglob("*") if p.is_file()}
    tracemalloc.start()
    try:
        with pytest.raises(MemoryFormatError) as error:
            read_memory(directory)
        peak_bytes = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    message = str(error.value)
    assert "\n" not in message and fragment in message
    bad_file = directory / MANIFEST_NAME if "manifest" in case else features_path(directory, 0)
    assert error.value.where == str(bad_file)
    assert peak_bytes < MAX_TRACED_BYTES
    assert {p: p.read_bytes() for p in directory.rglob("*") if p.is_file()} == before


def test_a_features_file_larger_than_the_limit_is_not_read(valid: Path, tmp_path: Path) -> None:
    directory = tmp_path / "memory"
    shutil.copytree(valid, directory)
    with open(features_path(directory, 1), "r+b") as f:
        f.truncate(100 * 2**20)  # sparse: 100 MB on paper, nothing on disk
    tracemalloc.start()
    try:
        with pytest.raises(MemoryFormatError, match="104857600 bytes, more than the 67174400"):
            read_memory(directory)
        assert tracemalloc.get_traced_memory()[1] < MAX_TRACED_BYTES
    finally:
        tracemalloc.stop()


# -- fuzz: mutated manifests and features files load or give a MemoryFormatError --------

_MUTATION = st.tuples(
    st.sampled_from(["flip", "truncate", "insert"]),
    st.floats(0.0, 1.0),
    st.binary(min_size=1, max_size=8),
)


def _mutate(data: bytes, mutation: tuple[str, float, bytes]) -> bytes:
    kind, where, payload = mutation
    at = int(where * (len(data) - 1))
    if kind == "flip":
        return data[:at] + bytes(b ^ p for b, p in zip(data[at:], payload, strict=False)) + \
            data[at + len(payload):]
    if kind == "truncate":
        return data[:at]
    return data[:at] + payload + data[at:]


@settings(derandomize=True, max_examples=80, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.sampled_from(["manifest", "features"]), mutations=st.lists(_MUTATION,
                                                                            min_size=1,
                                                                            max_size=3))
def test_fuzz_mutated_memory_loads_or_gives_a_memory_format_error(
    valid: Path, tmp_path: Path, which: str, mutations: list[tuple[str, float, bytes]]
) -> None:
    directory = tmp_path / "fuzzed"
    shutil.rmtree(directory, ignore_errors=True)
    shutil.copytree(valid, directory)
    path = directory / MANIFEST_NAME if which == "manifest" else features_path(directory, 1)
    data = path.read_bytes()
    for mutation in mutations:
        data = _mutate(data, mutation)
    path.write_bytes(data)
    try:
        memory = read_memory(directory)
    except MemoryFormatError as e:
        assert "\n" not in str(e)
    else:
        assert len(memory.keyframes) >= 1


def test_fortran_order_and_compressed_features_load_as_numpy_reads_them(
    valid: Path, tmp_path: Path
) -> None:
    """The checked reader reads what np.savez_compressed and Fortran-ordered arrays give."""
    directory = tmp_path / "memory"
    shutil.copytree(valid, directory)
    keyframe = read_memory(directory).keyframes[1]
    path = features_path(directory, 1)
    np.savez_compressed(path.with_suffix(""), pixels_xy=np.asfortranarray(keyframe.pixels_xy),
                        patches=np.asfortranarray(keyframe.patches))
    reread = read_memory(directory).keyframes[1]
    assert np.array_equal(reread.pixels_xy, keyframe.pixels_xy)
    assert np.array_equal(reread.patches, keyframe.patches)
