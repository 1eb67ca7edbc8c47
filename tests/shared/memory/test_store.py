from __future__ import annotations

import io
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest

import shared.atomic_file
from shared.calibration import camera_to_dict
from shared.errors import InputError, MemoryFormatError
from shared.memory import Junction, VisualMemory, add_path_to_disk, read_memory, write_memory
from shared.memory.store import (
    features_path,
    files_without_manifest,
    image_path,
    thumbnail_path,
)
from tests.shared.memory.builders import loop_memory, make_records, small_camera
from tools.bench.hostile_images import large_png


def assert_same_memory(a: VisualMemory, b: VisualMemory) -> None:
    assert camera_to_dict(a.camera) == camera_to_dict(b.camera)
    assert a.front_end == b.front_end
    assert a.paths == b.paths and a.junctions == b.junctions
    assert a.keyframes.keys() == b.keyframes.keys()
    for i, ka in a.keyframes.items():
        kb = b.keyframes[i]
        assert (ka.path_id, ka.index, ka.t_ns, ka.odom_pose, ka.distance_m) == (
            kb.path_id, kb.index, kb.t_ns, kb.odom_pose, kb.distance_m
        )
        for name in ("image", "pixels_xy", "patches", "thumbnail", "tracked_from_previous"):
            x, y = getattr(ka, name), getattr(kb, name)
            assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()


@pytest.fixture
def stored(tmp_path: Path, rng: np.random.Generator) -> tuple[Path, VisualMemory]:
    directory = tmp_path / "mem"
    memory = loop_memory(rng)
    write_memory(directory, memory)
    return directory, memory


class TestRoundTrip:
    def test_bit_identical(self, stored: tuple[Path, VisualMemory]) -> None:
        directory, memory = stored
        assert_same_memory(read_memory(directory), memory)
        manifest = json.loads((directory / "manifest.json").read_text())
        assert (manifest["format"], manifest["format_version"]) == ("vmnav-memory", 2)
        assert sorted(p.name for p in (directory / "images").iterdir()) == [
            f"{i}.png" for i in range(7)
        ]

    def test_manifest_has_one_key_image_per_line(self, stored: tuple[Path, VisualMemory]) -> None:
        lines = (stored[0] / "manifest.json").read_text().splitlines()
        assert sum('"odom_pose"' in line for line in lines) == 7

    def test_empty_memory(self, tmp_path: Path) -> None:
        write_memory(tmp_path, VisualMemory(small_camera()))
        assert read_memory(tmp_path).keyframes == {}

    def test_front_end_recorded(self, tmp_path: Path, rng: np.random.Generator) -> None:
        memory = VisualMemory(small_camera())
        memory.add_path("corridor", make_records(rng, memory.camera, [1.0]), "orb, 31 px window")
        write_memory(tmp_path, memory)
        assert read_memory(tmp_path).front_end == "orb, 31 px window"

    def test_version_1_reads_as_unknown_front_end(
        self, stored: tuple[Path, VisualMemory]
    ) -> None:
        directory, memory = stored
        data = json.loads((directory / "manifest.json").read_text())
        data["format_version"] = 1
        del data["front_end"]
        (directory / "manifest.json").write_text(json.dumps(data))
        old = read_memory(directory)
        assert old.front_end is None
        assert_same_memory(old, memory)


