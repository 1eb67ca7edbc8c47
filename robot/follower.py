"""The route follower: one servo cycle per frame, from the image to the velocity command.

Courbon et al. 2008, sec. III; DESIGN.md sec. 5.5-5.7. Per frame
(:meth:`RouteFollower.step`):

1. the base's odometry since the previous frame predicts the state
   (:meth:`robot.estimator.Estimator.predict`);
2. the frame's points (the front end's, :mod:`robot.vision.front_end`) are matched
   with the next key image's and give
   (s, y, theta) and the image errors (:func:`robot.vision.frame_state.state_from_frame`);
   a usable estimate updates the filter;
3. key image switching (:func:`robot.switching.observe_frame`) on errImageMax and
   the filtered s; a switch moves the filter to the next key image's frame
   (:meth:`robot.estimator.Estimator.switch_segment`) and prepares its segment.
   The goal, the last key image, is reached on the filtered s alone ("passed"):
   errImageMax falls under 20 px some 20 cm before a key image (measured in the
   lab), early for intermediate key images but a stop that far from the goal;
4. the control law (:func:`robot.control_law.steer`) on the filtered (y, theta);
   without an estimate the last command holds: zero before the first estimate
   (a start or a relocalization: the robot waits), the command before a junction
   crossing while the filter restarts there (the robot keeps its arc for the few
   frames it takes). An estimate that initialises the filter, which is not gated,
   must rest on at least ``EstimatorConfig.init_min_points`` triangulated points:
   three points past a junction once gave y = 1.05 m for a robot on the path.

The route is a list of key image ids from :meth:`shared.memory.VisualMemory.plan_route`.
A junction crossing (ids of different paths, the same place) is one target: the
key image on the path the route continues on (:func:`targets_from_route`). The
teach odometry of two paths shares no frame, and a junction joins key images
only up to about one key image spacing, so switching onto another path restarts
the estimator (its first vision estimate there initialises it, ungated) instead
of moving the state across.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from robot.config import (
    ControlConfig,
    EstimatorConfig,
    FeatureConfig,
    PathStateConfig,
    SwitchingConfig,
)
from robot.control_law import Twist, steer
from robot.estimator import Estimate, Estimator, EstimatorLost
from robot.segment_frame import arc_coordinates, relative_pose, segment_curvature_1_m
from robot.switching import FrameEvidence, KeyImageSwitch, SwitchState, observe_frame
from robot.vision.features import Features
from robot.vision.frame_state import (
    FrameState,
    KeySegment,
    key_segment_from_key_images,
    state_from_frame,
)
from robot.vision.front_end import check_front_end, make_front_end
from robot.vision.path_state import PathCoordinates
from shared.config import CameraMountConfig
from shared.errors import DegenerateGeometryError
from shared.interfaces import BaseState
from shared.memory import Keyframe, VisualMemory
from shared.pose import Pose2


@dataclass(frozen=True, slots=True)
class FollowerConfig:
    """The configs one servo cycle uses (all from :class:`robot.config.VmnavConfig`)."""

    features: FeatureConfig
    path_state: PathStateConfig
    estimator: EstimatorConfig
    switching: SwitchingConfig
    control: ControlConfig
    mount: CameraMountConfig


@dataclass(frozen=True, eq=False)
class FollowStep:
    """What one servo cycle did.

    Attributes:
        t_ns: the frame's time, ns.
        target_index: index into :attr:`RouteFollower.targets` headed for during the frame.
        twist: the command sent to the base.
        vision: the vision's answer (None when the segment has no usable key pair).
        corners_xy: (N, 2) float64 the frame's corners, px (for display).
        y_m, theta_rad, s_m: the filtered state used by the law (None before the first
            estimate).
        switch: the key image switch this frame completed, if any.
        lost: the estimator's LOST event, if this frame declared it.
        verified: the estimator took this frame's vision estimate (the robot's place
            along the route was verified by vision, not odometry alone).
    """

    t_ns: int
    target_index: int
    twist: Twist
    vision: FrameState | None
    corners_xy: npt.NDArray[np.float64]
    y_m: float | None
    theta_rad: float | None
    s_m: float | None
    switch: KeyImageSwitch | None
    lost: EstimatorLost | None
    verified: bool = False

    @property
    def arrived(self) -> bool:
        """The route's last key image was reached on this frame."""
        return self.switch is not None and self.switch.final


