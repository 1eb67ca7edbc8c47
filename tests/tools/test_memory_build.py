"""``vmnav memory build`` (robot/memory/path_from_log.py) from a ``vmnav teach --sim --log`` drive,
rotated into several files."""

from __future__ import annotations

import dataclasses
import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from robot.memory.path_from_log import Odometry
from shared.config import LogConfig
from shared.logs import topics
from shared.logs.messages import FrameTransform
from shared.logs.writer import LogWriter
from shared.memory import read_memory
from tests.shared.memory.builders import folder_bytes, memory_without_manifest
from tests.tools.short_routes import write_short_routes_world
from tests.tools.test_teach_cmd import run

#: At the default JPEG quality (85) the artefacts cost tracks: east_a gave 12 key images
#: from its log against 9 taught directly; at 95, 10. The log rotates every 4 s of the
#: drive: a series of files.
CONFIG = "[log]\njpeg_quality = 95\nrotate_period_ns = 4000000000\n"


@dataclass(frozen=True)
class Built:
    config: Path
    taught: Path
    log: Path
    series: tuple[Path, ...]
    teach: tuple[int, str, str]
    built: Path
    build: tuple[int, str, str]


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> Built:
    folder = tmp_path_factory.mktemp("build")
    world = write_short_routes_world(folder)
    config = folder / "vmnav.toml"
    config.write_text(CONFIG)
    taught, logs, memory = folder / "taught", folder / "logs", folder / "built"
    teach = run(["teach", "--sim", "--world", str(world), "--route", "east_a", "--memory",
                 str(taught), "--log", str(logs), "--config", str(config)])
    log = logs / "teach-east_a-0001.mcap"
    build = run(["memory", "build", str(log), "--memory", str(memory), "--config", str(config)])
    return Built(config, taught, log, tuple(sorted(logs.glob("teach-east_a-*.mcap"))), teach,
                 memory, build)


@pytest.mark.slow
class TestBuild:
    def test_teach_records_its_log(self, built: Built) -> None:
        code, out, err = built.teach
        assert code == 0, err
        assert len(built.series) > 2 and built.series[0] == built.log
        assert f"log {', '.join(map(str, built.series))}: " in out and "dropped" not in out

    def test_the_log_builds_the_path_taught_directly(self, built: Built) -> None:
        code, out, err = built.build
        assert code == 0, err
        assert out.startswith(f"built path 0 'teach-east_a-0001' from {built.log} "
                              f"(+{len(built.series) - 1} files): ")
        assert "left out" not in out  # every frame has its odometry at the same time
        assert "junctions made: 0" in out and f"memory {built.built}: 1 paths" in out
        taught, memory = read_memory(built.taught), read_memory(built.built)
        (a,), (b,) = taught.paths.values(), memory.paths.values()
        assert abs(len(b.keyframe_ids) - len(a.keyframe_ids)) <= 0.3 * len(a.keyframe_ids)
        # The same drive: the same first and last frames, times and odometry.
        for ia, ib in ((a.keyframe_ids[0], b.keyframe_ids[0]),
                       (a.keyframe_ids[-1], b.keyframe_ids[-1])):
            ka, kb = taught.keyframes[ia], memory.keyframes[ib]
            assert ka.t_ns == kb.t_ns
            np.testing.assert_allclose(kb.odom_pose, ka.odom_pose, atol=1e-9)
            assert kb.distance_m == pytest.approx(ka.distance_m, abs=1e-9)

    def test_memory_info_reads_it(self, built: Built) -> None:
        code, out, err = run(["memory", "info", "--memory", str(built.built)])
        assert code == 0, err
        assert "1 paths" in out and "'teach-east_a-0001'" in out

    def test_a_path_built_into_a_memory_is_joined(self, built: Built, tmp_path: Path) -> None:
        memory = tmp_path / "mem"
        shutil.copytree(built.taught, memory)
        code, out, err = run(["memory", "build", str(built.log), "--memory", str(memory),
                              "--name", "again", "--config", str(built.config)])
        assert code == 0, err
        assert out.startswith("built path 1 'again'")
        joined = read_memory(memory)
        assert [p.name for p in joined.paths.values()] == ["east_a", "again"]
        assert joined.junctions  # its ends localize on the same route's ends


    def test_the_files_of_a_series_given_in_any_order(self, built: Built,
                                                      tmp_path: Path) -> None:
        memory = tmp_path / "mem"
        code, _, err = run(["memory", "build", *map(str, reversed(built.series)), "--memory",
                              str(memory), "--name", "again", "--config", str(built.config)])
        assert code == 0, err
        (a,), (b,) = read_memory(built.built).paths.values(), read_memory(memory).paths.values()
        assert a.keyframe_ids == b.keyframe_ids


class TestOdometry:
    def test_poses_between_logged_ones_are_interpolated(self) -> None:
        yaw = np.unwrap([3.0, -3.0])  # across +-pi: the short way round
        odometry = Odometry(np.array([100, 200]), np.array([0.0, 1.0]), np.array([2.0, 4.0]),
                            yaw)
        assert odometry.pose_at(100) == pytest.approx((0.0, 2.0, 3.0))
        x, y, heading = odometry.pose_at(150)
        assert (x, y) == pytest.approx((0.5, 3.0))
        assert abs(heading) == pytest.approx(math.pi, abs=1e-9)
        assert odometry.pose_at(99) is None and odometry.pose_at(201) is None


