"""When the robot has reached the key image it heads for, and moves on to the next one.

Two rules (DESIGN.md sec. 5.7; reference visual-navigation.md sec. 1.3):

* ``"image_error"``: errImageMax, the longest distance between a matched point and
  its position in the key image, falls below a threshold (Courbon et al. 2008,
  sec. IV: 20 px; :func:`robot.vision.image_errors.image_errors`) while the
  robot is near the key image: a frame with an along-track estimate s must have
  s >= -``image_error_within_m`` (distant landmarks keep the image error small
  well before the key image; this guard adds to the paper's rule);
* ``"passed"``: the along-track coordinate s of the robot in the key image's frame
  (negative before it, :attr:`robot.vision.path_state.PathState.s_m`) reaches a
  margin: the robot has crossed the plane through the key image perpendicular to
  its heading. Image error alone is fragile when the robot runs laterally offset.

Rules of the state (:class:`SwitchState`), frame by frame:

1. The caller computes the frame's evidence against the key image at
   ``state.next_index`` and calls :func:`observe_frame`.
2. Each rule counts consecutive frames on which it holds (hysteresis). A frame
   with no value for a rule (None: not computed, no usable estimate) leaves its
   count alone; a value that fails the rule (including inf or NaN) resets it.
3. When a count reaches ``hold_frames``, the key image is reached: one
   :class:`KeyImageSwitch` event, ``next_index`` + 1, both counts back to 0. So at
   most one key image per frame, and every one has its event: none is skipped
   silently. Catching up after a long gap takes ``hold_frames`` frames per key image.
4. Reaching the route's last key image is the event with ``final = True``; the state
   is then finished and takes no more frames.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from robot.config import SwitchingConfig

#: Reasons of a :class:`KeyImageSwitch`, in order of precedence when both hold.
SWITCH_REASONS = ("image_error", "passed")


@dataclass(frozen=True, slots=True)
class FrameEvidence:
    """One frame's evidence about the key image at ``SwitchState.next_index``.

    Attributes:
        t_ns: the frame's time, ns.
        err_image_max_px: errImageMax against the key image, px; None when not computed
            (no evidence either way); inf when nothing matched (evidence against).
        s_m: along-track position relative to the key image, negative before it, m;
            None when there is no estimate.
    """

    t_ns: int
    err_image_max_px: float | None
    s_m: float | None


@dataclass(frozen=True, slots=True)
class SwitchState:
    """Progress along a route of ``route_length`` key images.

    Attributes:
        route_length: key images in the route, >= 1.
        next_index: route index of the key image the robot heads for;
            ``route_length`` once the last one is reached.
        image_frames: consecutive frames on which the image-error rule held.
        passed_frames: consecutive frames on which the passed rule held.
    """

    route_length: int
    next_index: int = 0
    image_frames: int = 0
    passed_frames: int = 0

    def __post_init__(self) -> None:
        if self.route_length < 1:
            raise ValueError(f"SwitchState: route_length must be >= 1, got {self.route_length}")
        if not 0 <= self.next_index <= self.route_length:
            raise ValueError(f"SwitchState: next_index must be in [0, {self.route_length}], "
                             f"got {self.next_index}")

    @property
    def finished(self) -> bool:
        """The last key image was reached."""
        return self.next_index >= self.route_length


@dataclass(frozen=True, slots=True)
class KeyImageSwitch:
    """The robot reached a key image of the route.

    Attributes:
        t_ns: time of the frame that completed the hysteresis, ns.
        reached_index: route index of the key image reached.
        next_index: route index now headed for (``route_length`` after the last).
        reason: one of ``SWITCH_REASONS``.
        err_image_max_px: the frame's errImageMax, px (None: not computed).
        s_m: the frame's along-track position relative to the reached key image, m
            (None: no estimate).
        final: the reached key image is the route's last.
    """

    t_ns: int
    reached_index: int
    next_index: int
    reason: str
    err_image_max_px: float | None
    s_m: float | None
    final: bool


def _count(held: bool | None, count: int) -> int:
    if held is None:
        return count
    return count + 1 if held else 0


def observe_frame(
    state: SwitchState, evidence: FrameEvidence, config: SwitchingConfig
) -> tuple[SwitchState, KeyImageSwitch | None]:
    """Advance the switching state by one frame.

    Args:
        state: the state before the frame.
        evidence: the frame's evidence about the key image at ``state.next_index``.
        config: thresholds and hysteresis.

    Returns:
        The new state, and the switch event when the frame completed one.

    Raises:
        RuntimeError: the state is finished (the route's last key image was reached).
    """
    if state.finished:
        raise RuntimeError(f"observe_frame: the route's last key image (index "
                         f"{state.route_length - 1}) was already reached")
    err, s = evidence.err_image_max_px, evidence.s_m
    near = s is None or s >= -config.image_error_within_m
    image_frames = _count(None if err is None else err < config.err_image_max_px and near,
                          state.image_frames)
    passed_frames = _count(None if s is None else s >= config.pass_margin_m, state.passed_frames)
    reasons = [reason for reason, frames in zip(SWITCH_REASONS, (image_frames, passed_frames),
                                                strict=True) if frames >= config.hold_frames]
    if not reasons:
        return replace(state, image_frames=image_frames, passed_frames=passed_frames), None
    reached = state.next_index
    new_state = SwitchState(route_length=state.route_length, next_index=reached + 1)
    event = KeyImageSwitch(t_ns=evidence.t_ns, reached_index=reached, next_index=reached + 1,
                           reason=reasons[0], err_image_max_px=err, s_m=s,
                           final=new_state.finished)
    return new_state, event
