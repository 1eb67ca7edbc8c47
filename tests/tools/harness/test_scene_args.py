"""The scene-change options (``--lighting``, ``--moved``) of ``vmnav demo`` and ``vmnav bench
follow``: parsed into a SceneChange, bad values refused in one line."""

from __future__ import annotations

import argparse
import dataclasses
import logging
from pathlib import Path

import pytest

from shared.errors import InputError
from sim.config import SimConfig
from sim.scene_change import LightingChange, SceneChange
from tools.cli import main
from tools.harness.scene_args import (
    add_change_arguments,
    check_change_fits,
    doors_from_text,
    lighting_from_text,
    scene_change_from_args,
)

EMPTY_ROOM = Path(__file__).parent / "empty_room.toml"


class TestLightingFromText:
    def test_every_change(self) -> None:
        assert lighting_from_text("scale=0.7, lamps-off=0.5, hour=17, step=0.5@20") == (
            LightingChange(scale=0.7, lamps_off=0.5, hour=17.0, step_factor=0.5,
                           step_at_s=20.0))
        assert lighting_from_text("step=2@0") == LightingChange(step_factor=2.0)
        assert lighting_from_text("lamps-off=all") == LightingChange(lamps_off=1.0)

    @pytest.mark.parametrize(("text", "message"), [
        ("dark", "'dark' is not KEY=VALUE"),
        ("hue=3", "unknown change 'hue' (known: scale=..., lamps-off=..., hour=..., step=...)"),
        ("scale=0.5,scale=0.6", "scale is given twice"),
        ("scale=bright", "scale: 'bright' is not a number"),
        ("lamps-off=most", "lamps-off: 'most' is not a number"),
        ("step=0.5", "step wants FACTOR@SECONDS, got '0.5'"),
        ("step=0.5@soon", "step: 'soon' is not a number"),
        ("scale=-1", "scale must be > 0, got -1.0"),
        ("hour=30", "hour must be in [0, 24], got 30.0"),
        ("step=0.5@-3", "step time must be >= 0 s"),
    ])
    def test_bad_text_names_the_problem(self, text: str, message: str) -> None:
        with pytest.raises(InputError, match=r"^--lighting: ") as info:
            lighting_from_text(text)
        assert message in str(info.value)


class TestDoorsFromText:
    def test_open_closed_and_degrees(self) -> None:
        assert doors_from_text("front=open, back=closed, side=45") == (
            ("front", 90.0), ("back", 0.0), ("side", 45.0))

    @pytest.mark.parametrize(("text", "message"), [
        ("front", "'front' is not KEY=VALUE"),
        ("front=ajar", "front: 'ajar' is not a number"),
        ("a=open,a=closed", "a is given twice"),
    ])
    def test_bad_text_names_the_problem(self, text: str, message: str) -> None:
        with pytest.raises(InputError, match=r"^--doors: ") as info:
            doors_from_text(text)
        assert message in str(info.value)


def parsed(*args: str):
    parser = argparse.ArgumentParser()
    add_change_arguments(parser)
    return scene_change_from_args(parser.parse_args(list(args)))


def test_the_options_make_one_scene_change() -> None:
    assert parsed() == SceneChange()
    assert parsed("--moved", "0.2", "--removed", "0.5", "--doors", "front=closed",
                  "--lighting", "hour=8") == SceneChange(
        lighting=LightingChange(hour=8.0), moved_fraction=0.2, removed_fraction=0.5,
        doors=(("front", 0.0),))
    assert parsed("--removed", "rocket, exit").removed == ("rocket", "exit")


@pytest.mark.parametrize("command", [["demo", "--no-video"], ["bench", "follow"]])
@pytest.mark.parametrize(("args", "message"), [
    (["--moved", "1.5"], "--moved: moved fraction must be in [0, 1], got 1.5"),
    (["--lighting", "scale=0"], "--lighting: scale must be > 0"),
    (["--removed", "2"], "--removed: removed fraction must be in [0, 1], got 2.0"),
    (["--removed", " , "], "--removed: names nothing"),
    (["--doors", "front=400"], "--doors: door 'front': opening must be in [-180, 180]"),
    (["--doors", "nosuchdoor=open"], "scene change: world 'lab' has no door named 'nosuchdoor'"),
    (["--removed", "nosuchthing"], "scene change: world 'lab' has no picture or object named "
                                   "'nosuchthing'"),
    (["--landmark-dropout", "0.3"], "--landmark-dropout: was removed: the fiducial landmarks "
                                    "are gone; say what changed with --lighting, --moved, "
                                    "--removed, --doors and --people"),
])
def test_bad_options_are_one_line(tmp_path, capsys, command, args, message) -> None:
    code = main([*command, "--out", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and message in err
    assert not (tmp_path / "out").exists()


def test_a_share_of_nothing_is_warned_about(caplog) -> None:
    with caplog.at_level(logging.WARNING):
        check_change_fits(SceneChange(moved_fraction=0.2, lighting=LightingChange(lamps_off=0.1)),
                          dataclasses.replace(SimConfig(), world=str(EMPTY_ROOM)))
    assert [r.getMessage() for r in caplog.records] == [
        "--lighting lamps-off 0.1 changes nothing: world 'room' has 0 lit lamps",
        "--moved 0.2 changes nothing: world 'room' has 0 movable objects"]
