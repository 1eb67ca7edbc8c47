"""The simulator's judgement of a repeat's safety, physics step by physics step (a step
hook: :class:`SafetyTruth`), and the distance driven blind (:func:`blind_distance_m`).

* Contacts between the robot and a person (any overlap of their shapes), split by
  whether the robot was moving towards the person at any step of the contact (its
  surface where it met them moving > 2 cm/s along the normal towards their centre:
  driving or turning into them), or the person walked into the robot (standing, or
  driving past them: a person walking into its side); each contact is listed with when,
  where and the robot's speed.
* The gap between the robot's front and the nearest obstacle ahead (its centre beyond
  the front, within the swept corridor) while the robot stood still.
* When the way truly cleared (no person or placed object within the stop distance plus
  the clear margin ahead, in the robot's swept corridor), for the resume latency.

The safety scenarios (:mod:`tools.harness.safety_scenarios`), ``vmnav bench safety``'s
people runs and every case of a sweep (:mod:`tools.sweep.case`) are judged by it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from robot.config import VmnavConfig
from sim.simulation import Simulation

#: A robot moving towards a person faster than this in a contact is the robot's fault, m/s.
MOVING_M_S = 0.02


@dataclass(frozen=True, slots=True)
class Contact:
    """One contact between the robot and a person, from the simulator's truth.

    Attributes:
        t_s: when it began, simulated seconds since the run's start.
        person: the person's index in the simulation.
        x_m: where the person's centre was when it began, robot frame (x forward, y
            left), m.
        y_m: as ``x_m``.
        towards_m_s: the fastest the robot's surface where it met the person moved
            towards the person's centre during it (along the contact's normal), m/s: a
            robot driving past a person who walks into its side does not move towards
            them; one turning or driving into them does.
        speed_m_s: the robot's fastest forward (or backward) speed during it, m/s.
        duration_s: how long the shapes overlapped, s.
    """

    t_s: float
    person: int
    x_m: float
    y_m: float
    towards_m_s: float
    speed_m_s: float
    duration_s: float

    @property
    def moving(self) -> bool:
        """The robot moved towards the person (faster than :data:`MOVING_M_S`)."""
        return self.towards_m_s > MOVING_M_S


class SafetyTruth:
    """The simulator's judgement, step by step (module docstring): a step hook.

    ``contacts`` lists every contact with a person that ended (all of them after
    :meth:`finish`)."""

    def __init__(self, sim: Simulation, config: VmnavConfig) -> None:
        self._sim = sim
        self._safety = config.safety
        self._start_ns: int | None = None
        # person -> (start ns, x_m, y_m robot frame at the start, fastest towards m/s,
        # fastest forward or back m/s)
        self._touching: dict[int, tuple[int, float, float, float, float]] = {}
        self._now_ns = 0
        self.contacts: list[Contact] = []
        self.blocked_truth = False
        self.cleared_at_ns: int | None = None
        self.min_stopped_gap_m: float | None = None

    @property
    def contacts_moving(self) -> int:
        """Contacts with a person the robot was moving towards."""
        return sum(contact.moving for contact in self.contacts)

    @property
    def contacts_still(self) -> int:
        """Contacts of people walking into the robot (standing, or driving past them)."""
        return len(self.contacts) - self.contacts_moving

    def step(self, now_ns: int, dt_ns: int) -> None:
        sim = self._sim
        if self._start_ns is None:
            self._start_ns = now_ns
        self._now_ns = now_ns
        x, y, yaw = sim.body.pose_w
        c, s = math.cos(yaw), math.sin(yaw)
        velocity = sim.body.velocity_base
        positions, radius, _ = sim.people_state()
        half_length = sim.config.body.length_m / 2
        half_width = sim.config.body.width_m / 2
        ahead = []  # (gap to the front, m) of obstacles in the corridor
        for i, (px, py) in enumerate(positions):
            rx, ry = c * (px - x) + s * (py - y), -s * (px - x) + c * (py - y)
            touching = (abs(rx) <= half_length + radius and abs(ry) <= half_width + radius
                        and _box_circle_overlap(rx, ry, half_length, half_width, radius))
            if touching:
                towards = _surface_towards(rx, ry, half_length, half_width, velocity)
                speed = abs(velocity[0])
                began_ns, x0, y0, fastest, top = self._touching.get(
                    i, (now_ns, rx, ry, towards, speed))
                self._touching[i] = (began_ns, x0, y0, max(fastest, towards), max(top, speed))
            elif i in self._touching:
                self._count(i, now_ns)
            if abs(ry) <= half_width + self._safety.side_margin_m + radius and rx > half_length:
                ahead.append(rx - radius - half_length)
        for obj in sim.added_objects.values():
            (ox, oy), (length, width), _ = obj.footprint()
            rx, ry = c * (ox - x) + s * (oy - y), -s * (ox - x) + c * (oy - y)
            reach = max(length, width) / 2
            if abs(ry) <= half_width + self._safety.side_margin_m + reach and rx > half_length:
                ahead.append(rx - min(length, width) / 2 - half_length)
        near = min(ahead, default=math.inf)
        blocked = near <= self._safety.stop_distance_m + self._safety.clear_margin_m
        if self.blocked_truth and not blocked:
            self.cleared_at_ns = now_ns
        self.blocked_truth = blocked
        if abs(velocity[0]) < 1e-3 and near < 1.5:
            self.min_stopped_gap_m = near if self.min_stopped_gap_m is None else min(
                self.min_stopped_gap_m, near)

    def finish(self) -> None:
        """The run ended: contacts still going on count."""
        for person in list(self._touching):
            self._count(person, self._now_ns)

    def _count(self, person: int, now_ns: int) -> None:
        began_ns, x_m, y_m, fastest, top = self._touching.pop(person)
        start_ns = self._start_ns or 0
        self.contacts.append(Contact(
            round(float(began_ns - start_ns) / 1e9, 2), int(person), round(float(x_m), 3),
            round(float(y_m), 3), round(float(fastest), 3), round(float(top), 3),
            round(float(now_ns - began_ns) / 1e9, 2)))


def _surface_towards(rx: float, ry: float, half_length: float, half_width: float,
                     velocity: tuple[float, float, float]) -> float:
    """How fast the robot's box (+-half_length x +-half_width, m) moves towards a person's
    centre at (rx, ry) (robot frame, m) where it is nearest to it, given the robot's
    (vx_m_s, vy_m_s, omega_rad_s): the velocity of that point of the box along the normal
    from it to the centre (from the robot's centre when the centre is inside the box), m/s.
    """
    qx = min(max(rx, -half_length), half_length)
    qy = min(max(ry, -half_width), half_width)
    nx, ny = rx - qx, ry - qy
    norm = math.hypot(nx, ny)
    if norm < 1e-9:
        nx, ny, norm = rx, ry, max(math.hypot(rx, ry), 1e-9)
    vx, vy, omega = velocity
    return ((vx - omega * qy) * nx + (vy + omega * qx) * ny) / norm


def _box_circle_overlap(rx: float, ry: float, half_length: float, half_width: float,
                        radius: float) -> bool:
    """A circle at (rx, ry) of ``radius`` overlaps the box +-half_length x +-half_width."""
    dx = max(abs(rx) - half_length, 0.0)
    dy = max(abs(ry) - half_width, 0.0)
    return dx * dx + dy * dy <= radius * radius


def judge(config: VmnavConfig) -> tuple[Callable[[Simulation], None], list[SafetyTruth]]:
    """An ``on_sim`` hook of :func:`tools.harness.demo.repeat_in_sim` that judges the
    repeat's simulation with a :class:`SafetyTruth` of ``config``'s safety settings, and the
    list the truth is put in."""
    truths: list[SafetyTruth] = []

    def hook(sim: Simulation) -> None:
        truths.append(SafetyTruth(sim, config))
        sim.add_step_hook(truths[-1].step)

    return hook, truths


def safety_figures(truth: SafetyTruth, run: Any) -> dict[str, Any]:
    """A repeat's safety figures, after :meth:`SafetyTruth.finish`: ``obstacle_waits`` (the
    mission's waits for an obstacle), ``contacts_moving``, ``contacts_still`` and
    ``blind_max_m`` (:func:`blind_distance_m`, m) of ``run``
    (:class:`tools.harness.demo.RepeatRun`) judged by ``truth``."""
    return {"obstacle_waits": sum(1 for e in run.result.events if e.reason == "obstacle"),
            "contacts_moving": truth.contacts_moving, "contacts_still": truth.contacts_still,
            "blind_max_m": round(blind_distance_m(run.samples), 3)}


def blind_distance_m(samples: Sequence[Any]) -> float:
    """The longest true distance driven between two verifications (a vision estimate the
    filter took, or a localization), m, over a repeat's cycle samples
    (:class:`tools.harness.demo.CycleSample`)."""
    longest = driven = 0.0
    previous = None
    for sample in samples:
        record = sample.record
        if previous is not None:
            driven += math.dist(previous[:2], sample.pose_w[:2])
        previous = sample.pose_w
        longest = max(longest, driven)
        localized = record.localization is not None and record.localization.ok
        if localized or (record.follow is not None and record.follow.verified):
            driven = 0.0
    return longest
