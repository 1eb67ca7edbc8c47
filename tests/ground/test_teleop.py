"""KeyboardTeleop: the held command (the 10 Hz loop runs in test_station.py)."""

from __future__ import annotations

from ground.teleop import KeyboardTeleop


def test_keys_change_the_held_command_within_limits() -> None:
    teleop = KeyboardTeleop()
    assert all(teleop.press(key) for key in "wwwwwwwdx")  # x: ignored
    assert (teleop.x, teleop.r) == (1.0, 0.2)
    assert all(teleop.press(key) for key in "saaa")
    assert (teleop.x, teleop.r) == (0.8, -0.4)
    assert teleop.press(" ") and (teleop.x, teleop.r) == (0.0, 0.0)
    assert not teleop.press("q") and not teleop.press("\x1b")