class TestAdding:
    def test_add_path_to_disk_creates_then_extends(
        self, tmp_path: Path, rng: np.random.Generator
    ) -> None:
        camera = small_camera()
        records = make_records(rng, camera, [1.0])
        first = add_path_to_disk(tmp_path / "m", camera, "corridor", records)
        png_before = image_path(tmp_path / "m", 0).read_bytes()
        second = add_path_to_disk(
            tmp_path / "m", camera, "hall", make_records(rng, camera, [0.5, 0.5], t0_ns=7)
        )
        assert (first.keyframe_ids, second.keyframe_ids) == ((0, 1), (2, 3, 4))
        memory = read_memory(tmp_path / "m")
        assert [p.name for p in memory.paths.values()] == ["corridor", "hall"]
        assert image_path(tmp_path / "m", 0).read_bytes() == png_before

    def test_add_path_to_disk_refuses_another_camera(
        self, stored: tuple[Path, VisualMemory], rng: np.random.Generator
    ) -> None:
        other = small_camera(200, 150)
        with pytest.raises(InputError, match="another camera calibration"):
            add_path_to_disk(stored[0], other, "x", make_records(rng, other, [1.0]))

    def test_path_of_another_front_end_refused(self, tmp_path: Path,
                                               rng: np.random.Generator) -> None:
        memory = VisualMemory(small_camera())
        memory.add_path("corridor", make_records(rng, memory.camera, [1.0]), "orb, 31 px window")
        with pytest.raises(MemoryFormatError, match="taught with front end 'teblid, 31 px "
                                                    "window', but the memory's key images"):
            memory.add_path("hall", make_records(rng, memory.camera, [1.0]),
                            "teblid, 31 px window")
        assert len(memory.paths) == 1
        memory.add_path("hall", make_records(rng, memory.camera, [1.0]), "orb, 31 px window")
        assert memory.front_end == "orb, 31 px window"

    def test_unknown_front_end_stays_unknown(self, stored: tuple[Path, VisualMemory],
                                             rng: np.random.Generator) -> None:
        memory = read_memory(stored[0])
        memory.add_path("spur", make_records(rng, memory.camera, [0.5]), "orb, 31 px window")
        assert memory.front_end is None  # its older key images' front end is still unknown

    def test_read_modify_write_with_junctions(
        self, stored: tuple[Path, VisualMemory], rng: np.random.Generator
    ) -> None:
        directory, _ = stored
        memory = read_memory(directory)
        spur = memory.add_path("spur", make_records(rng, memory.camera, [0.5]))
        memory.add_junction(Junction(spur.keyframe_ids[0], 2, 44))
        write_memory(directory, memory)
        again = read_memory(directory)
        assert_same_memory(again, memory)
        assert again.plan_route(0, spur.keyframe_ids[-1]) == [0, 1, 2, *spur.keyframe_ids]

    def test_refuses_a_memory_that_drops_or_changes_what_is_stored(
        self, stored: tuple[Path, VisualMemory], rng: np.random.Generator
    ) -> None:
        directory, memory = stored
        described = VisualMemory.from_parts(memory.camera, memory.keyframes.values(),
                                            memory.paths.values(), memory.junctions, "sift")
        write_memory(directory, described)  # an unknown front end becomes known
        before = (directory / "manifest.json").read_bytes()
        unjoined = VisualMemory.from_parts(
            memory.camera, memory.keyframes.values(), memory.paths.values(), memory.junctions[:1],
            "sift")
        other = VisualMemory(memory.camera)
        other.add_path("corridor", make_records(rng, memory.camera, [0.5, 0.5, 0.5]), "sift")
        relabelled = VisualMemory.from_parts(memory.camera, memory.keyframes.values(),
                                             memory.paths.values(), memory.junctions, "orb")
        cases = [
            (relabelled, "described by front end 'sift', these by 'orb'"),
            (unjoined, "its junction 6 -> 0 is missing here"),
            (other, "its key image 0 is missing or different here"),
            (VisualMemory(small_camera(200, 150)), "another camera calibration"),
        ]
        for new, fragment in cases:
            with pytest.raises(InputError, match=fragment):
                write_memory(directory, new)
        assert (directory / "manifest.json").read_bytes() == before