def targets_from_route(memory: VisualMemory, route: list[int]) -> tuple[int, ...]:
    """The key images to head for along a planned route, junction crossings merged.

    A run of junction crossings (consecutive ids on different paths) is one place;
    its last key image, on the path the route continues on, is the target.

    Raises:
        ValueError: the route is empty (no route from the start to the goal).
    """
    if not route:
        raise ValueError("route is empty: the memory does not connect start and goal")
    path_of = [memory.keyframe(k).path_id for k in route]
    return tuple(k for i, k in enumerate(route)
                 if i + 1 == len(route) or path_of[i + 1] == path_of[i])


def odometry_increment(before: Pose2, after: Pose2, distance_m: float) -> tuple[float, float]:
    """Forward distance (m, negative when reversing) and heading change (rad) between poses.

    Args:
        before: odometry pose at the previous frame.
        after: odometry pose now, same frame.
        distance_m: |path length| driven in between, m (odometry's distance counter).
    """
    dx, _, dpsi = relative_pose(before, after)
    return math.copysign(distance_m, dx), dpsi


class RouteFollower:
    """Follows one planned route key image after key image (see the module docstring).

    Args:
        memory: the visual memory.
        route: key image ids from the start to the goal (``plan_route``), not empty.
        config: the cycle's configs.
        rng: draws the RANSAC samples.
        now_ns: the current time, ns (starts the estimator's LOST timer).
        base: the base's state now (odometry origin of the first increment).

    Raises:
        ValueError: the route is empty.
        UnknownKeyframeError: a route id is not in the memory.
        MemoryFormatError: another front end than the config's described the memory.
    """

    def __init__(self, memory: VisualMemory, route: list[int], config: FollowerConfig,
                 rng: np.random.Generator, now_ns: int, base: BaseState) -> None:
        self._memory = memory
        self._config = config
        self._rng = rng
        self.targets = targets_from_route(memory, route)
        self._front_end = make_front_end(config.features, memory.camera)
        check_front_end(memory, config.features)
        self._estimator = Estimator(config.estimator, now_ns)
        self._paused_ns: int | None = None
        self._switching = SwitchState(route_length=len(self.targets))
        self._segments: dict[int, KeySegment | None] = {}
        self._odom = base.odom_pose
        self._distance_m = base.odom_distance_m
        self._twist = Twist(v_m_s=0.0, omega_rad_s=0.0)  # the last command
        self._init_gate = InitGate(config.estimator)

    @property
    def target_index(self) -> int:
        """Index of the target headed for (``len(targets)`` once arrived)."""
        return self._switching.next_index

    @property
    def finished(self) -> bool:
        """The goal key image was reached."""
        return self._switching.finished

    def pause(self, t_ns: int) -> None:
        """The robot stops for the safety layer at ``t_ns``; :meth:`resume` goes on."""
        self._paused_ns = t_ns

    def resume(self, t_ns: int) -> None:
        """Go on after :meth:`pause`: the route, the key image and the estimate stay; the
        time stood still does not count against the estimator's LOST timeout."""
        if self._paused_ns is not None:
            self._estimator.stood_still(t_ns - self._paused_ns)
        self._paused_ns = None

    def step(self, t_ns: int, image: npt.NDArray[np.uint8], base: BaseState) -> FollowStep:
        """One servo cycle on a frame.

        Args:
            t_ns: the frame's time, ns.
            image: (H, W) uint8 grey frame of the memory's camera.
            base: the base's state at the frame.

        Raises:
            RuntimeError: the route was already finished.
        """
        if self.finished:
            raise RuntimeError("RouteFollower.step: the route's goal was already reached")
        ds, dpsi = odometry_increment(self._odom, base.odom_pose,
                                      base.odom_distance_m - self._distance_m)
        self._odom, self._distance_m = base.odom_pose, base.odom_distance_m
        self._estimator.predict(ds, dpsi)
        index = self.target_index
        corners = self._front_end.describe(image)
        vision = self._vision(index, corners)
        verified = False
        if vision is not None and vision.state.ok and self._trusted(index, vision):
            verified = self._estimator.update(t_ns, vision.state.s_m, vision.state.y_m,
                                              vision.state.theta_rad).used
        lost = self._estimator.poll(t_ns)
        estimate = self._estimator.estimate
        final = index == len(self.targets) - 1
        evidence = FrameEvidence(
            t_ns=t_ns,
            err_image_max_px=None if vision is None or final
            else vision.image_errors.err_image_max_px,
            s_m=None if estimate is None else estimate.s_m,
        )
        self._switching, switch = observe_frame(self._switching, evidence,
                                                self._config.switching)
        if switch is not None and not switch.final:
            self._switch_estimator(t_ns, switch.next_index)
        twist = self._twist = self._command(index, estimate)
        return FollowStep(
            t_ns=t_ns, target_index=index, twist=twist, vision=vision,
            corners_xy=corners.pixels_xy,
            y_m=None if estimate is None else estimate.y_m,
            theta_rad=None if estimate is None else estimate.theta_rad,
            s_m=None if estimate is None else estimate.s_m,
            switch=switch, lost=lost, verified=verified,
        )

    def _keyframe(self, index: int) -> Keyframe:
        return self._memory.keyframe(self.targets[index])

    def _vision(self, index: int, corners: Features) -> FrameState | None:
        segment = self._segment(index)
        if segment is None:
            return None
        cfg = self._config
        return state_from_frame(corners, segment, self._front_end, cfg.mount, self._rng,
                                cfg.path_state)

    def _segment(self, index: int) -> KeySegment | None:
        """The target's segment, prepared once: with the previous key image of its path,
        or on a path's first key image with the one after it."""
        if index not in self._segments:
            self._segments[index] = self._prepare(self._keyframe(index))
        return self._segments[index]

    def _prepare(self, key: Keyframe) -> KeySegment | None:
        """The key image's segment with the nearest key image of its path that gives a
        trustworthy key pair at least :data:`_SHORT_BASELINE_M` away: the previous one,
        else up to ``_PARTNERS`` back, else up to as many forward (:func:`_partners`); the
        nearest trustworthy one when none is that far. Close key images in a turn, seeing
        only distant landmarks (the ``campus`` courtyard), can triangulate too few points,
        or fit a baseline whose direction disagrees with the odometry; key images a few
        centimetres apart triangulate points that the frames rarely match among their
        inliers."""
        cfg = self._config
        nearest: KeySegment | None = None
        for other, tracks in _partners(self._memory, key):
            try:
                segment = key_segment_from_key_images(
                    self._front_end.features_from_keyframe(key),
                    self._front_end.features_from_keyframe(other), key.odom_pose,
                    other.odom_pose, self._front_end, cfg.mount, self._rng, cfg.path_state,
                    tracks)
            except DegenerateGeometryError:
                continue
            if not segment.key_pair.ok:
                continue
            if segment.key_pair.baseline_m >= _SHORT_BASELINE_M:
                return segment
            if nearest is None:
                nearest = segment
        return nearest

    def _switch_estimator(self, t_ns: int, next_index: int) -> None:
        """Move the filter to the next target's frame (teach odometry), or restart it when
        the route changes paths there."""
        current, following = self._keyframe(next_index - 1), self._keyframe(next_index)
        if current.path_id == following.path_id:
            self._estimator.switch_segment(relative_pose(current.odom_pose, following.odom_pose))
        else:
            self._estimator.reset(t_ns)

    def _trusted(self, index: int, vision: FrameState) -> bool:
        """Whether a usable estimate may update the filter: always once it runs (the
        gate judges), else when :class:`InitGate` admits it."""
        if self._estimator.tracking:
            self._init_gate.clear()
            return True
        return self._init_gate.admits(index, vision.state.y_m, vision.state.theta_rad,
                                      vision.state.n_points)

    def _command(self, index: int, estimate: Estimate | None) -> Twist:
        cfg = self._config.control
        if estimate is None:
            return self._twist
        coords = PathCoordinates(estimate.s_m, estimate.y_m, estimate.theta_rad)
        curvature = self._curvature(index) if cfg.law == "paper+ff" else 0.0
        if curvature != 0.0:
            coords = arc_coordinates(coords, curvature)
        return steer(coords.y_m, coords.theta_rad, cfg, curvature)

    def _curvature(self, index: int) -> float:
        """Teach-path curvature into the target from its path predecessor, 1/m (0 if none)."""
        key = self._keyframe(index)
        if key.index == 0:
            return 0.0
        path = self._memory.paths[key.path_id].keyframe_ids
        previous = self._memory.keyframe(path[key.index - 1])
        length = key.distance_m - previous.distance_m
        if length <= 0:
            return 0.0
        return segment_curvature_1_m(previous.odom_pose, key.odom_pose, length)


