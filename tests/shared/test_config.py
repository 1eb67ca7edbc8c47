from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pytest

from shared.config import SimConfig, VmnavConfig, from_mapping, load_config, require
from shared.errors import ConfigError


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "vmnav.toml"
    path.write_text(text)
    return path


class TestLoadConfig:
    def test_none_gives_defaults(self) -> None:
        assert load_config(None) == VmnavConfig()

    def test_values_and_nested_tables(self, tmp_path: Path) -> None:
        cfg = load_config(
            write(
                tmp_path,
                '[sim]\nworld = "campus"\nseed = 7\n'
                "[sim.body]\nmax_speed_m_s = 0.5\n[sim.people]\ncount = 3\n",
            )
        )
        assert cfg.sim.world == "campus"
        assert cfg.sim.seed == 7
        assert cfg.sim.body.max_speed_m_s == 0.5
        assert cfg.sim.body.accel_m_s2 == SimConfig().body.accel_m_s2
        assert cfg.sim.people.count == 3

    def test_int_accepted_for_float(self, tmp_path: Path) -> None:
        assert (
            load_config(write(tmp_path, "[sim.render]\nnoise_sigma = 3\n")).sim.render.noise_sigma
            == 3.0
        )

    @pytest.mark.parametrize(
        ("text", "fragment"),
        [
            ('[sim]\nseed = "one"\n', "sim.seed: expected an integer, got str 'one'"),
            ("[sim]\nsed = 1\n", "sim: unknown key 'sed'"),
            ("[sim.body]\nmax_speed_m_s = -1\n", "sim.body: max_speed_m_s must be > 0, got -1.0"),
            (
                "[sim.render]\nnoise_sigma = nan\n",
                "sim.render.noise_sigma: expected a finite number",
            ),
            (
                "[sim.render]\nnoise_sigma = inf\n",
                "sim.render.noise_sigma: expected a finite number",
            ),
            ("[sim]\nbody = 3\n", "sim.body: expected a table"),
            ("[sim.people]\ncount = true\n", "sim.people.count: expected an integer"),
            ("[sim]\nframe_period_ns = 1000\n", "frame_period_ns (1000) must be >= physics_dt_ns"),
            ("[sim\n", "not valid TOML"),
            ('[mission]\nbase_lost_action = "stop"\n',
             "base_lost_action must be one of hold, continue, got 'stop'"),
            ("[pioneer]\nreport_timeout_ns = 0\n", "report_timeout_ns must be > 0, got 0"),
        ],
    )
    def test_bad_input_names_file_key_and_problem(
        self, tmp_path: Path, text: str, fragment: str
    ) -> None:
        path = write(tmp_path, text)
        with pytest.raises(ConfigError) as err:
            load_config(path)
        message = str(err.value)
        assert message.startswith(str(path))
        assert fragment in message
        assert "\n" not in message

    def test_missing_file(self, tmp_path: Path) -> None:
        with pytest.raises(ConfigError, match="file not found"):
            load_config(tmp_path / "nope.toml")


@dataclass(frozen=True)
class _Point:
    x: float
    y: float = 0.0


@dataclass(frozen=True)
class _Shape:
    name: str
    points: tuple[_Point, ...] = ()
    corner: tuple[float, float] = (0.0, 0.0)
    label: str | None = None
    extras: list[int] = field(default_factory=list)


class TestFromMapping:
    def test_arrays_of_tables_and_fixed_tuples(self) -> None:
        shape = from_mapping(
            _Shape,
            {"name": "a", "points": [{"x": 1}, {"x": 2, "y": 3}], "corner": [1, 2]},
            "f.toml",
        )
        assert shape.points == (_Point(1.0), _Point(2.0, 3.0))
        assert shape.corner == (1.0, 2.0)
        assert shape.label is None

    def test_missing_required_key(self) -> None:
        with pytest.raises(ConfigError, match=r"f.toml: points\[1\]: missing required key 'x'"):
            from_mapping(_Shape, {"name": "a", "points": [{"x": 1}, {"y": 2}]}, "f.toml")

    def test_wrong_tuple_length(self) -> None:
        with pytest.raises(ConfigError, match="corner: expected an array of 2 values"):
            from_mapping(_Shape, {"name": "a", "corner": [1, 2, 3]}, "f.toml")

    def test_unsupported_field_type_is_a_bug_not_a_config_error(self) -> None:
        with pytest.raises(TypeError):
            from_mapping(_Shape, {"name": "a", "extras": [1]}, "f.toml")


def test_require() -> None:
    require(True, "never")
    with pytest.raises(ValueError, match="boom"):
        require(False, "boom")