class TestInterruptedWrite:
    @pytest.mark.parametrize(
        ("failing_call", "exception"),
        [
            (1, OSError(28, "No space left on device")),
            (4, KeyboardInterrupt()),
            (10, OSError(5, "Input/output error")),
        ],
    )
    def test_old_memory_still_loads(
        self,
        stored: tuple[Path, VisualMemory],
        rng: np.random.Generator,
        monkeypatch: pytest.MonkeyPatch,
        failing_call: int,
        exception: BaseException,
    ) -> None:
        # Adding a 3-key-image path makes 9 data files and then the manifest (call 10).
        directory, memory = stored
        calls = []
        real_replace = os.replace

        def replace(src: str, dst: str | Path) -> None:
            calls.append(dst)
            if len(calls) == failing_call:
                raise exception
            real_replace(src, dst)

        monkeypatch.setattr(shared.atomic_file.os, "replace", replace)
        bigger = read_memory(directory)
        bigger.add_path("new", make_records(rng, memory.camera, [0.5, 0.5]))
        with pytest.raises((InputError, KeyboardInterrupt)):
            write_memory(directory, bigger)
        assert len(calls) == failing_call
        monkeypatch.undo()
        assert_same_memory(read_memory(directory), memory)
        assert not [p for p in directory.rglob("*.tmp")]
        write_memory(directory, bigger)  # the next write completes the job
        assert_same_memory(read_memory(directory), bigger)


# -- bad input: each case damages a stored memory, loading must name the file and the problem ----

Corruption = Callable[[Path], Path]


def edit_manifest(change: Callable[[dict[str, Any]], object]) -> Corruption:
    def corrupt(directory: Path) -> Path:
        path = directory / "manifest.json"
        data = json.loads(path.read_text())
        change(data)
        path.write_text(json.dumps(data))
        return path

    return corrupt


def write_file(where: Callable[[Path], Path], content: Callable[[Path], bytes]) -> Corruption:
    def corrupt(directory: Path) -> Path:
        path = where(directory)
        path.write_bytes(content(path))
        return path

    return corrupt


def png(image: np.ndarray) -> bytes:
    return cv2.imencode(".png", image)[1].tobytes()


def npz(**arrays: Any) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    return buffer.getvalue()


def remove(where: Callable[[Path], Path]) -> Corruption:
    def corrupt(directory: Path) -> Path:
        where(directory).unlink()
        return where(directory)

    return corrupt


def image3(d: Path) -> Path:
    return image_path(d, 3)


def features3(d: Path) -> Path:
    return features_path(d, 3)


def thumb3(d: Path) -> Path:
    return thumbnail_path(d, 3)


def manifest(d: Path) -> Path:
    return d / "manifest.json"


GOOD_XY = np.zeros((12, 2))
GOOD_PATCHES = np.zeros((12, 25), np.float32)