#: Key images of a path tried as a target's partner in its key pair.
INIT_AGREEMENT_M = 0.05
"""Two estimates of y agree within this, m (``EstimatorConfig.init_agreeing_points``)."""
INIT_AGREEMENT_RAD = math.radians(3.0)
"""Two estimates of theta agree within this, rad."""


class InitGate:
    """Whether a vision estimate may initialise the filter (ungated: at a start, after a
    junction crossing or LOST): with ``init_min_points`` points behind it, or with at
    least ``init_agreeing_points`` when it agrees with the ``init_agreeing_frames`` - 1
    estimates of as many points before it (:class:`EstimatorConfig`). An estimate of fewer
    points is no vote and breaks no count: in a dim scene most frames have too few (a robot
    started 0.3 m beside the lab's route with half the lamps off: 3 or 4 points on 56 frames
    in 76, 5 or 6 on the others, all agreeing; clearing the count on the weak frames kept
    it from ever reaching three, and the robot, standing, never started)."""

    def __init__(self, config: EstimatorConfig) -> None:
        self._config = config
        self._votes: list[tuple[int, float, float]] = []  # (target index, y, theta) in a row

    def clear(self) -> None:
        """Forget the estimates seen so far."""
        self._votes.clear()

    def admits(self, index: int, y_m: float, theta_rad: float, n_points: int) -> bool:
        """Whether this estimate (target ``index``, y m, theta rad, key-pair points) may
        initialise the filter; an admitted one starts a new count."""
        cfg = self._config
        if n_points >= cfg.init_min_points:
            self._votes.clear()
            return True
        if n_points < cfg.init_agreeing_points:
            return False
        vote = (index, y_m, theta_rad)
        kept = self._votes[len(self._votes) + 1 - cfg.init_agreeing_frames:]
        self._votes = [*kept, vote] if all(_agree(v, vote) for v in kept) else [vote]
        if len(self._votes) < cfg.init_agreeing_frames:
            return False
        self._votes.clear()
        return True


