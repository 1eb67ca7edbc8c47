"""The robot's live view: what its camera sees, served as MJPEG over HTTP (``vmnav robot
--video``) and described for the MAVLink camera protocol.

Rules:

1. **The loop never waits for it.** :meth:`LiveView.offer` is called by the robot's loop
   with every frame and the cycle it ran; it hands a frame over at most every
   ``VideoConfig.frame_period_ns`` (the others return at once) and only by reference:
   :class:`~shared.mjpeg_server.MjpegServer` scales, draws and encodes it in its
   clients' threads, and a client too slow for the frames skips to the newest one.
2. **The matches** drawn in the ``?matches=1`` view are the corners of the frame the
   vision matched with the key image the robot heads for, inliers of its estimate
   marked (:attr:`robot.vision.frame_state.FrameState.matched_xy`): while following only;
   other frames go without points. The key image's corners they were matched with
   (``FrameState.key_xy``) and its id go with them, for ``/matches.json``: a viewer
   draws them on the key image.
3. :func:`video_stream` describes the stream for the camera component
   (:mod:`shared.mavlink.camera`): its URI, the size it is served at, its rate, and the
   lens's horizontal field of view.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from robot.config import VideoConfig
from robot.mission_run import CycleRecord
from shared.camera_model import CameraModel
from shared.clock import NS_PER_S
from shared.mavlink.camera import VideoStream
from shared.mjpeg_server import MjpegServer, scaled_size

MatchedPoints = tuple[npt.NDArray[np.float64] | None, npt.NDArray[np.bool_] | None,
                      npt.NDArray[np.float64] | None]
"""(frame corners (N, 2) px, which are inliers (N,) bool, key image corners (N, 2) px)."""


def matched_points(record: CycleRecord | None) -> MatchedPoints:
    """The frame's matched corners, which are inliers, and the key image's corners they
    were matched with (rule 2); (None, None, None) without."""
    follow = None if record is None else record.follow
    vision = None if follow is None else follow.vision
    if vision is None or len(vision.matched_xy) == 0:
        return None, None, None
    inliers = vision.state.inlier_mask
    key_xy = vision.key_xy if len(vision.key_xy) == len(vision.matched_xy) else None
    return (vision.matched_xy, inliers if len(inliers) == len(vision.matched_xy) else None,
            key_xy)


class FramePacer:
    """At most one frame per ``period_ns`` of frame time: the first frame is due, then one
    each period after it; after a gap, the next frame is due at once.

    Args:
        period_ns: the shortest time between two frames let through, ns.
    """

    def __init__(self, period_ns: int) -> None:
        self._period_ns = period_ns
        self._next_ns: int | None = None

    def due(self, t_ns: int) -> bool:
        """Whether the frame at ``t_ns`` goes out (then the next is due a period later)."""
        if self._next_ns is not None and t_ns < self._next_ns:
            return False
        next_ns = (t_ns if self._next_ns is None else self._next_ns) + self._period_ns
        self._next_ns = next_ns if next_ns > t_ns else t_ns + self._period_ns
        return True


class LiveView:
    """The robot loop's side of the live view (rule 1).

    Args:
        server: where the frames go (opened by the caller, who closes it).
        config: the frame period.
    """

    def __init__(self, server: MjpegServer, config: VideoConfig) -> None:
        self.server = server
        self._pacer = FramePacer(config.frame_period_ns)

    def offer(self, t_ns: int, image: npt.NDArray[np.uint8], record: CycleRecord | None,
              next_key: int | None = None) -> None:
        """The loop's frame at ``t_ns`` (H, W) uint8 grey, the cycle it ran (None: no
        mission run) and the key image it headed for (VISUAL_SERVO_STATUS ``next_key``):
        published if a period has passed since the last one."""
        if self._pacer.due(t_ns):
            points_xy, inliers, key_xy = matched_points(record)
            self.server.publish(t_ns, image, points_xy, inliers, key_xy=key_xy,
                                key_id=None if key_xy is None else next_key)


def video_stream(server: MjpegServer, config: VideoConfig, camera: CameraModel) -> VideoStream:
    """The stream ``server`` serves, for the camera protocol (rule 3).

    Args:
        server: the live view's server (its URL and port).
        config: the served width and the frame period.
        camera: the calibrated camera whose frames it serves (their size, the lens's
            field of view).
    """
    width, height = scaled_size((camera.width, camera.height), config.width_px)
    return VideoStream(server.stream_url, width, height, NS_PER_S / config.frame_period_ns,
                       hfov_deg=min(360, round(camera.fov_deg)))
