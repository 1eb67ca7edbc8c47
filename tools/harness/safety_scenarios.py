"""The safety scenarios of issue 17, in lock-step: a person or a box in the robot's way.

Each scenario drives the robot's runtime (behind its safety layer, on the emulated
Pioneer's sonars and bumpers) along the lab's short ``east_a`` route, from (2, 10) to
(4.5, 10) in the 2 m corridor, and scripts the simulator: people placed and walking
(they do not avoid the robot: ``PeopleConfig.avoid_robot`` False), boxes placed and
taken away. The simulator's truth judges the run, physics step by physics step
(:mod:`tools.harness.safety_truth`): contacts, the gap the robot stopped short by, how
long after the way truly cleared the mission resumed.

It couples ``robot/`` and ``sim/``, so it lives in the harness (``tools/harness/``);
``tests/tools/harness/test_safety_scenarios.py`` runs every scenario once and
``vmnav bench safety`` runs them with its other cases.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from robot.config import VmnavConfig
from robot.mission import MissionState
from robot.runtime import RobotRuntime
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode
from shared.memory import read_memory
from shared.pose import Pose2
from sim.config import PeopleConfig, SimConfig
from sim.decor import PlacedObject
from sim.sim_camera import SimFrameSource
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from sim.world import load_world
from tools.harness.lockstep_pioneer import lockstep_pioneer
from tools.harness.safety_truth import SafetyTruth

#: The start of ``east_a``, facing along it.
START = Pose2(2.0, 10.0, 0.0)


@dataclass
class Stage:
    """What a scenario's script may touch: the simulation and its added objects."""

    sim: Simulation
    boxes: dict[str, int] = field(default_factory=dict)


#: A script step: (stage, seconds since the mission started) -> None.
Script = Callable[[Stage, float], None]


@dataclass(frozen=True, slots=True)
class Scenario:
    """One scenario.

    Attributes:
        name: its name in ``vmnav bench safety`` and the tests.
        what: one line on what happens.
        expect: the mission's end it must reach: "arrived", or an abort reason
            ("blocked", "bumper").
        people: people in the world (scripted by ``script``).
        script: called before every frame.
        limit_s: simulated time allowed after the mission starts, s.
        stop_short: the robot must stop short of the scripted obstacle (its gap counts).
    """

    name: str
    what: str
    expect: str
    people: int
    script: Script
    limit_s: float
    stop_short: bool = True


@dataclass(frozen=True, slots=True)
class ScenarioResult:
    """How a scenario went, from the runtime's telemetry and the simulator's truth.

    Attributes:
        name: the scenario.
        passed: it ended as expected, without a contact the robot caused, stopping short
            where it must.
        state: the mission's final state.
        detail: its detail line.
        waits: times the mission entered WAITING.
        resume_latency_s: from the way truly clearing to the mission resuming, s, the
            longest over the waits that resumed (None: none resumed).
        min_stopped_gap_m: the smallest gap between the robot's front and an obstacle
            in its corridor while it stood still, m (None: it never stood before one).
        contacts_moving: contacts with a person the robot was moving towards.
        contacts_still: contacts of people walking into a robot that stood still.
        sim_time_s: simulated time of the mission, s.
        transitions: (t_s, state, detail) of every mission state change.
    """

    name: str
    passed: bool
    state: str
    detail: str
    waits: int
    resume_latency_s: float | None
    min_stopped_gap_m: float | None
    contacts_moving: int
    contacts_still: int
    sim_time_s: float
    transitions: tuple[tuple[float, str, str], ...]


#: The "beside" scenario's bin: its near face 9 cm outside the swept corridor of
#: ``east_a`` (the robot's half width, 0.2525 m, plus the side margin, 0.1 m), m.
BESIDE = (3.6, 10.0 + 0.2525 + 0.1 + 0.09 + 0.175)
#: Where a scripted person waits before their walk: the corridor's far east end.
PARKED = (26.0, 10.0)


def _person(person: int, wait_at: tuple[float, float], until_s: float,
            walk_from: tuple[float, float], walk_to: tuple[float, float]) -> Script:
    """A person standing at ``wait_at`` until ``until_s``, then walking from ``walk_from``
    to ``walk_to`` (standing in the way, then leaving: ``walk_from`` = ``wait_at``;
    appearing for a walk: parked at :data:`PARKED` first)."""
    walking = [False]

    def script(stage: Stage, t_s: float) -> None:
        people = stage.sim.people
        if t_s == 0.0:
            people.place(person, wait_at, wait_at)
            people.hold(person, until_s + 1.0)
        elif t_s >= until_s and not walking[0]:
            people.place(person, walk_from, walk_to)
            walking[0] = True
    return script


def _box(at: tuple[float, float], remove_at_s: float | None, *, sonar: bool = True,
         size: tuple[float, float] = (0.4, 0.4), height_m: float = 0.8) -> Script:
    """A box placed at ``at`` when the mission starts, taken away at ``remove_at_s``."""
    def script(stage: Stage, t_s: float) -> None:
        if t_s == 0.0:
            stage.boxes["box"] = stage.sim.add_object(
                PlacedObject("box", at, size, height_m, sonar=sonar))
        elif remove_at_s is not None and t_s >= remove_at_s and "box" in stage.boxes:
            stage.sim.remove_object(stage.boxes.pop("box"))
    return script


