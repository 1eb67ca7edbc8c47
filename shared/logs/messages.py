"""Message builders: numbers and arrays in, JSON-ready dicts matching :mod:`.schemas` out
(and :func:`image_from_compressed`, the way back for images).

Pure functions (no clock, no I/O); the log writer's thread calls them, so the
control loop never pays for building or encoding a message. Times are integer ns, >= 0:
the Foxglove builders (``timestamp``, {sec, nsec}) are given Unix time, the data's time
plus the log's epoch offset (:mod:`shared.logs.writer`); our own messages
(``sip_fields``, ``base_state_fields``: ``stamp_ns``) keep the loop's clock, which is
what control and replay read.
"""

from __future__ import annotations

import base64
import binascii
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from shared.aria.sip import Sip, SipFlags, SipType
from shared.errors import InputError
from shared.image_decode import decode_grey
from shared.interfaces import BaseState
from shared.logs.schemas import LOG_LEVELS, POINTS_ANNOTATION_TYPES

NS_PER_S = 1_000_000_000

Rgba = tuple[float, float, float, float]
"""A colour, each channel in [0, 1]."""


def time_from_ns(t_ns: int) -> dict[str, int]:
    """Foxglove ``time`` ({sec, nsec}) of ``t_ns`` (>= 0, ns; Unix time in our logs)."""
    if t_ns < 0:
        raise ValueError(f"t_ns must be >= 0 for a Foxglove timestamp, got {t_ns}")
    sec, nsec = divmod(int(t_ns), NS_PER_S)
    return {"sec": sec, "nsec": nsec}


def encode_json(message: Mapping[str, Any]) -> bytes:
    """UTF-8 JSON of ``message``; NaN and infinities (not JSON) become ``null``."""
    try:
        return json.dumps(message, separators=(",", ":"), allow_nan=False).encode()
    except ValueError:
        return json.dumps(_finite(message), separators=(",", ":")).encode()


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, Mapping):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


def compressed_image(t_ns: int, frame_id: str, data: bytes, fmt: str = "jpeg") -> dict[str, Any]:
    """A ``foxglove.CompressedImage`` of encoded image bytes (``fmt``: jpeg, png, ...)."""
    return {"timestamp": time_from_ns(t_ns), "frame_id": frame_id,
            "data": base64.b64encode(data).decode("ascii"), "format": fmt}


def image_from_compressed(message: Mapping[str, Any]) -> tuple[npt.NDArray[np.uint8], str]:
    """The grey image of a ``foxglove.CompressedImage`` message, and its ``format``.

    Returns:
        (H, W) uint8 grey image (colour images are converted), and the format as logged
        (``jpeg``, ``png``, ...; ``""`` when missing).

    Raises:
        ValueError: no base64 ``data`` field, or data that is not a PNG or JPEG within
            :func:`shared.image_decode.decode_grey`'s limits, or does not decode.
    """
    try:
        data = base64.b64decode(message["data"], validate=True)
    except (KeyError, TypeError, binascii.Error):
        raise ValueError("no base64 'data' field") from None
    try:
        image = decode_grey(data, "data")
    except InputError as e:
        raise ValueError(e.problem) from None
    return image, str(message.get("format", ""))


def _color(rgba: Rgba) -> dict[str, float]:
    return dict(zip("rgba", map(float, rgba), strict=True))


def image_points(t_ns: int, pixels_xy: npt.NDArray[np.float64], color: Rgba, thickness_px: float,
                 label: str | None = None) -> dict[str, Any]:
    """A ``foxglove.ImageAnnotations`` with one POINTS annotation and an optional label.

    Args:
        t_ns: the annotated image's ``t_ns`` exactly: the Image panel pairs them by timestamp.
        pixels_xy: (N, 2) float64, pixel coordinates, origin at the top-left corner of the
            top-left pixel (OpenCV's pixel centres are at integers: add 0.5 to them).
        color: of the points.
        thickness_px: point size, px.
        label: text drawn at the top-left corner, e.g. ``"key 42: 117 matches"``.
    """
    stamp = time_from_ns(t_ns)
    transparent = _color((0.0, 0.0, 0.0, 0.0))
    points = {"timestamp": stamp, "type": POINTS_ANNOTATION_TYPES["POINTS"],
              "points": [{"x": x, "y": y} for x, y in np.asarray(pixels_xy, float).tolist()],
              "outline_color": _color(color), "outline_colors": [], "fill_color": transparent,
              "thickness": float(thickness_px)}
    texts = [] if label is None else [{
        "timestamp": stamp, "position": {"x": 8.0, "y": 24.0}, "text": label, "font_size": 18.0,
        "text_color": _color(color), "background_color": _color((0.0, 0.0, 0.0, 0.6))}]
    return {"circles": [], "points": [points], "texts": texts}


