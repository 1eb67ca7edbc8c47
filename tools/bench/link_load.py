"""A kinematic load generator for the MAVLink link (``vmnav bench link``).

Not the robot: :class:`LinkLoadApp` is a stand-in that implements
:class:`~robot.vehicle.app_port.VehicleApp` well enough that a real
:class:`~robot.vehicle.endpoint.VehicleEndpoint` streams, validates and reports
what a robot on a mission would: it drives around a ring of key images, accepts
goals among them, and runs the real mission state machine (``robot.mission``)
through LOCALIZING, FOLLOWING and ARRIVED, so the telemetry (odometry, servo
state, mission progress) changes over time with plausible numbers. Its modes
follow the robot runtime's rules (``robot.runtime``): HOLD and armed at the start,
AUTO while a mission runs, HOLD after the last goal; another mode aborts the run.
It has no camera, memory or base: photo goals and teaching are refused, manual
control is ignored.

The vehicles processes (``tools.bench.link_vehicles``) build each vehicle's application
with an ``AppFactory``; :func:`make_load_app` is the one used today, and the robot
runtime can take its place with the same signature.

Threads: every call into a :class:`LinkLoadApp` comes from its vehicle's I/O
thread (``UdpVehicle`` rule 1), so it keeps no lock. It advances its motion to the
clock's reading whenever the endpoint reads its telemetry (every service round).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path

from robot.config import MissionConfig, VmnavConfig
from robot.mission import (
    Abort,
    Arrived,
    Localized,
    Mission,
    MissionState,
    Start,
    Transition,
)
from robot.vehicle.app_port import (
    ACTIVE_STATES,
    GcsLostAction,
    JobOutcome,
    ServoTelemetry,
    VehicleApp,
    VehicleTelemetry,
)
from shared.clock import NS_PER_S, Clock
from shared.mavlink.dialect import mavlink
from shared.mavlink.mission.goal import Goal
from shared.mavlink.mission.items import MissionRefusal
from shared.mavlink.modes import Mode
from shared.pose import Pose2
from tools.bench.link_vehicles import AppContext

#: Distance between neighbouring key images on the ring, m.
KEY_SPACING_M = 0.5
#: Forward speed while following, m/s (the paper's V).
SPEED_M_S = 0.2
#: Time LOCALIZING takes before the start key image is "found", ns.
LOCALIZE_NS = NS_PER_S
#: Lateral error amplitude, m, and angular error amplitude, rad, while following.
Y_AMPLITUDE_M = 0.02
THETA_AMPLITUDE_RAD = 0.01
#: Period of the lateral/angular error oscillation, ns.
ERROR_PERIOD_NS = 7 * NS_PER_S
#: Matched points just after a key image and just before the next one.
MATCHES_FAR, MATCHES_NEAR = 60, 150
#: errImageMax just after a key image and at the next one, px (the paper switches < 20 px).
ERR_IMAGE_FAR_PX, ERR_IMAGE_NEAR_PX = 150.0, 15.0
#: errPoints as a fraction of errImageMax.
ERR_POINTS_RATIO = 0.4
#: Battery: full voltage, V, and drain while driving, V/s.
BATTERY_FULL_V = 12.8
BATTERY_DRAIN_V_S = 0.001


class LinkLoadApp:
    """A kinematic stand-in vehicle that loads the link like a robot on a mission.

    The key images lie on a ring (a circle of ``len(key_images) * KEY_SPACING_M``
    metres, counter-clockwise from the odometry origin, in sorted id order); a goal is
    reached by driving forward along the ring at :data:`SPEED_M_S`. The servo state
    follows the geometry: ``s`` counts up to the next key image, matches rise and the
    image errors fall as it nears, ``y`` and ``theta`` oscillate by a few cm and mrad.

    Args:
        key_images: the key image ids on the ring (at least one).
        clock: time for the motion and the mission inputs.
        phase: offsets the error oscillation, rad (vehicles differ).
        config: the mission state machine's limits.

    Raises:
        ValueError: no key images.
    """

    def __init__(self, key_images: Sequence[int], clock: Clock, phase: float = 0.0,
                 config: MissionConfig | None = None) -> None:
        if not key_images:
            raise ValueError("LinkLoadApp needs at least one key image")
        self._ring = sorted(set(key_images))
        self._index = {key: i for i, key in enumerate(self._ring)}
        self._ring_m = len(self._ring) * KEY_SPACING_M
        self._radius_m = self._ring_m / (2 * math.pi)
        self._clock = clock
        self._phase = phase
        self._mission_config = config if config is not None else MissionConfig()
        self._mode = Mode.HOLD
        self._armed = True
        self._mission: Mission | None = None
        self._detail = ""
        self._entered_ns = 0
        self._goals: tuple[Goal, ...] = ()
        self._goal_arcs_m: list[float] = []
        self._first_seq = 0
        self._reached: tuple[int, ...] = ()
        self._arc_m = 0.0
        self._battery_v = BATTERY_FULL_V
        self._last_ns = clock.now_ns()

    # -- VehicleApp ---------------------------------------------------------------------

    def telemetry(self) -> VehicleTelemetry:
        now_ns = self._clock.now_ns()
        self._advance(now_ns)
        state = self._state
        following = state is MissionState.FOLLOWING
        goal = self._goals[-1].key_image_id if self._goals else None
        seq = (self._first_seq + min(len(self._reached), len(self._goals) - 1)
               if self._goals else None)
        return VehicleTelemetry(
            mode=self._mode, mission_state=state, armed=self._armed,
            mission_detail=self._detail, battery_v=self._battery_v,
            odom_pose=self._pose(now_ns),
            velocity=(SPEED_M_S, SPEED_M_S / self._radius_m) if following else (0.0, 0.0),
            goal_key=goal, servo=self._servo(now_ns) if following else None,
            mission_seq=seq, reached_seqs=self._reached, home_pose=(0.0, 0.0, 0.0))

    def validate_goals(self, goals: tuple[Goal, ...]) -> MissionRefusal | None:
        for seq, goal in enumerate(goals):
            if goal.key_image_id not in self._index:
                return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM1,
                                      f"item {seq}: no key image {goal.key_image_id}")
        return None

    def set_mode(self, mode: Mode) -> bool:
        self._stop_mission(f"switched to {mode.name}")
        self._mode = mode
        return True

    def arm(self, armed: bool, force: bool) -> bool:
        if not armed:
            self._stop_mission("disarmed")
        self._armed = armed
        return True

    def start_mission(self, goals: tuple[Goal, ...], first_seq: int) -> bool:
        """Refused while disarmed or while a mission runs."""
        if not self._armed or self._state in ACTIVE_STATES:
            return False
        now_ns = self._clock.now_ns()
        self._advance(now_ns)
        self._mission = Mission(self._mission_config)
        self._goals, self._first_seq, self._reached = goals, first_seq, ()
        self._goal_arcs_m = []
        arc_m = self._arc_m
        for goal in goals:
            arc_m = self._next_arc_m(self._index[goal.key_image_id], arc_m)
            self._goal_arcs_m.append(arc_m)
        self._mode = Mode.AUTO
        self._apply(self._mission.handle(Start(now_ns, goals[-1].key_image_id)))
        return True

    def goto_image(self, path: Path) -> bool:
        """Refused: no memory to localize a photo in."""
        return False

    def params_changed(self, config: VmnavConfig) -> None:
        """Nothing to retune."""

    def manual_control(self, x: float, y: float, z: float, r: float, buttons: int,
                       now_ns: int) -> None:
        """Ignored: the load generator is not driven by hand."""

    def teach_start(self, name: str) -> bool:
        """Refused: nothing to record."""
        return False

    def teach_stop(self) -> bool:
        """Refused: never teaching."""
        return False

    def gcs_lost(self, action: GcsLostAction) -> None:
        if action == "stop":
            self.set_mode(Mode.MANUAL)
        elif action == "hold":
            self.set_mode(Mode.HOLD)

    def gcs_regained(self) -> None:
        """Stays where :meth:`gcs_lost` left it."""

    def next_notice(self) -> tuple[int, str] | None:
        """None: everything it does shows in the telemetry."""
        return None

    def next_job_outcome(self) -> JobOutcome | None:
        """None: it takes no photo goal."""
        return None

    # -- motion -------------------------------------------------------------------------

    @property
    def _state(self) -> MissionState:
        return self._mission.state if self._mission is not None else MissionState.IDLE

    def _apply(self, transition: Transition | None) -> None:
        if transition is not None:
            self._detail = transition.detail
            self._entered_ns = transition.t_ns

    def _stop_mission(self, reason: str) -> None:
        if self._mission is not None and self._state in ACTIVE_STATES:
            self._apply(self._mission.handle(Abort(self._clock.now_ns(), "operator_abort", reason)))

    def _next_arc_m(self, ring_index: int, from_arc_m: float) -> float:
        """The first arc length >= ``from_arc_m`` at which key image ``ring_index`` lies."""
        base_m = ring_index * KEY_SPACING_M
        laps = math.ceil((from_arc_m - base_m) / self._ring_m - 1e-9)
        return base_m + max(laps, 0) * self._ring_m

    def _advance(self, now_ns: int) -> None:
        """Move on to ``now_ns``: localize after :data:`LOCALIZE_NS`, drive, reach goals."""
        since_ns, self._last_ns = self._last_ns, now_ns
        mission = self._mission
        if mission is None:
            return
        if mission.state is MissionState.LOCALIZING and now_ns - self._entered_ns >= LOCALIZE_NS:
            since_ns = self._entered_ns + LOCALIZE_NS  # found then; driving starts there
            key = self._ring[int(self._arc_m // KEY_SPACING_M) % len(self._ring)]
            self._apply(mission.handle(Localized(since_ns, key, MATCHES_NEAR)))
        if mission.state is not MissionState.FOLLOWING:
            return
        dt_s = (now_ns - since_ns) / NS_PER_S
        self._arc_m += SPEED_M_S * dt_s
        self._battery_v -= BATTERY_DRAIN_V_S * dt_s
        while len(self._reached) < len(self._goals):
            goal_arc_m = self._goal_arcs_m[len(self._reached)]
            if self._arc_m < goal_arc_m:
                return
            self._reached += (self._first_seq + len(self._reached),)
            self._arc_m = goal_arc_m
        self._apply(mission.handle(Arrived(now_ns, self._goals[-1].key_image_id)))
        self._mode = Mode.HOLD

    def _errors(self, now_ns: int) -> tuple[float, float]:
        """(y_m, theta_rad): the slow oscillation about the route."""
        angle = 2 * math.pi * (now_ns % ERROR_PERIOD_NS) / ERROR_PERIOD_NS + self._phase
        return Y_AMPLITUDE_M * math.sin(angle), THETA_AMPLITUDE_RAD * math.cos(angle)

    def _pose(self, now_ns: int) -> Pose2:
        """The pose in the odometry frame: on the ring, offset by the errors while following."""
        phi = self._arc_m / self._radius_m
        x_m, y_m = self._radius_m * math.sin(phi), self._radius_m * (1 - math.cos(phi))
        if self._state is not MissionState.FOLLOWING:
            return Pose2(x_m, y_m, phi)
        lateral_m, theta_rad = self._errors(now_ns)
        return Pose2(x_m - lateral_m * math.sin(phi), y_m + lateral_m * math.cos(phi),
                     phi + theta_rad)

    def _servo(self, now_ns: int) -> ServoTelemetry:
        passed = int(self._arc_m // KEY_SPACING_M)
        s_m = self._arc_m - (passed + 1) * KEY_SPACING_M
        near = 1 + s_m / KEY_SPACING_M  # 0 just after a key image, 1 at the next
        err_max_px = ERR_IMAGE_FAR_PX + (ERR_IMAGE_NEAR_PX - ERR_IMAGE_FAR_PX) * near
        y_m, theta_rad = self._errors(now_ns)
        count = len(self._ring)
        return ServoTelemetry(
            current_key=self._ring[passed % count], next_key=self._ring[(passed + 1) % count],
            matches=round(MATCHES_FAR + (MATCHES_NEAR - MATCHES_FAR) * near),
            err_image_max_px=err_max_px, err_points_px=ERR_POINTS_RATIO * err_max_px,
            y_m=y_m, theta_rad=theta_rad, s_m=s_m)


def make_load_app(context: AppContext) -> VehicleApp:
    """The ``AppFactory`` of ``vmnav bench link`` today: a :class:`LinkLoadApp` whose
    error oscillation is phased by its system id."""
    return LinkLoadApp(context.key_images, context.clock, phase=0.7 * context.system_id)
