"""Sonar ranges, bumpers and stall of the emulated Pioneer, as the SIPs report them."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shared.aria import Command, SipFlags
from shared.aria.p3at import FRONT_BUMPER_SEGMENTS, SONAR_POSES
from shared.pose import Pose2
from sim.config import EmulatorConfig
from sim.free_space import WALL_HALF_THICKNESS_M
from tests.sim.pioneer.rig import Rig

ROOM = (12.0, 6.0)
MAX_RANGE_M = 5.0


def expected_range(number: int, pose: Pose2, config: EmulatorConfig | None = None) -> float:
    """Noise-free reading of sonar ``number`` from ``pose`` in the bare room, m: the
    nearest echo among the cone's rays off the walls' inner faces, where a ray echoes
    if it meets its face within the critical angle of the normal and beyond the
    minimum range (sim.pioneer.sonar rules 2-4, computed here without pymunk)."""
    config = config or EmulatorConfig()
    yaw = pose.yaw_rad
    sx, sy, heading = SONAR_POSES[number]
    x = pose.x_m + math.cos(yaw) * sx - math.sin(yaw) * sy
    y = pose.y_m + math.sin(yaw) * sx + math.cos(yaw) * sy
    half = math.radians(config.sonar_beam_width_deg) / 2
    cos_critical = math.cos(math.radians(config.sonar_critical_angle_deg))
    lo = WALL_HALF_THICKNESS_M
    nearest = MAX_RANGE_M
    for offset in np.linspace(-half, half, config.sonar_rays):
        dx, dy = math.cos(yaw + heading + offset), math.sin(yaw + heading + offset)
        faces = []  # (distance, cosine of the incidence) of the x and y faces ahead
        for p, d, size in ((x, dx, ROOM[0]), (y, dy, ROOM[1])):
            if abs(d) > 1e-9:
                faces.append((((size - lo if d > 0 else lo) - p) / d, abs(d)))
        distance, cos_incidence = min(faces)
        if config.sonar_min_range_m <= distance < nearest and cos_incidence >= cos_critical:
            nearest = distance
    return nearest


def collect_readings(rig: Rig, seconds: float) -> tuple[dict[int, list[float]], list[int]]:
    """Sonar readings by number over ``seconds``, and the number of readings per SIP."""
    first = len(rig.host.sips)
    rig.run_for(seconds)
    by_number: dict[int, list[float]] = {}
    per_sip = []
    for _, sip in rig.host.sips[first:]:
        per_sip.append(len(sip.sonar))
        for reading in sip.sonar:
            by_number.setdefault(reading.number, []).append(reading.range_m)
    return by_number, per_sip


class TestSonar:
    # Headings are multiples of 10 degrees and the rays 5 degrees apart: yaws of 2 and 37
    # degrees keep every incidence off the 50 degree critical angle by 2 degrees or more.
    @pytest.mark.parametrize("pose", [Pose2(10.0, 3.0, math.radians(2.0)),
                                      Pose2(4.0, 2.0, math.radians(37.0))])
    def test_ranges_match_the_walls(self, pose: Pose2) -> None:
        rig = Rig(world=None, start=pose)
        rig.connect()
        readings, per_sip = collect_readings(rig, 1.0)
        assert sorted(readings) == list(range(16))
        assert all(4 <= n <= 6 for n in per_sip)  # a few per SIP, as the firmware fires them
        for number, ranges in readings.items():
            expected = expected_range(number, pose)
            assert ranges == pytest.approx([expected] * len(ranges), abs=0.04), number
        assert any(r == MAX_RANGE_M for ranges in readings.values() for r in ranges)

    def test_noise_free_ranges_are_exact_to_the_mm(self) -> None:
        pose = Pose2(10.0, 3.0, math.radians(2.0))
        rig = Rig(config=EmulatorConfig(sonar_noise_m=0.0), start=pose)
        rig.connect()
        readings, _ = collect_readings(rig, 0.5)
        for number, ranges in readings.items():
            assert ranges[-1] == pytest.approx(expected_range(number, pose), abs=0.001)

    def test_sonar_off_and_on(self) -> None:
        rig = Rig()
        rig.connect()
        rig.command(Command.SONAR, 0)
        rig.run_for(0.2)
        readings, _ = collect_readings(rig, 0.5)
        assert readings == {}
        assert SipFlags.SONAR_ARRAY_1 not in rig.host.sips[-1][1].flags
        rig.command(Command.SONAR, 1)
        rig.run_for(0.2)
        readings, _ = collect_readings(rig, 0.5)
        assert len(readings) == 16
        assert SipFlags.SONAR_ARRAY_1 | SipFlags.SONAR_ARRAY_2 in rig.host.sips[-1][1].flags


class TestBumpersAndStall:
    def test_driving_into_a_wall_bumps_and_stalls(self) -> None:
        rig = Rig(start=Pose2(10.9, 3.0, 0.0))  # 0.74 m of floor ahead of the bumper
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 300)
        rig.run_for(1.0)
        sip = rig.host.sips[-1][1]
        assert sip.front_bumpers == 0 and not sip.left_stalled
        rig.run_for(3.5)
        readings, _ = collect_readings(rig, 0.5)
        sip = rig.host.sips[-1][1]
        assert sip.front_bumpers == FRONT_BUMPER_SEGMENTS and sip.rear_bumpers == 0
        assert sip.left_stalled and sip.right_stalled
        nose_x = rig.sim.body.pose_w[0] + rig.sim.config.body.length_m / 2
        assert nose_x == pytest.approx(ROOM[0] - WALL_HALF_THICKNESS_M, abs=0.02)
        # The front sonars are 7 cm from the wall, inside their minimum range: blind.
        assert readings[3] + readings[4] == [MAX_RANGE_M] * len(readings[3] + readings[4])
        rig.command(Command.VEL, -200)
        rig.run_for(1.5)
        sip = rig.host.sips[-1][1]
        assert sip.front_bumpers == 0 and not sip.left_stalled