@dataclass(frozen=True, slots=True)
class FrameTransform:
    """Where ``child`` is in ``parent``: a point p_child maps to R p_child + t in ``parent``.

    Attributes:
        parent: parent frame id, e.g. ``"odom"``.
        child: child frame id, e.g. ``"base_link"``.
        translation_m: (x, y, z) of the child's origin in the parent frame, m.
        rotation_wxyz: unit quaternion of the child's orientation in the parent frame.
    """

    parent: str
    child: str
    translation_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation_wxyz: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)

    @classmethod
    def planar(cls, parent: str, child: str, x_m: float, y_m: float,
               yaw_rad: float) -> FrameTransform:
        """A pose in the plane: position (x, y), m, and yaw about z, rad, counter-clockwise."""
        half = 0.5 * yaw_rad
        return cls(parent, child, (float(x_m), float(y_m), 0.0),
                   (math.cos(half), 0.0, 0.0, math.sin(half)))


def frame_transforms(t_ns: int, transforms: Sequence[FrameTransform]) -> dict[str, Any]:
    """A ``foxglove.FrameTransforms``, every transform stamped ``t_ns``."""
    stamp = time_from_ns(t_ns)
    return {"transforms": [{
        "timestamp": stamp, "parent_frame_id": tf.parent, "child_frame_id": tf.child,
        "translation": dict(zip("xyz", map(float, tf.translation_m), strict=True)),
        "rotation": dict(zip("wxyz", map(float, tf.rotation_wxyz), strict=True)),
    } for tf in transforms]}


def log_entry(t_ns: int, level: str, message: str, name: str, file: str = "",
              line: int = 0) -> dict[str, Any]:
    """A ``foxglove.Log``; ``level`` is one of DEBUG, INFO, WARNING, ERROR, FATAL."""
    return {"timestamp": time_from_ns(t_ns), "level": LOG_LEVELS[level], "message": message,
            "name": name, "file": file, "line": int(line)}


def sip_fields(t_ns: int, sip: Sip) -> dict[str, Any]:
    """A ``vmnav.Sip``: the SIP's scalars, SI units, plus a summary of its sonar readings."""
    ranges = [reading.range_m for reading in sip.sonar]
    return {"stamp_ns": t_ns, "moving": sip.sip_type == SipType.MOVING,
            "x_counts": sip.x_counts, "y_counts": sip.y_counts, "th_counts": sip.th_counts,
            "left_vel_m_s": sip.left_vel_m_s, "right_vel_m_s": sip.right_vel_m_s,
            "battery_v": sip.battery_v, "left_stalled": sip.left_stalled,
            "right_stalled": sip.right_stalled, "front_bumpers": sip.front_bumpers,
            "rear_bumpers": sip.rear_bumpers, "flags": int(sip.flags),
            "motors_enabled": bool(sip.flags & SipFlags.MOTORS_ENABLED),
            "compass_rad": sip.compass_rad, "sonar_count": len(ranges),
            "sonar_min_m": min(ranges) if ranges else None, "rot_vel_rad_s": sip.rot_vel_rad_s,
            "real_battery_v": sip.real_battery_v, "temperature_c": sip.temperature_c,
            "state_of_charge_pct": sip.state_of_charge_pct}


def base_state_fields(t_ns: int, state: BaseState) -> dict[str, Any]:
    """A ``vmnav.BaseState``: every field of ``state``, poses split in three."""
    x_m, y_m, yaw_rad = state.odom_pose
    blocked = state.blocked
    distance = None if blocked is None or math.isnan(blocked.distance_m) else blocked.distance_m
    return {"stamp_ns": t_ns, "x_m": x_m, "y_m": y_m, "yaw_rad": yaw_rad,
            "odom_distance_m": state.odom_distance_m, "bumped": state.bumped,
            "bumped_rear_only": state.bumped_rear_only,
            "stalled": state.stalled, "battery_v": state.battery_v,
            "motors_enabled": state.motors_enabled,
            "blocked_cause": None if blocked is None else blocked.cause,
            "blocked_distance_m": distance,
            "blocked_since_ns": None if blocked is None else blocked.since_ns,
            "ranges": [{"sensor": r.sensor, "sensor_x_m": r.sensor_pose[0],
                        "sensor_y_m": r.sensor_pose[1], "sensor_heading_rad": r.sensor_pose[2],
                        "range_m": r.range_m, "stamp_ns": r.t_ns, "odom_x_m": r.odom_pose[0],
                        "odom_y_m": r.odom_pose[1], "odom_yaw_rad": r.odom_pose[2]}
                       for r in state.ranges]}


def mavlink_fields(msg: Any) -> dict[str, Any]:
    """The fields of a decoded pymavlink message (``mavlink.<NAME>``); bytes become base64."""
    fields = {}
    for name in msg.fieldnames:
        value = getattr(msg, name)
        if isinstance(value, bytes | bytearray):
            value = base64.b64encode(value).decode("ascii")
        fields[name] = value
    return fields


def mavlink_raw(direction: str, msg: Any, frame: bytes) -> dict[str, Any]:
    """A ``mavlink.Raw``: the packet ``frame`` of ``msg`` that went ``direction`` (in, out)."""
    return {"direction": direction, "msgid": msg.get_msgId(), "name": msg.get_type(),
            "sysid": msg.get_srcSystem(), "compid": msg.get_srcComponent(),
            "seq": msg.get_seq(), "frame": base64.b64encode(frame).decode("ascii")}
