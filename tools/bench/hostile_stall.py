"""Hostile input, a stalled loop (issue 15, item 2): how far the robot drives when its
control loop stops producing commands.

:func:`measure` runs :func:`tools.harness.stall_rig.run_stall`: the robot process drives
by hand at 0.2 m/s through the real Pioneer driver (its I/O thread) over loopback TCP to
the emulated Pioneer in real time, then its loop blocks for 3 s as the operator lets go.
The figures come from the simulation's ground truth. Takes about 10 s (2 s driving, 3 s
stalled, 1 s after, and starting the parts).
"""

from __future__ import annotations

from tools.harness.stall_rig import StallPlan, run_stall

#: The issue's targets: the stop reaches the base within this long after the stall, s...
STOP_TARGET_S = 0.5
#: ...and the robot drives less than this after the stall, m (at 0.2 m/s).
DISTANCE_TARGET_M = 0.15


def measure(seed: int = 0) -> dict[str, object]:
    """Drive at 0.2 m/s, stall the loop for 3 s, measure on the simulation's truth.

    Figures: ``speed_at_stall_m_s``; ``command_timeout_s`` (the driver's watchdog,
    ``[pioneer] command_timeout_ns``); ``stop_after_stall_s`` (from the stall until the
    base began to brake: the stop reached it; target < 0.5 s); ``standstill_after_stall_s``
    (until it stood still: that plus braking, 0.33 s from 0.2 m/s at 0.6 m/s²);
    ``distance_after_stall_m`` (driven during the stall; target < 0.15 m);
    ``distance_after_resume_m`` (driven once the loop ran again: the runtime's dead-man
    holds it); ``expired_commands``; ``stall_s``; and ``targets_met``.

    Args:
        seed: the simulation's seed (sonar noise only; the drive has no randomness).
    """
    plan = StallPlan(seed=seed)
    run = run_stall(plan)
    stop_s = run.stop_after_stall_s
    return {
        "speed_at_stall_m_s": round(run.speed_at_stall_m_s, 3),
        "command_timeout_s": plan.driver.command_timeout_ns / 1e9,
        "stall_s": round(run.stall_s, 3),
        "stop_after_stall_s": None if stop_s is None else round(stop_s, 3),
        "standstill_after_stall_s": (None if run.standstill_after_stall_s is None
                                     else round(run.standstill_after_stall_s, 3)),
        "distance_after_stall_m": round(run.distance_after_stall_m, 3),
        "distance_after_resume_m": round(run.distance_after_resume_m, 3),
        "expired_commands": run.expired_commands,
        "targets_met": (stop_s is not None and stop_s < STOP_TARGET_S
                        and run.distance_after_stall_m < DISTANCE_TARGET_M),
    }
