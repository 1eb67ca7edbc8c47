"""The simulator's judgement (tools/harness/safety_truth.py): contacts in a bare room (who
moved into whom, where and when), the distance driven blind on made-up samples."""

from __future__ import annotations

import json
from dataclasses import asdict
from types import SimpleNamespace

import pytest

from robot.config import VmnavConfig
from tests.sim.rooms import box_room
from tests.sim.test_people import people_sim
from tools.harness.safety_truth import MOVING_M_S, SafetyTruth, blind_distance_m, judge


def test_a_person_walking_into_the_standing_robot_is_a_contact_of_theirs() -> None:
    sim = people_sim(box_room(), count=1, avoid_robot=False)
    truth = SafetyTruth(sim, VmnavConfig())
    sim.add_step_hook(truth.step)
    sim.people.place(0, (8.0, 3.0), (2.0, 3.0))  # straight at the robot's front
    sim.step_until(4_000_000_000)
    truth.finish()
    assert (truth.contacts_moving, truth.contacts_still) == (0, 1)
    contact = truth.contacts[0]
    assert contact.person == 0 and not contact.moving
    # walking 1 m/s from 3 m ahead of the robot's centre: the shapes meet after about 2.5 s
    assert 2.0 < contact.t_s < 3.0
    reach = sim.config.body.length_m / 2 + sim.config.people.radius_m
    assert contact.x_m == pytest.approx(reach, abs=0.05) and abs(contact.y_m) < 0.01
    assert contact.duration_s > 0.0
    json.dumps(asdict(contact))  # the benchmark's JSON row


def test_the_robot_driving_into_a_standing_person_is_its_contact() -> None:
    sim = people_sim(box_room(), count=1, speed=0.0, avoid_robot=False)
    hook, truths = judge(VmnavConfig())  # as a repeat's on_sim hook
    hook(sim)
    (truth,) = truths
    sim.people.place(0, (6.5, 3.0), (6.5, 3.0))
    sim.body.command(0.3, 0.0)
    sim.step_until(4_000_000_000)
    assert truth.contacts == []  # still touching: counted when it ends
    truth.finish()
    assert (truth.contacts_moving, truth.contacts_still) == (1, 0)
    assert truth.contacts[0].towards_m_s > MOVING_M_S


def test_a_person_walking_into_the_side_of_the_robot_driving_past_is_not_its_contact() -> None:
    sim = people_sim(box_room(), count=1, avoid_robot=False)
    truth = SafetyTruth(sim, VmnavConfig())
    sim.add_step_hook(truth.step)
    # across the robot's path from its right, to meet its side as it drives by at 0.2 m/s
    sim.people.place(0, (5.1, 1.5), (5.1, 4.5))
    sim.body.command(0.2, 0.0)
    sim.step_until(3_000_000_000)
    truth.finish()
    assert len(truth.contacts) >= 1
    contact = truth.contacts[0]
    assert contact.y_m < 0 and abs(contact.x_m) < sim.config.body.length_m / 2
    assert contact.speed_m_s > 0.1 and not contact.moving


def sample(x: float, *, verified: bool = False, localized: bool = False) -> SimpleNamespace:
    follow = SimpleNamespace(verified=verified)
    localization = SimpleNamespace(ok=True) if localized else None
    return SimpleNamespace(pose_w=(x, 0.0, 0.0), record=SimpleNamespace(
        follow=None if localized else follow, localization=localization))


def test_blind_distance_restarts_at_each_verification() -> None:
    samples = [sample(0.0, localized=True), sample(0.3), sample(0.5, verified=True),
               sample(0.9), sample(1.6), sample(1.7, verified=True), sample(1.8)]
    assert blind_distance_m(samples) == pytest.approx(1.2)  # 0.5 -> 1.7
