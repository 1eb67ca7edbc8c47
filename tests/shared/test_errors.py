from __future__ import annotations

import pickle

import pytest

from shared.errors import (
    CalibrationError,
    ChecksumError,
    ConfigError,
    IllegalEventError,
    InputError,
    ShapeError,
    VmnavError,
    check_shape,
)


def test_tree() -> None:
    assert issubclass(ConfigError, InputError)
    assert issubclass(CalibrationError, InputError)
    assert issubclass(InputError, VmnavError)
    assert issubclass(ShapeError, ValueError)
    assert issubclass(ChecksumError, VmnavError)


def test_input_error_names_where() -> None:
    err = ConfigError("world.toml", "walls[3]: zero length")
    assert str(err) == "world.toml: walls[3]: zero length"
    assert err.where == "world.toml"


@pytest.mark.parametrize("kind", [InputError, ConfigError, CalibrationError])
def test_input_errors_cross_process_boundaries_unchanged(kind: type[InputError]) -> None:
    again = pickle.loads(pickle.dumps(kind("route 'east_a'", "did not reach the end")))
    assert type(again) is kind and str(again) == "route 'east_a': did not reach the end"
    assert (again.where, again.problem) == ("route 'east_a'", "did not reach the end")


def test_checksum_error_carries_values() -> None:
    err = ChecksumError(0x1234, 0x4321)
    assert (err.expected, err.actual) == (0x1234, 0x4321)
    assert "0x1234" in str(err)


class TestCheckShape:
    def test_accepts_wildcard(self) -> None:
        check_shape("points", (7, 3), (None, 3))

    @pytest.mark.parametrize("shape", [(7, 2), (7,), (7, 3, 1)])
    def test_rejects_and_names_both_shapes(self, shape: tuple[int, ...]) -> None:
        with pytest.raises(ShapeError, match=r"points: expected shape \(N, 3\), got"):
            check_shape("points", shape, (None, 3))


def test_illegal_event_error_names_machine_state_and_event() -> None:
    err = IllegalEventError("mission", "IDLE", "Arrived")
    assert str(err) == "mission: event Arrived is not allowed in state IDLE"
    assert (err.machine, err.state, err.event) == ("mission", "IDLE", "Arrived")
    assert isinstance(err, VmnavError)