def _agree(a: tuple[int, float, float], b: tuple[int, float, float]) -> bool:
    """Whether two (target index, y, theta) estimates agree: same target, close y, theta."""
    return (a[0] == b[0] and abs(a[1] - b[1]) <= INIT_AGREEMENT_M
            and abs(a[2] - b[2]) <= INIT_AGREEMENT_RAD)


_PARTNERS = 3
#: A key pair's baseline below this is a last resort, m. Measured on a teach by
#: teleoperation whose first key images came 9 to 16 cm apart (the HIL demo on a loaded
#: machine): paired with the key image 11 cm before it, key image 3 gave a state on 1
#: frame in 10 of the robot standing 0.3 m beside the route, and the robot got lost
#: three times; paired with the one 26 cm before it, on 6 in 10.
_SHORT_BASELINE_M = 0.15


def _partners(memory: VisualMemory,
              key: Keyframe) -> Iterator[tuple[Keyframe, npt.NDArray[np.int64]]]:
    """Key images of ``key``'s path to pair it with, each with the teach tracks (key's
    corner, partner's corner) chained through the key images between: up to
    :data:`_PARTNERS` before it, nearest first, then up to as many after it (a key image
    whose view of distant landmarks in a turn disagrees with the odometry towards every
    earlier one may agree with a later one)."""
    path = memory.paths[key.path_id].keyframe_ids
    for step in (-1, 1):
        tracks = np.column_stack([np.arange(len(key.pixels_xy))] * 2).astype(np.int64)
        current = key
        for n in range(1, _PARTNERS + 1):
            index = key.index + step * n
            if not 0 <= index < len(path):
                break
            partner = memory.keyframe(path[index])
            # tracked_from_previous pairs (earlier key image's corner, later's); link
            # pairs (current's corner, partner's).
            link = (current.tracked_from_previous[:, ::-1] if step < 0
                    else partner.tracked_from_previous)
            tracks = chain_tracks(tracks, link)
            current = partner
            yield partner, tracks


def chain_tracks(a_b: npt.ArrayLike, b_c: npt.ArrayLike) -> npt.NDArray[np.int64]:
    """Compose two track lists through their shared middle image.

    Args:
        a_b: (K, 2) int (corner in image a, corner in image b).
        b_c: (L, 2) int (corner in image b, corner in image c).

    Returns:
        (M, 2) int64 (corner in a, corner in c) for every b corner in both lists, in
        ``a_b``'s order.
    """
    a_b, b_c = np.asarray(a_b, dtype=np.int64), np.asarray(b_c, dtype=np.int64)
    to_c = dict(zip(b_c[:, 0].tolist(), b_c[:, 1].tolist(), strict=True))
    rows = [(a, to_c[b]) for a, b in a_b.tolist() if b in to_c]
    return np.array(rows, dtype=np.int64).reshape(-1, 2)
