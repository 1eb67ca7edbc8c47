"""A control loop stalled while the robot drives (issue 15, item 2): the real driver over
real TCP to the emulated Pioneer in real time; the driver's command watchdog stops it.

The bounds are generous (CI machines are shared; the exact figures are
``tools/bench/hostile_stall.py``'s): without the watchdog the robot drives on at
0.2 m/s through the whole 3 s stall, 0.6 m.
"""

from __future__ import annotations

import pytest

from tools.harness.stall_rig import StallPlan, run_stall

pytestmark = pytest.mark.slow


def test_a_stalled_loop_leaves_the_robot_stopped_by_the_driver() -> None:
    run = run_stall(StallPlan(speed_m_s=0.2, drive_s=2.0, stall_s=3.0, settle_s=1.0))
    assert run.speed_at_stall_m_s > 0.1  # it was driving (0.2 m/s unless the loop lagged)
    assert run.expired_commands >= 1  # the watchdog sent the stop (more if the loop lagged)
    # Braking began and the robot stood still well before the stall ended.
    assert run.stop_after_stall_s is not None and run.standstill_after_stall_s is not None
    assert run.standstill_after_stall_s < run.stall_s - 1.0
    assert run.distance_after_stall_m < 0.3
    # The loop back, the operator's stick long released: the dead-man keeps it still.
    assert run.distance_after_resume_m < 0.01