BAD_INPUT: dict[str, tuple[Corruption, str]] = {
    "no manifest": (remove(manifest), "file not found: not a visual memory"),
    "truncated manifest": (
        write_file(manifest, lambda p: p.read_bytes()[:200]), r"not valid JSON \(truncated\?\)"
    ),
    "NaN in manifest": (
        write_file(
            manifest,
            lambda p: p.read_bytes().replace(b'"distance_m": 0.5', b'"distance_m": NaN'),
        ),
        "NaN is not a JSON number",
    ),
    "not an object": (write_file(manifest, lambda p: b"[1, 2]"), "JSON object, got an array"),
    "wrong format": (edit_manifest(lambda d: d.update(format="vmnav-camera")), "format: expected"),
    "future version": (edit_manifest(lambda d: d.update(format_version=3)), "version 3 is not"),
    "front end not text": (edit_manifest(lambda d: d.update(front_end=7)),
                           "front_end: expected null or a printable text"),
    "front end in version 1": (edit_manifest(lambda d: d.update(format_version=1)),
                               "unknown field 'front_end'"),
    "version as text": (edit_manifest(lambda d: d.update(format_version="1")), "version '1' is"),
    "missing field": (edit_manifest(lambda d: d.pop("junctions")), "missing field 'junctions'"),
    "unknown field": (edit_manifest(lambda d: d.update(extra=1)), "unknown field 'extra'"),
    "paths not a list": (edit_manifest(lambda d: d.update(paths={})), "paths: expected a JSON"),
    "bad camera": (
        edit_manifest(lambda d: d["camera"].update(xi=-1.0)), "camera: xi: must be >= 0"
    ),
    "key image field missing": (
        edit_manifest(lambda d: d["keyframes"][2].pop("distance_m")),
        "keyframes\\[2\\]: missing field 'distance_m'",
    ),
    "key image id negative": (
        edit_manifest(lambda d: d["keyframes"][2].update(id=-2)),
        "keyframes\\[2\\]: id: expected an integer >= 0",
    ),
    "key image distance negative": (
        edit_manifest(lambda d: d["keyframes"][1].update(distance_m=-1.0)),
        "keyframes\\[1\\]: key image 1: distance_m: must be >= 0",
    ),
    "key image pose text": (
        edit_manifest(lambda d: d["keyframes"][1].update(odom_pose=["a", 0, 0])),
        "key image 1: odom_pose: expected a finite number",
    ),
    "path name empty": (
        edit_manifest(lambda d: d["paths"][1].update(name="")), "paths\\[1\\]: path 1: name"
    ),
    "duplicate key image ids": (
        edit_manifest(lambda d: d["keyframes"].append(dict(d["keyframes"][3]))),
        "key image 3: duplicate key image id",
    ),
    "duplicate path ids": (
        edit_manifest(lambda d: d["paths"][1].update(id=0)), "path 0 'back': duplicate path id"
    ),
    "dangling id in a path": (
        edit_manifest(lambda d: d["paths"][0]["keyframe_ids"].append(55)), "lists key image 55"
    ),
    "dangling id in a junction": (
        edit_manifest(lambda d: d["junctions"][0].update(to_id=77)), "key image 77 does not exist"
    ),
    "key image on two paths": (
        edit_manifest(lambda d: d["paths"][1]["keyframe_ids"].insert(0, 3)),
        "key image 3: is already on path 0",
    ),
    "missing image": (remove(image3), "file not found"),
    "empty image file": (write_file(image3, lambda p: b""), "file is empty"),
    "truncated image": (write_file(image3, lambda p: p.read_bytes()[:300]), "truncated PNG"),
    "not a PNG": (write_file(image3, lambda p: npz(a=GOOD_XY)), "not a PNG file"),
    "corrupt PNG": (
        write_file(image3, lambda p: p.read_bytes()[:60] + bytes(100) + p.read_bytes()[-12:]),
        "corrupt PNG",
    ),
    "colour image": (
        write_file(image3, lambda p: png(np.zeros((120, 160, 3), np.uint8))), "got 3 channels"
    ),
    "16-bit image": (
        write_file(image3, lambda p: png(np.zeros((120, 160), np.uint16))),
        "expected dtype uint8, got uint16",
    ),
    "image of the wrong size": (
        write_file(image3, lambda p: png(np.zeros((600, 800), np.uint8))),
        "expected 160x120 px, got 800x600 px",
    ),
    "thumbnail of the wrong size": (
        write_file(thumb3, lambda p: png(np.zeros((120, 160), np.uint8))),
        "expected 80x60 px, got 160x120 px",
    ),
    "PNG bomb": (write_file(image3, lambda p: large_png(8192)), "more than the 33554432 allowed"),
    "missing features": (remove(features3), "file not found"),
    "truncated features": (
        write_file(features3, lambda p: p.read_bytes()[:500]), "not a valid .npz archive"
    ),
    "pickled features": (
        write_file(features3, lambda p: npz(pixels_xy=np.array([None]), patches=GOOD_PATCHES)),
        "holds pickled objects",
    ),
    "npy not npz": (
        write_file(features3, lambda p: (np.save(b := io.BytesIO(), GOOD_XY), b.getvalue())[1]),
        "expected an .npz archive",
    ),
    "wrong array names": (
        write_file(features3, lambda p: npz(xy=GOOD_XY, patches=GOOD_PATCHES)),
        "expected arrays \\['pixels_xy', 'patches'\\]",
    ),
    "pixels_xy shape": (
        write_file(features3, lambda p: npz(pixels_xy=np.zeros((12, 3)), patches=GOOD_PATCHES)),
        "pixels_xy: expected shape \\(N, 2\\), got \\(12, 3\\)",
    ),
    "patches dtype": (
        write_file(features3, lambda p: npz(pixels_xy=GOOD_XY, patches=np.zeros((12, 25)))),
        "patches: expected dtype float32, got float64",
    ),
    "row counts differ": (
        write_file(features3, lambda p: npz(pixels_xy=GOOD_XY[:5], patches=GOOD_PATCHES)),
        "5 corners in pixels_xy but 12 rows in patches",
    ),
    "unknown feature array": (
        write_file(
            features3, lambda p: npz(pixels_xy=GOOD_XY, patches=GOOD_PATCHES, extra=GOOD_XY)
        ),
        "optionally \\['tracked_from_previous'\\]\\), got \\['extra', ",
    ),
    "tracks out of range": (
        write_file(features3, lambda p: npz(pixels_xy=GOOD_XY, patches=GOOD_PATCHES,
                                            tracked_from_previous=np.array([[0, 12]]))),
        "tracked_from_previous: corner 12 of this key image, which has 12",
    ),
    "descriptor length differs": (
        write_file(
            features3, lambda p: npz(pixels_xy=GOOD_XY, patches=np.zeros((12, 9), np.float32))
        ),
        "patches: descriptors have 9 values, the memory's have 25",
    ),
}


