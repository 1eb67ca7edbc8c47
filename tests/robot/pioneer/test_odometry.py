"""Odometry from SIP counters: conversion factors, the 15-bit wrap, headings, reconnects."""

from __future__ import annotations

import math

import pytest

from robot.pioneer.odometry import (
    DEFAULT_SUBTYPE,
    Odometry,
    heading_delta_counts,
    params_for_subtype,
)
from shared.aria.handshake import RobotIdentity
from shared.aria.sip import Sip, wrap_position
from tests.robot.pioneer.responder import Responder, Rig

ANGLE_CONV = 0.001534  # rad per THPOS count, every P3 subtype


def sip_at(x_counts: int, y_counts: int, th_counts: int) -> Sip:
    return Sip(x_counts=wrap_position(x_counts), y_counts=wrap_position(y_counts),
               th_counts=th_counts)


def test_subtype_table() -> None:
    assert params_for_subtype("p3at").dist_mm_per_count == 0.465  # reference §8
    assert params_for_subtype("P3AT-SH").dist_mm_per_count == 1.0  # ARIA lower-cases
    assert params_for_subtype("p3dx").dist_mm_per_count == 0.485
    assert params_for_subtype("p3dx-sh").dist_mm_per_count == 1.0
    assert params_for_subtype("p3at").angle_rad_per_count == ANGLE_CONV
    assert params_for_subtype("amigo") is None
    assert DEFAULT_SUBTYPE == "p3at-sh"


@pytest.mark.parametrize(("previous", "current", "delta"), [
    (0, 10, 10), (10, 0, -10), (2047, -2048, 1), (-2048, 2047, -1), (4090, 5, 11), (0, 2048, -2048),
])
def test_heading_delta_takes_the_short_way(previous: int, current: int, delta: int) -> None:
    assert heading_delta_counts(previous, current) == delta


def test_first_sip_is_the_origin_whatever_it_carries() -> None:
    odometry = Odometry()
    odometry.update(sip_at(-100, 5000, 1024), params_for_subtype("p3at-sh"))  # reference §5
    assert odometry.pose == (0.0, 0.0, 0.0)
    assert odometry.distance_m == 0.0


def test_motion_in_the_robots_frame_is_rotated_into_the_odometry_frame() -> None:
    odometry, params = Odometry(), params_for_subtype("p3at-sh")
    odometry.update(sip_at(0, 0, 1024), params)  # the robot thinks it faces +y
    odometry.update(sip_at(0, 400, 1024), params)  # and drives 400 mm that way
    odometry.update(sip_at(0, 400, 1024 + 512), params)  # then turns 45 deg left
    odometry.update(sip_at(-300, 700, 1024 + 512), params)  # and drives 424 mm
    x_m, y_m, th_rad = odometry.pose
    assert (x_m, y_m) == pytest.approx((0.7, 0.3), abs=1e-4)
    assert th_rad == pytest.approx(512 * ANGLE_CONV)
    assert odometry.distance_m == pytest.approx(0.4 + math.hypot(0.3, 0.3))


def test_restart_continues_from_the_same_pose() -> None:
    odometry, params = Odometry(), params_for_subtype("p3at-sh")
    odometry.update(sip_at(0, 0, 0), params)
    odometry.update(sip_at(1000, 0, 100), params)
    pose = odometry.pose
    odometry.restart()
    odometry.update(sip_at(20000, 9, -700), params)  # new session, other counters
    assert odometry.pose == pose
    odometry.update(sip_at(20000, 9, -600), params)
    assert odometry.pose[2] == pytest.approx(pose[2] + 100 * ANGLE_CONV)


@pytest.mark.parametrize(("subclass", "mm_per_count"), [("p3at-sh", 1.0), ("p3at", 0.465)])
def test_straight_line_across_the_15_bit_wrap(subclass: str, mm_per_count: float) -> None:
    rig = Rig(responder=Responder(RobotIdentity("vmnav", "Pioneer", subclass)))
    rig.responder.x_counts = 32_000  # close to the wrap at 0x8000
    rig.connect()
    step_counts, steps = 1500, 75  # 112 500 counts: the counter wraps three times
    for _ in range(steps):
        rig.responder.x_counts += step_counts
        rig.run(0.1)
    rig.run(0.2)
    expected_m = steps * step_counts * mm_per_count / 1000
    assert expected_m > 32.768
    state = rig.driver.state()
    assert state.odom_pose == pytest.approx((expected_m, 0.0, 0.0))
    assert state.odom_distance_m == pytest.approx(expected_m)
    assert rig.driver.counters().sips >= steps


def test_rotation_uses_the_angle_conversion_factor() -> None:
    rig = Rig()
    rig.connect()
    for _ in range(100):  # 5000 counts: more than a full turn
        rig.responder.th_counts -= 50
        rig.run(0.1)
    rig.run(0.2)
    x_m, y_m, th_rad = rig.driver.state().odom_pose
    assert (x_m, y_m) == (0.0, 0.0)
    assert th_rad == pytest.approx(math.remainder(-5000 * ANGLE_CONV, math.tau))
