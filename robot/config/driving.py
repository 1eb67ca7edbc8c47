"""The robot's driving configs: the control law, the estimator, key image switching, the
mission's give-up policy, the safety layer and driving by hand.

Tables ``[control]``, ``[estimator]``, ``[switching]``, ``[mission]``, ``[safety]`` and
``[teleop]`` of a vmnav config file (:mod:`robot.config`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shared.config import require

#: Control laws of :class:`ControlConfig`: "paper" (Courbon et al. 2008, eq. 2) and
#: "paper+ff" (eq. 2 plus a feed-forward of the teach path's curvature).
CONTROL_LAWS = ("paper", "paper+ff")

#: Domains of :attr:`ControlConfig.double_pole`: "distance" (1/m, the chained form's own
#: variable) or "time" (1/s, converted to 1/m by dividing by the speed).
POLE_DOMAINS = ("distance", "time")


@dataclass(frozen=True, slots=True)
class ControlConfig:
    """The path-following law (Courbon et al. 2008, sec. III-C and IV; DESIGN.md sec. 5.6).

    Gains put a double pole at g (1/m) on the lateral error's response to the
    distance travelled: Kp = g^2, Kd = 2 g. The paper says only "a double pole
    located at value 0.3". Read in the distance domain (0.3 1/m) it takes 10.8 m to
    bring a 0.3 m offset under 5 cm (reference visual-navigation.md sec. 1.2), while
    the paper's own run (280 key images over about 500 s at 0.2 m/s, so one every
    ~0.36 m) is said to regulate the errors "to zero for each key view". We read it
    as a time-domain pole, 0.3 1/s = 1.5 1/m at 0.2 m/s (2.3 m to 5 cm); set
    ``pole_domain = "distance"`` for the other reading.
    """

    law: str = "paper+ff"
    """One of ``CONTROL_LAWS``: the paper's eq. (2), or eq. (2) plus curvature feed-forward.
    The default adds the feed-forward: eq. (2) regulates towards the straight line through
    the next key image and so cuts turns (lab, seed 1: lateral RMS 7.8 cm, max 22.6 cm;
    with the feed-forward 1.8 cm, 5.5 cm). The paper's law: ``law = "paper"``."""
    speed_m_s: float = 0.2
    """Forward speed V, m/s (paper: 200 mm/s)."""
    max_omega_rad_s: float = math.radians(25.0)
    """Bound on |omega|, rad/s (paper: 10 deg/s). With V it bounds the turn radius from
    below at V / max_omega: the paper's 10 deg/s at 0.2 m/s cannot turn tighter than
    1.15 m, while the lab's doorways need 0.8 m arcs (14.3 deg/s) and the law a margin
    above that to correct errors in a turn; hence 25 deg/s (0.46 m)."""
    double_pole: float = 0.3
    """The closed loop's double pole, in 1/m or 1/s as ``pole_domain`` says (paper: 0.3)."""
    pole_domain: str = "time"
    """One of ``POLE_DOMAINS``: the unit of ``double_pole``."""

    def __post_init__(self) -> None:
        require(self.law in CONTROL_LAWS,
                f"law must be one of {', '.join(CONTROL_LAWS)}, got {self.law!r}")
        require(self.pole_domain in POLE_DOMAINS,
                f"pole_domain must be one of {', '.join(POLE_DOMAINS)}, got {self.pole_domain!r}")
        for name in ("speed_m_s", "max_omega_rad_s", "double_pole"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")

    @property
    def pole_1_m(self) -> float:
        """The double pole g in the distance domain, 1/m."""
        if self.pole_domain == "distance":
            return self.double_pole
        return self.double_pole / self.speed_m_s


@dataclass(frozen=True, slots=True)
class EstimatorConfig:
    """The Kalman filter over (s, y, theta) (``robot.estimator``): odometry predicts, vision
    updates.

    Measurement noise defaults come from the three-view simulation of reference
    visual-navigation.md sec. 1.2 (median |dy| about 1 cm, p90 about 3 cm; median
    |dtheta| 0.5 to 0.8 degrees, p90 up to 2.4 degrees).
    """

    sigma_y_m: float = 0.02
    """Std of the vision estimate of y, m."""
    sigma_theta_rad: float = math.radians(1.5)
    """Std of the vision estimate of theta, rad."""
    sigma_s_m: float = 0.05
    """Std of the vision estimate of s (along-track), m."""
    process_var_position_m2_per_m: float = 1e-4
    """Growth of var(s) and var(y) per metre driven, m^2/m (wheel slip, unmodelled motion)."""
    process_var_theta_rad2_per_m: float = 1e-4
    """Growth of var(theta) per metre driven, rad^2/m (uneven wheels, ground)."""
    rotation_scale_sigma: float = 0.03
    """Std of the odometry's rotation error as a fraction of the turn measured (skid
    steering slips in turns; the simulator draws 3 %)."""
    gate_chi2: float | None = 16.3
    """A vision estimate (s, y, theta) whose squared Mahalanobis distance to the prediction
    exceeds this is rejected (16.3 = chi-square, 3 degrees of freedom, p = 0.999); None
    accepts all (code only: TOML cannot write None)."""
    init_min_points: int = 10
    """A vision estimate initialises the filter (ungated: at a start, after a junction
    crossing or LOST) only with at least this many triangulated key-pair points behind it;
    three points once gave y = 1.05 m for a robot on the path."""
    init_agreeing_points: int = 5
    """With fewer than ``init_min_points`` points but at least this many, an estimate
    initialises the filter when it agrees with the ``init_agreeing_frames`` - 1 estimates
    before it (within :data:`robot.follower.INIT_AGREEMENT_M` and ``_RAD``): the robot
    waits while uninitialised, so a true estimate repeats and a chance one does not. A
    robot started 0.3 m and 10 deg off a textured lab's route saw 5-9 points for 40 s."""
    init_agreeing_frames: int = 3
    """Agreeing estimates in a row that initialise the filter (see above; frames of fewer
    points in between do not count), >= 1."""
    lost_timeout_ns: int = 2_000_000_000
    """No accepted vision estimate for this long means LOST, ns (30 frames at 15 Hz, 0.4 m
    of odometry alone at 0.2 m/s)."""
    lost_distance_m: float = 1.0
    """...nor while driving this far on odometry alone, m: the robot stops (issue 17,
    "lost means stop"), whatever its speed."""

    def __post_init__(self) -> None:
        for name in ("sigma_y_m", "sigma_theta_rad", "sigma_s_m", "lost_timeout_ns",
                     "lost_distance_m"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        for name in ("process_var_position_m2_per_m", "process_var_theta_rad2_per_m",
                     "rotation_scale_sigma"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(self.gate_chi2 is None or self.gate_chi2 > 0,
                f"gate_chi2 must be > 0 or None, got {self.gate_chi2}")
        require(self.init_min_points >= 0,
                f"init_min_points must be >= 0, got {self.init_min_points}")
        require(self.init_agreeing_points >= 0,
                f"init_agreeing_points must be >= 0, got {self.init_agreeing_points}")
        require(self.init_agreeing_frames >= 1,
                f"init_agreeing_frames must be >= 1, got {self.init_agreeing_frames}")


@dataclass(frozen=True, slots=True)
class SwitchingConfig:
    """When the next key image counts as reached (Courbon et al. 2008, sec. IV; reference
    visual-navigation.md sec. 1.3)."""

    err_image_max_px: float = 20.0
    """Reached when errImageMax is below this, px (paper: 20 px)."""
    image_error_within_m: float = 0.25
    """...and, when the frame has an along-track estimate s, the robot is at most this far
    before the key image, m (a large value is the paper's rule). Far landmarks (the ``campus``
    courtyard's facades) keep errImageMax under 20 px up to 0.75 m before a key image:
    the switch came early and the next key image, turned 15 deg, looked 30 cm off."""
    pass_margin_m: float = 0.0
    """Reached when the along-track coordinate s (relative to the key image, negative
    before it) is at least this, m."""
    hold_frames: int = 2
    """A rule must hold on this many consecutive frames with evidence before it switches
    (hysteresis against a single noisy frame)."""

    def __post_init__(self) -> None:
        require(self.err_image_max_px > 0,
                f"err_image_max_px must be > 0, got {self.err_image_max_px}")
        require(self.image_error_within_m > 0,
                f"image_error_within_m must be > 0, got {self.image_error_within_m}")
        require(self.pass_margin_m >= 0, f"pass_margin_m must be >= 0, got {self.pass_margin_m}")
        require(self.hold_frames >= 1, f"hold_frames must be >= 1, got {self.hold_frames}")



#: What a mission run does when the base stops reporting (a cut ARIA cable, a Pioneer
#: that went quiet; :attr:`MissionConfig.base_lost_action`). The robot stops either way
#: (and the Pioneer's own watchdog stops it 2 s after the last packet it got): "hold"
#: ends the run and waits in HOLD for the operator, "continue" pauses the run and goes
#: on when the base reports again.
BASE_LOST_ACTIONS = ("hold", "continue")


@dataclass(frozen=True, slots=True)
class MissionConfig:
    """Give-up policy of the mission state machine (``robot.mission``)."""

    localize_timeout_ns: int = 30_000_000_000
    """LOCALIZING for this long without success fails the mission, ns (paper: one
    localization took 6.5 s)."""
    localize_attempts: int = 5
    """This many failed localizations in a row fail the mission."""
    relocalize_timeout_ns: int = 20_000_000_000
    """LOST for this long without relocalizing fails the mission, ns."""
    relocalize_attempts: int = 10
    """This many failed relocalizations in one LOST episode fail the mission."""
    lost_limit: int = 3
    """Lost this many times without reaching a key image in between fails the mission
    (each relocalization led nowhere; a campus robot once went LOST 579 times and drove
    57 m)."""
    relocalize_radius_m: float = 2.5
    """LOST, the robot relocalizes only at key images within this distance of the one it
    was heading for, m, along the memory's paths and junctions either way: it stands, or
    drives blind at most the estimator's ``lost_distance_m``, so a key image farther away
    is a look-alike (a corridor repeats its tiles and lamps every few metres)."""
    base_lost_action: str = "continue"
    """One of ``BASE_LOST_ACTIONS``: what a mission run does when the base stops reporting."""

    def __post_init__(self) -> None:
        for name in ("localize_timeout_ns", "localize_attempts", "relocalize_timeout_ns",
                     "relocalize_attempts", "lost_limit", "relocalize_radius_m"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        require(self.base_lost_action in BASE_LOST_ACTIONS,
                f"base_lost_action must be one of {', '.join(BASE_LOST_ACTIONS)}, "
                f"got {self.base_lost_action!r}")


@dataclass(frozen=True, slots=True)
class SafetyConfig:
    """The safety layer under every mission and the stick (``robot.safety``).

    The footprint defaults are the Pioneer 3-AT's with its bumpers (ARIA
    ``params/p3at-sh.p``: RobotLength 626 mm, RobotWidth 505 mm, the centre of rotation
    in the middle).
    """

    enabled: bool = True
    """The layer bounds every command. A developer's switch (to measure the servo alone in
    the simulator), in the config file only: no parameter turns it off, and the robot
    warns at start-up when a file did."""
    stop_distance_m: float = 0.4
    """Forward motion stops when an echo in the robot's swept corridor is this close to
    its front, m."""
    slow_distance_m: float = 1.2
    """Echoes beyond this far ahead of the front leave the speed alone; nearer, the speed
    falls linearly towards ``min_speed_ratio`` of the command at ``stop_distance_m``, m."""
    min_speed_ratio: float = 0.25
    """The slowest fraction of the commanded speed short of stopping (so the robot reaches
    its stop line instead of creeping towards it)."""
    clear_margin_m: float = 0.1
    """Stopped, the way counts as clear again only beyond ``stop_distance_m`` + this, m."""
    clear_dwell_ns: int = 1_000_000_000
    """...and only after it stayed clear this long, ns."""
    side_margin_m: float = 0.1
    """The swept corridor is the robot's width plus this on each side, m."""
    side_stop_margin_m: float = 0.03
    """Only an echo within this of the robot's swept sides stops it (rule 3); one farther
    out, still in the corridor, that cannot lie nearer (the readings saw the nearer part
    of its cone free, and it is not coming at the robot) slows it no lower than
    ``min_speed_ratio``: it creeps past, as a safety scanner's speed-dependent fields let
    a vehicle, m (<= ``side_margin_m``; equal to it, the robot creeps past nothing:
    docs/safety.md says what the creep gains and what it risks)."""
    turn_margin_m: float = 0.05
    """Turning in place is refused while an echo lies within the circle the robot's
    corners sweep plus this, m."""
    front_m: float = 0.313
    """From the centre of rotation to the front bumper, m."""
    rear_m: float = 0.313
    """From the centre of rotation to the rear bumper, m."""
    half_width_m: float = 0.2525
    """Half the robot's width, m."""
    sonar_stale_ns: int = 1_000_000_000
    """A sonar whose latest reading is older than this counts as not clear, ns (a P3's
    ring fires every transducer every 320 ms)."""
    wait_ns: int = 60_000_000_000
    """A mission stopped by an obstacle waits this long for the way to clear, then holds,
    ns."""
    approach_horizon_ns: int = 1_000_000_000
    """An echo that comes towards the robot (a person walking at it) counts where it will
    be this long after now, ns: the time to notice it on the next ping and to brake."""
    approach_min_m_s: float = 0.4
    """...when it comes at least this fast, m/s: slower apparent motion is sonar noise, or
    the echo sliding along an oblique wall as the robot drives."""
    approach_gate_m: float = 0.7
    """Two successive echoes of one sonar further apart than this are different things
    (the beam swept onto another surface), not one thing moving, m."""
    beam_width_rad: float = math.radians(30.0)
    """A sonar's cone: its echo comes from somewhere on the arc this wide at its range, rad
    (30 degrees: the P3's Polaroid transducers)."""
    clear_width_rad: float = math.radians(15.0)
    """A reading shows free space (nothing nearer than its range) only in the middle of its
    cone this wide, rad (15 degrees: where even a thin object echoes)."""
    free_margin_m: float = 0.05
    """A point counts as seen free by a reading only this much nearer than its range, m
    (range noise and odometry drift over ``carve_window_ns``)."""
    carve_distance_m: float = 1.0
    """Readings taken within this distance of where the robot stands place an echo on its
    arc (``robot.safety`` rule 1): the robot's motion is the baseline, m."""
    carve_window_ns: int = 20_000_000_000
    """...and only readings this recent (odometry drifts, turning most), ns."""

    def __post_init__(self) -> None:
        for name in ("stop_distance_m", "slow_distance_m", "front_m", "rear_m",
                     "half_width_m", "sonar_stale_ns", "wait_ns", "approach_min_m_s",
                     "approach_gate_m", "beam_width_rad", "clear_width_rad"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")
        for name in ("clear_margin_m", "clear_dwell_ns", "side_margin_m", "side_stop_margin_m",
                     "turn_margin_m",
                     "approach_horizon_ns", "free_margin_m", "carve_distance_m",
                     "carve_window_ns"):
            require(getattr(self, name) >= 0, f"{name} must be >= 0, got {getattr(self, name)}")
        require(self.slow_distance_m > self.stop_distance_m,
                f"slow_distance_m must be > stop_distance_m ({self.stop_distance_m}), "
                f"got {self.slow_distance_m}")
        require(0 < self.min_speed_ratio <= 1,
                f"min_speed_ratio must be in (0, 1], got {self.min_speed_ratio}")
        require(self.side_stop_margin_m <= self.side_margin_m,
                f"side_stop_margin_m must be <= side_margin_m ({self.side_margin_m}), "
                f"got {self.side_stop_margin_m}")
        require(self.clear_width_rad <= self.beam_width_rad,
                f"clear_width_rad must be <= beam_width_rad ({self.beam_width_rad}), "
                f"got {self.clear_width_rad}")


@dataclass(frozen=True, slots=True)
class TeleopConfig:
    """Driving by hand over the link (MANUAL_CONTROL in MANUAL mode, ``robot.runtime``)."""

    max_speed_m_s: float = 0.4
    """Forward speed at full stick (x = +-1000), m/s."""
    max_omega_rad_s: float = 0.7853981633974483
    """Turn rate at full stick (r = +-1000), rad/s (45 deg/s)."""
    deadman_ns: int = 500_000_000
    """No MANUAL_CONTROL for this long stops the robot, ns (ground stations send 10-50 Hz;
    QGroundControl's joystick sends at least every 50 ms while held)."""
    frame_timeout_ns: int = 500_000_000
    """No camera frame for this long stops the base until frames return, ns."""

    def __post_init__(self) -> None:
        for name in ("max_speed_m_s", "max_omega_rad_s", "deadman_ns", "frame_timeout_ns"):
            require(getattr(self, name) > 0, f"{name} must be > 0, got {getattr(self, name)}")

