"""The scene-change options (``--lighting``, ``--moved``) of ``vmnav demo`` and ``vmnav bench
follow``: parsed into a SceneChange, bad values refused in one line."""

from __future__ import annotations

import pytest

from shared.errors import InputError
from sim.scene_change import LightingChange
from tools.cli import main
from tools.harness.scene_args import lighting_from_text


class TestLightingFromText:
    def test_scale_and_step(self) -> None:
        assert lighting_from_text("scale=0.7, step=0.5@20") == LightingChange(
            scale=0.7, step_factor=0.5, step_at_s=20.0)
        assert lighting_from_text("step=2@0") == LightingChange(step_factor=2.0)

    @pytest.mark.parametrize(("text", "message"), [
        ("dark", "unknown change 'dark' (known: scale=..., step=...)"),
        ("hue=3", "unknown change 'hue=3'"),
        ("scale=0.5,scale=0.6", "scale is given twice"),
        ("scale=bright", "scale: 'bright' is not a number"),
        ("step=0.5", "step wants FACTOR@SECONDS, got '0.5'"),
        ("step=0.5@soon", "step: 'soon' is not a number"),
        ("scale=-1", "scale must be > 0, got -1.0"),
        ("step=0.5@-3", "step time must be >= 0 s"),
    ])
    def test_bad_text_names_the_problem(self, text: str, message: str) -> None:
        with pytest.raises(InputError, match=r"^--lighting: ") as info:
            lighting_from_text(text)
        assert message in str(info.value)


@pytest.mark.parametrize("command", [["demo", "--no-video"], ["bench", "follow"]])
@pytest.mark.parametrize(("args", "message"), [
    (["--moved", "1.5"], "--moved: moved fraction must be in [0, 1], got 1.5"),
    (["--lighting", "scale=0"], "--lighting: scale must be > 0"),
    (["--landmark-dropout", "0.3"], "--landmark-dropout: was removed: the fiducial landmarks "
                                    "are gone; say what changed with --lighting, --moved and "
                                    "--people"),
])
def test_bad_options_are_one_line(tmp_path, capsys, command, args, message) -> None:
    code = main([*command, "--out", str(tmp_path / "out"), *args])
    err = capsys.readouterr().err
    assert code == 1 and err.count("\n") == 1 and message in err
    assert not (tmp_path / "out").exists()
