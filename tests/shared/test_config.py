"""The config machinery (shared/config.py): TOML tables to frozen dataclasses, checked.

The shared config types are tested where they are used; the robot's and the
simulator's configs in tests/robot/config/ and tests/sim/test_config.py.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pytest

from shared.config import IN_FILE, from_mapping, load_toml, require
from shared.errors import ConfigError


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
    origin: _Point = field(default_factory=lambda: _Point(0.0), metadata={IN_FILE: False})


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

    def test_a_field_not_in_file_is_an_unknown_key_and_keeps_its_default(self) -> None:
        assert from_mapping(_Shape, {"name": "a"}, "f.toml").origin == _Point(0.0)
        with pytest.raises(ConfigError, match=r"f.toml: unknown key 'origin' \(known: corner"):
            from_mapping(_Shape, {"name": "a", "origin": {"x": 1}}, "f.toml")

    def test_unsupported_field_type_is_a_bug_not_a_config_error(self) -> None:
        with pytest.raises(TypeError):
            from_mapping(_Shape, {"name": "a", "extras": [1]}, "f.toml")


def test_require() -> None:
    require(True, "never")
    with pytest.raises(ValueError, match="boom"):
        require(False, "boom")


class TestLoadToml:
    def test_tables(self, tmp_path: Path) -> None:
        path = tmp_path / "vmnav.toml"
        path.write_text("[a.b]\nc = 1\n")
        assert load_toml(path) == {"a": {"b": {"c": 1}}}

    def test_missing_file(self, tmp_path: Path) -> None:
        with pytest.raises(ConfigError, match=r"nope\.toml: file not found"):
            load_toml(tmp_path / "nope.toml")

    def test_not_toml(self, tmp_path: Path) -> None:
        path = tmp_path / "vmnav.toml"
        path.write_text("[a\n")
        with pytest.raises(ConfigError, match="not valid TOML"):
            load_toml(path)
