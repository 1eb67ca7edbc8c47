"""Topic and metadata names of the field logs (ROS-style, REP-105 frames; mcap-logging.md §3).

One place for them, so the robot, the sim, the ground station and the log tools
(info, replay, plots) agree.
"""

from __future__ import annotations

CAMERA_IMAGE = "/camera/image/compressed"
"""foxglove.CompressedImage, JPEG, frame ``camera``."""
CAMERA_ANNOTATIONS = "/camera/annotations"
"""foxglove.ImageAnnotations: matched points on the image with the same timestamp."""
TF = "/tf"
"""foxglove.FrameTransforms: ``odom`` -> ``base_link``, ``base_link`` -> ``camera``."""
SERVO_STATE = "/servo/state"
"""vmnav.ServoState, flat numbers per servo cycle."""
BASE_STATE = "/base/state"
"""vmnav.BaseState: what the mobile base reported at each mission cycle (replay feeds it back)."""
CMD_VEL = "/cmd_vel"
"""vmnav.Command sent to the base."""
SIP = "/pioneer/sip"
"""vmnav.Sip from the Pioneer."""
MISSION_EVENTS = "/mission/events"
"""vmnav.MissionEvent."""
MISSION_START = "/mission/start"
"""vmnav.MissionStart: a mission run's goal, random generator state and config (for replay)."""
LOG = "/log"
"""foxglove.Log: the bridge's text log (Log panel)."""
MAVLINK_RAW = "/mavlink/raw"
"""mavlink.Raw: every MAVLink frame in or out, base64, for lossless replay."""

FRAME_ODOM = "odom"
FRAME_BASE = "base_link"
FRAME_CAMERA = "camera"

MAVLINK_DIRECTIONS = ("in", "out")

CLOCK_METADATA = "clock"
"""Name of the metadata record, in every file, that ties the writer's clock to Unix time."""
UNIX_OFFSET_KEY = "unix_offset_ns"
"""Key of :data:`CLOCK_METADATA`: Unix time minus the writer's clock reading, integer ns, in
decimal. A message's ``log_time`` minus it is the data's time on that clock (time since
boot, or simulated time); a file without it (written before it existed) has 0."""


def mavlink_topic(direction: str, message_name: str) -> str:
    """``/mavlink/<direction>/<NAME>``: one topic per message type and direction (in, out)."""
    return f"/mavlink/{direction}/{message_name}"
