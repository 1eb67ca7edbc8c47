from __future__ import annotations

import json
from pathlib import Path

import cv2
import pytest

from tools.cli import main


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


class TestSnapshot:
    def test_writes_frame_map_and_json(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code, out, _ = run(
            [
                "sim",
                "snapshot",
                "--world",
                "lab",
                "--seed",
                "1",
                "--out",
                str(tmp_path),
                "--x",
                "8",
                "--y",
                "10",
            ],
            capsys,
        )
        assert code == 0
        assert "landmarks visible" in out
        frame = cv2.imread(str(tmp_path / "frame.png"), cv2.IMREAD_UNCHANGED)
        assert frame.shape == (600, 800)
        topdown = cv2.imread(str(tmp_path / "map.png"), cv2.IMREAD_UNCHANGED)
        assert topdown.ndim == 3 and topdown.shape[2] == 3
        summary = json.loads((tmp_path / "snapshot.json").read_text())
        assert summary["pose_w"] == {"x_m": 8.0, "y_m": 10.0, "yaw_deg": 0.0}
        assert summary["visible_landmarks"] == len(summary["visible"]) > 20
        assert summary["world"] == "lab"
        assert summary["sensor"]["mean_grey"] == pytest.approx(110.0, abs=15.0)  # auto-exposure
        assert summary["sensor"]["blur_px"] == 0.0  # standing still
        assert all(0 <= v["u_px"] < 800 and 0 <= v["v_px"] < 600 for v in summary["visible"])

    def test_campus_and_start_pose(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code, _, _ = run(["sim", "snapshot", "--world", "campus", "--out", str(tmp_path)], capsys)
        assert code == 0
        assert json.loads((tmp_path / "snapshot.json").read_text())["world"] == "campus"

    @pytest.mark.parametrize(("world", "x", "y"), [("campus", "22", "10"), ("building", "20", "6")])
    def test_the_readme_pictures(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str], world: str, x: str, y: str
    ) -> None:
        code, _, _ = run(["sim", "snapshot", "--world", world, "--seed", "1", "--x", x, "--y", y,
                          "--yaw", "0", "--out", str(tmp_path)], capsys)
        assert code == 0
        summary = json.loads((tmp_path / "snapshot.json").read_text())
        assert summary["world"] == world and summary["visible_landmarks"] > 5

    @pytest.mark.parametrize(
        ("args", "fragment"),
        [
            (["--world", "moon"], "moon"),
            (["--x", "1"], "give both --x and --y"),
            (["--x", "0.0", "--y", "10.0"], "--x/--y/--yaw: (0.0, 10.0, 0.0 deg) overlaps a wall"),
            (["--x", "1e9", "--y", "10.0"], "--x/--y/--yaw: (1000000000.0, 10.0, 0.0 deg) is "
             "outside world 'lab' (x 0 to 30 m, y 0 to 20 m)"),
            (["--calibration", "/nonexistent/camera.json"], "/nonexistent/camera.json"),
            (["--config", "/nonexistent/vmnav.toml"], "/nonexistent/vmnav.toml"),
            (["--doors", "nosuch=open"], "scene change: world 'lab' has no door named 'nosuch'"),
        ],
    )
    def test_bad_input_is_one_line_and_exit_1(
        self, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], fragment: str
    ) -> None:
        code, _, err = run(["sim", "snapshot", "--out", str(tmp_path), *args], capsys)
        assert code == 1
        assert err.count("\n") == 1 and err.startswith("vmnav sim: error:")
        assert fragment in err
        assert "Traceback" not in err

    def test_malformed_world_file(self, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
        world = tmp_path / "bad.toml"
        world.write_text(
            'name = "bad"\nstart = { x_m = 1.0, y_m = 1.0 }\n'
            "walls = [{ start = [0, 0], end = [0, 0], height_m = 2.0 }]\n"
        )
        code, _, err = run(
            ["sim", "snapshot", "--world", str(world), "--out", str(tmp_path / "o")], capsys
        )
        assert code == 1
        assert str(world) in err and err.count("\n") == 1


class TestChangedSnapshot:
    ROOM = """
name = "room"
start = { x_m = 1.0, y_m = 2.0 }
walls = [
    { start = [0.0, 0.0], end = [8.0, 0.0], height_m = 2.5 },
    { start = [8.0, 0.0], end = [8.0, 4.0], height_m = 2.5 },
    { start = [8.0, 4.0], end = [0.0, 4.0], height_m = 2.5 },
    { start = [0.0, 4.0], end = [0.0, 0.0], height_m = 2.5 },
]
pictures = [{ at = [7.8, 2.0], texture = "poster_rocket", height_m = 1.4, name = "rocket" }]
objects = [
    { kind = "box", center = [4.0, 1.2], size = [0.8, 0.8], height_m = 1.5, movable = true },
]
"""

    def snapshot(self, tmp_path: Path, capsys: pytest.CaptureFixture[str], name: str,
                 *change: str) -> tuple[int, object]:
        world = tmp_path / "room.toml"
        world.write_text(self.ROOM)
        code, _, _ = run(["sim", "snapshot", "--world", str(world), "--out", str(tmp_path / name),
                          *change], capsys)
        return code, cv2.imread(str(tmp_path / name / "frame.png"), cv2.IMREAD_GRAYSCALE)

    def test_the_frame_shows_the_change(self, tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
        code_a, taught = self.snapshot(tmp_path, capsys, "taught")
        code_b, again = self.snapshot(tmp_path, capsys, "again")
        code_c, changed = self.snapshot(tmp_path, capsys, "changed", "--moved", "1",
                                        "--removed", "rocket")
        assert code_a == code_b == code_c == 0
        assert (taught == again).all()
        assert (cv2.absdiff(taught, changed) > 40).sum() > 500


def test_help_lists_only_working_commands(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    listed = [  # a command's line, not a help text's continuation
        line.split()[0] for line in out.split("options:")[0].splitlines()
        if line.startswith("    ") and line[4] != " "
    ]
    assert listed == ["sim", "calibrate", "bench", "memory", "teach", "demo", "pioneer", "robot",
                      "log", "replay", "ground", "vision", "sweep"]


def test_version_is_the_installed_package_s(capsys: pytest.CaptureFixture[str]) -> None:
    import importlib.metadata

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out == f"vmnav {importlib.metadata.version('vmnav')}\n"
