from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from shared.memory import Junction, memory_summary, read_memory, write_memory
from tests.shared.memory.builders import loop_memory, make_records
from tools.cli import main


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def memory_dir(tmp_path: Path, rng: np.random.Generator) -> Path:
    """The loop memory plus a spur (7-9) that leaves from key image 2 and never comes back."""
    memory = loop_memory(rng)
    spur = memory.add_path("spur", make_records(rng, memory.camera, [0.5, 0.5]))
    memory.add_junction(Junction(spur.keyframe_ids[0], 2, 61))
    write_memory(tmp_path / "mem", memory)
    return tmp_path / "mem"


def test_info_text(memory_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(["memory", "info", "--memory", str(memory_dir)], capsys)
    assert code == 0 and err == ""
    lines = out.splitlines()
    assert lines[0] == "10 key images on 3 paths, 4.50 m taught; camera 160x120 px, 185 deg"
    assert "  0 'corridor': 4 key images (0..3), 1.50 m, spacing mean 0.500 m" in out
    assert "(2.00 key images/m)" in out
    assert "  7 (path 2) <-> 2 (path 0), 61 matches" in out
    assert "strongly connected: no (3 components)" in out
    assert "  cannot reach the main component: 8-9" in out
    assert "  not reachable from the main component: none" in out


def test_info_json_is_the_summary(memory_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(["memory", "info", "--json", "--memory", str(memory_dir)], capsys)
    assert code == 0
    summary = json.loads(out)
    assert summary == memory_summary(read_memory(memory_dir))
    assert summary["connectivity"]["unreachable_ids"] == [8, 9]


@pytest.mark.parametrize(
    ("damage", "fragment"),
    [
        (lambda d: (d / "manifest.json").unlink(), "manifest.json: file not found"),
        (lambda d: (d / "images" / "4.png").write_bytes(b""), "4.png: file is empty"),
    ],
)
def test_bad_memory_is_one_line_and_exit_1(
    memory_dir: Path, capsys: pytest.CaptureFixture[str], damage: object, fragment: str
) -> None:
    damage(memory_dir)  # type: ignore[operator]
    code, out, err = run(["memory", "info", "--memory", str(memory_dir)], capsys)
    assert code == 1 and out == ""
    assert err.startswith("vmnav memory: error: ") and err.count("\n") == 1
    assert fragment in err and str(memory_dir) in err


def test_needs_a_subcommand(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["memory"])
    assert exit_.value.code == 2
    assert "required: SUBCOMMAND" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["memory", "--help"])
    assert "    info " in capsys.readouterr().out


class TestRoute:
    def test_plans_across_a_junction(
        self, memory_dir: Path, capsys: pytest.CaptureFixture[str]
    ) -> None:
        code, out, _ = run(["memory", "route", "--memory", str(memory_dir), "2", "5"], capsys)
        assert code == 0
        # 2 -> 3 along the corridor (0.5 m), junction 3 <-> 4 (0 m), 4 -> 5 along "back" (1 m).
        assert out.splitlines() == [
            "route from key image 2 to 5: 4 key images, 1.50 m, 1 junction(s), "
            "along corridor -> back",
            "  2 3 4 5",
        ]

    def test_json(self, memory_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
        code, out, _ = run(["memory", "route", "--json", "--memory", str(memory_dir), "5", "1"],
                           capsys)
        assert code == 0
        report = json.loads(out)
        assert report["keyframe_ids"] == [5, 6, 0, 1]
        assert report["paths"] == ["back", "corridor"]

    def test_unknown_goal_id(self, memory_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
        code, _, err = run(["memory", "route", "--memory", str(memory_dir), "0", "99"], capsys)
        assert code == 1 and err.count("\n") == 1
        assert "no key image with id 99" in err

    def test_unreachable_goal(self, memory_dir: Path, capsys: pytest.CaptureFixture[str]) -> None:
        code, _, err = run(["memory", "route", "--memory", str(memory_dir), "8", "0"], capsys)
        assert code == 1 and err.count("\n") == 1
        assert "cannot be reached from key image 8" in err