@pytest.mark.parametrize("case", BAD_INPUT)
def test_bad_input_names_the_file_and_the_problem(
    stored: tuple[Path, VisualMemory], case: str
) -> None:
    corrupt, fragment = BAD_INPUT[case]
    bad_file = corrupt(stored[0])
    with pytest.raises(MemoryFormatError, match=fragment) as error:
        read_memory(stored[0])
    assert error.value.where == str(bad_file)
    assert "\n" not in str(error.value)


def test_features_without_tracks_load_with_none(stored: tuple[Path, VisualMemory]) -> None:
    # Memories written before the tracks were stored hold only pixels_xy and patches.
    directory, memory = stored
    keyframe = memory.keyframes[3]
    features3(directory).write_bytes(npz(pixels_xy=keyframe.pixels_xy, patches=keyframe.patches))
    assert len(keyframe.tracked_from_previous) > 0
    assert read_memory(directory).keyframes[3].tracked_from_previous.shape == (0, 2)


def test_missing_folder(tmp_path: Path) -> None:
    with pytest.raises(MemoryFormatError, match="no such folder"):
        read_memory(tmp_path / "nowhere")


class TestFilesWithoutManifest:
    def test_none_in_a_memory_an_empty_folder_or_no_folder(
        self, stored: tuple[Path, VisualMemory], tmp_path: Path
    ) -> None:
        assert files_without_manifest(stored[0]) == 0
        (tmp_path / "empty" / "images").mkdir(parents=True)
        assert files_without_manifest(tmp_path / "empty") == 0
        assert files_without_manifest(tmp_path / "nowhere") == 0
        (tmp_path / "a_file").write_text("not a folder")
        assert files_without_manifest(tmp_path / "a_file") == 0

    def test_a_memory_that_lost_its_manifest_counts_its_key_image_files(
        self, stored: tuple[Path, VisualMemory]
    ) -> None:
        directory, memory = stored
        (directory / "manifest.json").unlink()
        # image, features and thumbnail of each key image, in sub-folders.
        assert files_without_manifest(directory) == 3 * len(memory.keyframes) == 21
        (directory / "notes.txt").write_text("top-level files count too")
        assert files_without_manifest(directory) == 22


def test_write_refuses_to_replace_an_unreadable_memory(stored: tuple[Path, VisualMemory]) -> None:
    directory, memory = stored
    (directory / "manifest.json").write_text("{")
    with pytest.raises(MemoryFormatError, match="not valid JSON"):
        write_memory(directory, memory)
    assert (directory / "manifest.json").read_text() == "{"