def scenarios(stand_s: float = 90.0) -> dict[str, Scenario]:
    """The scenarios by name; ``stand_s``: how long the "standing_long" person stands (the
    tests shorten it with a shorter ``SafetyConfig.wait_ns``)."""
    out = (4.0, 11.6)  # a doorway to the north rooms: out of the corridor
    return {s.name: s for s in (
        Scenario("crossing", "a person crosses the corridor 1.5 m ahead of the robot",
                 "arrived", 1, _person(0, PARKED, 2.0, (3.9, 8.8), (3.9, 12.5)), 40.0, False),
        Scenario("standing_short", "a person stands on the route for 10 s, then leaves",
                 "arrived", 1, _person(0, (3.7, 10.0), 10.0, (3.7, 10.0), out), 60.0),
        Scenario("standing_long", f"a person stands on the route for {stand_s:.0f} s",
                 "blocked", 1, _person(0, (3.7, 10.0), stand_s, (3.7, 10.0), out),
                 stand_s + 30.0),
        Scenario("box", "a box is put on the route after teaching, taken away after 10 s",
                 "arrived", 0, _box((3.6, 10.0), 10.0), 60.0),
        Scenario("towards", "a person walks along the corridor towards the robot and passes "
                 "it by a hand's breadth (the paper's Fig. 12)", "arrived", 1,
                 _person(0, PARKED, 0.5, (6.5, 10.55), (0.8, 10.55)), 60.0, False),
        Scenario("beside", "a bin stands by the corridor's wall, 9 cm outside the robot's "
                 "swept corridor (the building world's bin_corridor)", "arrived", 0,
                 _box(BESIDE, None, size=(0.35, 0.35), height_m=0.55), 40.0, False),
        Scenario("glass_door", "a glass door the sonar does not hear closes the corridor",
                 "bumper", 0, _box((3.6, 10.0), None, sonar=False, size=(0.05, 1.9)),
                 40.0, False),
    )}


def run_scenario(scenario: Scenario, world_file: Path, memory_dir: Path, config: VmnavConfig,
                 seed: int = 1) -> ScenarioResult:
    """Run ``scenario`` on the memory taught of ``east_a`` in ``world_file`` (module
    docstring): start the mission to the route's last key image, script, judge."""
    memory = read_memory(memory_dir)
    people = PeopleConfig(count=scenario.people, avoid_robot=False)
    sim = Simulation(load_world(world_file), SimConfig(world=str(world_file), seed=seed,
                                                       people=people))
    sim.place_robot(START)
    clock = SimClock(sim)
    rng = np.random.default_rng([seed, 17])
    base, _ = lockstep_pioneer(clock, config.pioneer, rng)
    frames = SimFrameSource(sim, memory.camera, clock)
    runtime = RobotRuntime(memory, memory_dir, config, base, clock, rng, lockstep=True)
    truth = SafetyTruth(sim, config)
    sim.add_step_hook(truth.step)
    stage = Stage(sim)
    goal = memory.paths[min(memory.paths)].keyframe_ids[-1]
    runtime.start_mission((Goal(goal),), 0)
    started_ns = clock.now_ns()
    transitions: list[tuple[float, str, str]] = []
    latencies: list[float] = []
    last = None
    period_ns = sim.config.frame_period_ns
    deadline_ns = started_ns
    while True:
        t_s = (clock.now_ns() - started_ns) / 1e9
        scenario.script(stage, t_s)
        runtime.step(*frames.read())
        telemetry = runtime.telemetry()
        state = (telemetry.mission_state, telemetry.mission_detail)
        if state != last:
            transitions.append((round(t_s, 3), state[0].value, state[1]))
            if (last is not None and last[0] is MissionState.WAITING
                    and state[0] is MissionState.FOLLOWING and truth.cleared_at_ns is not None):
                latencies.append((clock.now_ns() - truth.cleared_at_ns) / 1e9)
            last = state
        if telemetry.mode is Mode.HOLD and t_s > 0:
            break
        if t_s > scenario.limit_s:
            runtime.time_limit(f"scenario limit {scenario.limit_s:.0f} s reached")
        deadline_ns += period_ns
        clock.sleep_until_ns(deadline_ns)
    truth.finish()
    runtime.close()
    result = runtime.last_result
    assert result is not None  # the loop ends in HOLD after the run
    reason = result.reason
    ended_as_expected = (result.state is MissionState.ARRIVED if scenario.expect == "arrived"
                         else reason == scenario.expect)
    short = (not scenario.stop_short or (truth.min_stopped_gap_m is not None
                                         and truth.min_stopped_gap_m >= 0.25))
    return ScenarioResult(
        name=scenario.name,
        passed=bool(ended_as_expected and truth.contacts_moving == 0 and short),
        state=result.state.value, detail=f"{reason}: {result.detail}",
        waits=sum(1 for _, s, _ in transitions if s == MissionState.WAITING.value),
        resume_latency_s=max(latencies) if latencies else None,
        min_stopped_gap_m=(None if truth.min_stopped_gap_m is None
                           else round(float(truth.min_stopped_gap_m), 3)),
        contacts_moving=truth.contacts_moving, contacts_still=truth.contacts_still,
        sim_time_s=round((clock.now_ns() - started_ns) / 1e9, 2),
        transitions=tuple(transitions))


def scenario_config(config: VmnavConfig, wait_s: float | None = None) -> VmnavConfig:
    """``config`` with the safety layer's wait set to ``wait_s`` (None: unchanged)."""
    if wait_s is None:
        return config
    return dataclasses.replace(config, safety=dataclasses.replace(
        config.safety, wait_ns=round(wait_s * 1e9)))
