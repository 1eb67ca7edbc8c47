"""``vmnav teach --sim`` (tools/teach_cmd.py): two short routes taught into one memory."""

from __future__ import annotations

import contextlib
import io
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from shared.memory import read_memory, write_memory
from tests.shared.memory.builders import folder_bytes, loop_memory, memory_without_manifest
from tests.tools.short_routes import write_short_routes_world
from tools.cli import main


def run(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


@dataclass(frozen=True)
class Taught:
    world: Path
    memory: Path
    first: tuple[int, str, str]
    second: tuple[int, str, str]


@pytest.fixture(scope="module")
def taught(tmp_path_factory: pytest.TempPathFactory) -> Taught:
    folder = tmp_path_factory.mktemp("teach")
    world = write_short_routes_world(folder)
    memory = folder / "mem" / "lab"
    teach = ["teach", "--sim", "--world", str(world), "--memory", str(memory), "--route"]
    return Taught(world, memory, run([*teach, "east_a"]), run([*teach, "east_b"]))


@pytest.mark.slow
class TestTeach:
    def test_the_first_route_makes_a_new_memory(self, taught: Taught) -> None:
        code, out, err = taught.first
        assert code == 0, err
        assert "taught route 'east_a' as path 0:" in out
        assert "key images per metre" in out and "junctions made: 0" in out
        memory = read_memory(taught.memory)
        path = memory.paths[0]
        assert path.name == "east_a"
        # About 2.5 m of corridor at about two key images per metre.
        length_m = memory.keyframes[path.keyframe_ids[-1]].distance_m
        assert 2.3 <= length_m <= 2.7
        assert 3 <= len(path.keyframe_ids) <= 12

    def test_the_second_route_joins_the_first_where_it_starts(self, taught: Taught) -> None:
        code, out, err = taught.second
        assert code == 0, err
        assert "taught route 'east_b' as path 1:" in out and "junctions made: 1" in out
        memory = read_memory(taught.memory)
        assert [p.name for p in memory.paths.values()] == ["east_a", "east_b"]
        (junction,) = memory.junctions
        end_of_a = memory.paths[0].keyframe_ids[-1]
        start_of_b = memory.paths[1].keyframe_ids[0]
        assert junction.pair == {end_of_a, start_of_b}
        assert junction.matches >= 40
        start, goal = memory.paths[0].keyframe_ids[0], memory.paths[1].keyframe_ids[-1]
        route = memory.plan_route(start, goal)
        assert route[0] == start and route[-1] == goal and end_of_a in route

    def test_another_front_end_is_refused_before_driving(self, taught: Taught,
                                                         tmp_path: Path) -> None:
        config = tmp_path / "teblid.toml"
        config.write_text('[features]\nmethod = "teblid"\n')
        before = (taught.memory / "manifest.json").read_bytes()
        code, out, err = run(["teach", "--sim", "--world", str(taught.world), "--memory",
                              str(taught.memory), "--route", "corridor", "--config", str(config)])
        assert code != 0 and out == ""
        assert err.strip().splitlines() == [
            "vmnav teach: error: visual memory: its key images were described by front end "
            "'orb, 31 px window', the config's [features] makes 'teblid, 31 px window': set "
            "[features] method = 'orb' (and its window) as when it was taught, or teach again"]
        assert (taught.memory / "manifest.json").read_bytes() == before


class TestBadInput:
    @pytest.mark.parametrize(
        ("args", "message"),
        [
            (["--route", "nope"], "--route: unknown route 'nope' in world 'lab' (known: corridor, "
             "office_loop, north_loop, east_a, east_b)"),
            (["--route", "east_a", "--world", "atlantis"], "atlantis: unknown world (built-in:"),
        ],
    )
    def test_unknown_route_or_world(
        self, taught: Taught, tmp_path: Path, args: list[str], message: str
    ) -> None:
        argv = ["teach", "--sim", "--world", str(taught.world), "--memory", str(tmp_path / "m")]
        code, out, err = run(argv + args)
        assert code == 1 and out == ""
        assert err.startswith("vmnav teach: error: ") and message in err
        assert err.count("\n") == 1

    def test_a_file_where_the_memory_folder_should_be(self, tmp_path: Path) -> None:
        (tmp_path / "file").write_text("x")
        memory = str(tmp_path / "file")
        code, _, err = run(["teach", "--sim", "--route", "corridor", "--memory", memory])
        assert code == 1 and "file: is not a folder" in err

    def test_a_memory_folder_that_cannot_be_created(self, tmp_path: Path) -> None:
        (tmp_path / "file").write_text("x")
        memory = str(tmp_path / "file" / "mem")
        code, _, err = run(["teach", "--sim", "--route", "corridor", "--memory", memory])
        assert code == 1 and "cannot create the memory folder: Not a directory" in err

    @pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere")
    def test_an_unwritable_memory_folder(self, tmp_path: Path) -> None:
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        memory = str(locked / "m")
        code, _, err = run(["teach", "--sim", "--route", "corridor", "--memory", memory])
        assert code == 1 and "cannot create the memory folder" in err

    @pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere")
    def test_a_read_only_existing_folder(self, tmp_path: Path) -> None:
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        code, _, err = run(["teach", "--sim", "--route", "corridor", "--memory", str(locked)])
        assert code == 1 and "the memory folder is not writable" in err

    def test_only_the_simulator_for_now(self, tmp_path: Path) -> None:
        code, _, err = run(["teach", "--route", "corridor", "--memory", str(tmp_path)])
        assert code == 1 and "only --sim is available" in err

    def test_a_corrupt_memory_is_refused_before_driving(self, tmp_path: Path) -> None:
        (tmp_path / "manifest.json").write_text("{")
        code, _, err = run(["teach", "--sim", "--route", "corridor", "--memory", str(tmp_path)])
        assert code == 1 and "manifest.json" in err

    def test_files_without_a_manifest_are_not_taught_over(
        self, tmp_path: Path, rng: np.random.Generator
    ) -> None:
        before = memory_without_manifest(tmp_path, rng)
        code, out, err = run(["teach", "--sim", "--route", "corridor", "--memory", str(tmp_path)])
        assert (code, out) == (1, "")
        assert err == (f"vmnav teach: error: memory {tmp_path}: manifest.json missing but the "
                       "folder holds 21 files; restore it or point --memory to an empty folder\n")
        assert folder_bytes(tmp_path) == before

    def test_a_memory_of_another_camera_is_not_added_to(
        self, tmp_path: Path, rng: np.random.Generator
    ) -> None:
        write_memory(tmp_path, loop_memory(rng))  # a small camera, not the simulated one
        before = folder_bytes(tmp_path)
        code, out, err = run(["teach", "--sim", "--route", "corridor", "--memory", str(tmp_path)])
        assert (code, out) == (1, "")
        assert err == (f"vmnav teach: error: {tmp_path}: holds a memory taught with another "
                       "camera than the one given\n")
        assert folder_bytes(tmp_path) == before