def write_log(folder: Path, frames: bool, odometry: bool, shape: tuple[int, int]) -> Path:
    with LogWriter(LogConfig(output_dir=str(folder)), "drive") as writer:
        for i in range(3):
            t_ns = i * 100_000_000
            if frames:
                writer.log_image(t_ns, topics.CAMERA_IMAGE, np.full(shape, 50 * i, np.uint8))
            if odometry:
                writer.log_transform(t_ns, [FrameTransform.planar(
                    topics.FRAME_ODOM, topics.FRAME_BASE, 0.1 * i, 0.0, 0.0)])
    return folder / "drive-0001.mcap"


class TestBadInput:
    @pytest.mark.parametrize(
        ("frames", "odometry", "shape", "message"),
        [
            (False, True, (600, 800), "drive-0001.mcap: no camera frames (no messages on "
             "/camera/image/compressed)"),
            (True, False, (600, 800), "drive-0001.mcap: no odometry (no messages on /tf)"),
            (True, True, (60, 80), "drive-0001.mcap: camera frame at 0 ns: is 80x60 px; the "
             "memory's camera takes 800x600 px"),
        ],
    )
    def test_a_log_without_what_teaching_needs(
        self, tmp_path: Path, frames: bool, odometry: bool, shape: tuple[int, int], message: str
    ) -> None:
        log = write_log(tmp_path / "logs", frames, odometry, shape)
        memory = tmp_path / "mem"
        code, out, err = run(["memory", "build", str(log), "--memory", str(memory)])
        assert code == 1 and out == ""
        assert err.startswith("vmnav memory: error: ") and message in err
        assert err.count("\n") == 1
        assert not memory.exists()

    def test_odometry_of_other_frames_only(self, tmp_path: Path) -> None:
        with LogWriter(LogConfig(output_dir=str(tmp_path)), "drive") as writer:
            writer.log_image(0, topics.CAMERA_IMAGE, np.zeros((600, 800), np.uint8))
            writer.log_transform(0, [FrameTransform(topics.FRAME_BASE, topics.FRAME_CAMERA)])
        code, _, err = run(["memory", "build", str(tmp_path / "drive-0001.mcap"), "--memory",
                            str(tmp_path / "mem")])
        assert code == 1 and "no odometry: no odom -> base_link transform on /tf" in err

    def test_frames_outside_the_odometry(self, tmp_path: Path) -> None:
        with LogWriter(LogConfig(output_dir=str(tmp_path)), "drive") as writer:
            writer.log_image(0, topics.CAMERA_IMAGE, np.zeros((600, 800), np.uint8))
            for t_ns in (500_000_000, 600_000_000):
                writer.log_transform(t_ns, [FrameTransform.planar(
                    topics.FRAME_ODOM, topics.FRAME_BASE, 0.0, 0.0, 0.0)])
        code, _, err = run(["memory", "build", str(tmp_path / "drive-0001.mcap"), "--memory",
                            str(tmp_path / "mem")])
        assert code == 1 and "no camera frame lies within the odometry's span (1 frames" in err
        assert not (tmp_path / "mem").exists()

    def test_a_gap_in_the_series(self, built: Built, tmp_path: Path) -> None:
        memory = tmp_path / "mem"
        first, missing, third = built.series[:3]
        code, out, err = run(["memory", "build", str(first), str(third), "--memory",
                              str(memory)])
        assert code == 1 and out == "" and err.count("\n") == 1
        assert (f"{missing}: missing from the series: a gap between {first.name} and "
                f"{third.name}") in err
        assert not memory.exists()

    def test_two_drives_that_overlap(self, tmp_path: Path) -> None:
        a = write_log(tmp_path / "a", True, True, (600, 800))
        b = write_log(tmp_path / "b", True, True, (600, 800))
        code, _, err = run(["memory", "build", str(a), str(b), "--memory", str(tmp_path / "m")])
        assert code == 1 and f"{b}: overlaps {a}: it starts at 0.000 s" in err

    def test_not_an_mcap_file_leaves_the_memory_untouched(self, built: Built,
                                                          tmp_path: Path) -> None:
        memory = tmp_path / "mem"
        shutil.copytree(built.taught, memory)
        manifest = (memory / "manifest.json").read_text()
        bad = tmp_path / "drive.mcap"
        bad.write_text("not a log")
        code, out, err = run(["memory", "build", str(bad), "--memory", str(memory)])
        assert code == 1 and out == "" and err.count("\n") == 1
        assert "drive.mcap: not an MCAP file" in err
        assert (memory / "manifest.json").read_text() == manifest

    def test_a_camera_file_that_is_not_the_memorys(self, built: Built, tmp_path: Path) -> None:
        from shared.calibration import write_camera
        from shared.camera_model import CameraModel

        camera = tmp_path / "camera.json"
        write_camera(camera, dataclasses.replace(CameraModel.default(), fov_deg=180.0))
        before = folder_bytes(built.taught)
        code, out, err = run(["memory", "build", str(built.log), "--memory", str(built.taught),
                              "--calibration", str(camera)])
        assert (code, out) == (1, "")
        assert err == (f"vmnav memory: error: {built.taught}: holds a memory taught with another "
                       "camera than the one given\n")
        assert folder_bytes(built.taught) == before

    def test_files_without_a_manifest_are_not_built_over(
        self, built: Built, tmp_path: Path, rng: np.random.Generator
    ) -> None:
        memory = tmp_path / "mem"
        before = memory_without_manifest(memory, rng)
        code, out, err = run(["memory", "build", str(built.log), "--memory", str(memory)])
        assert (code, out) == (1, "")
        assert err == (f"vmnav memory: error: memory {memory}: manifest.json missing but the "
                       "folder holds 21 files; restore it or point --memory to an empty folder\n")
        assert folder_bytes(memory) == before
