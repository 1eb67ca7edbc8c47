"""JSON Schemas of every logged message, keyed by schema name (the schema's ``title``).

Every channel is ``json`` with a ``jsonschema`` schema. Foxglove recognises its
well-known types by schema name in any encoding it supports, JSON included, with
``bytes`` fields as base64 strings (docs.foxglove.dev: "Custom schema encodings";
the schema pages' "Reference implementations" table: JSON -> ``foxglove.CompressedImage``).
The Foxglove schemas below copy the field names, types and ``required`` lists of
``schemas/jsonschema/*.json`` in foxglove/foxglove-sdk, minus the optional ``uuid`` /
``lineage`` / ``metadata`` fields we never fill.

Our own schemas are flat (numbers at the top level, SI units in the names), so a
Plot panel takes ``/servo/state.lateral_error_m`` directly (mcap-logging.md §3).
MAVLink messages get one generated schema per message type, ``mavlink.<NAME>``.
"""

from __future__ import annotations

import functools
from typing import Any

Schema = dict[str, Any]
"""A JSON Schema object with a ``title`` (the MCAP schema name)."""


def _time(description: str) -> Schema:
    return {"type": "object", "title": "time", "description": description,
            "properties": {"sec": {"type": "integer", "minimum": 0},
                           "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}}


def _object(title: str, description: str, properties: dict[str, Schema]) -> Schema:
    """An object whose every property is required (Foxglove's generated schemas do so)."""
    return {"title": title, "description": description, "type": "object",
            "properties": properties, "required": list(properties)}


def _numbers(title: str, description: str, names_descriptions: dict[str, str]) -> Schema:
    return _object(title, description, {name: {"type": "number", "description": text}
                                        for name, text in names_descriptions.items()})


def _point2(description: str) -> Schema:
    return _numbers("foxglove.Point2", description,
                    {"x": "x coordinate position", "y": "y coordinate position"})


def _color(description: str) -> Schema:
    return _numbers("foxglove.Color", description, {c: f"{name} value between 0 and 1" for c, name
                                                   in zip("rgba", ("Red", "Green", "Blue", "Alpha"),
                                                          strict=True)})


_PIXELS = ("in 2D image coordinates (pixels).\nThe coordinate uses the top-left corner of the "
           "top-left pixel of the image as the origin.")

COMPRESSED_IMAGE = _object("foxglove.CompressedImage", "A compressed image", {
    "timestamp": _time("Timestamp of image"),
    "frame_id": {"type": "string", "description": "Frame of reference for the image. The origin "
                 "of the frame is the optical center of the camera. +x points to the right in the "
                 "image, +y points down, and +z points into the plane of the image."},
    "data": {"type": "string", "contentEncoding": "base64", "description": "Compressed image data"},
    "format": {"type": "string",
               "description": "Image format\n\nSupported values: `jpeg`, `png`, `webp`, `avif`"},
})

POINTS_ANNOTATION_TYPES = {"UNKNOWN": 0, "POINTS": 1, "LINE_LOOP": 2, "LINE_STRIP": 3,
                           "LINE_LIST": 4}
"""foxglove.PointsAnnotationType values."""

_POINTS_ANNOTATION = _object("foxglove.PointsAnnotation", "An array of points on a 2D image", {
    "timestamp": _time("Timestamp of annotation"),
    "type": {"title": "foxglove.PointsAnnotationType",
             "description": "Type of points annotation to draw",
             "oneOf": [{"title": k, "const": v} for k, v in POINTS_ANNOTATION_TYPES.items()]},
    "points": {"type": "array", "items": _point2("A point representing a position in 2D space"),
               "description": f"Points {_PIXELS}"},
    "outline_color": _color("Outline color"),
    "outline_colors": {"type": "array", "items": _color("A color in RGBA format"),
                       "description": "Per-point colors, if `type` is `POINTS`, or per-segment "
                       "stroke colors, if `type` is `LINE_LIST`, `LINE_STRIP` or `LINE_LOOP`."},
    "fill_color": _color("Fill color"),
    "thickness": {"type": "number", "description": "Stroke thickness in pixels"},
})

_CIRCLE_ANNOTATION = _object("foxglove.CircleAnnotation", "A circle annotation on a 2D image", {
    "timestamp": _time("Timestamp of circle"),
    "position": _point2(f"Center of the circle {_PIXELS}"),
    "diameter": {"type": "number", "description": "Circle diameter in pixels"},
    "thickness": {"type": "number", "description": "Line thickness in pixels"},
    "fill_color": _color("Fill color"),
    "outline_color": _color("Outline color"),
})

_TEXT_ANNOTATION = _object("foxglove.TextAnnotation", "A text label on a 2D image", {
    "timestamp": _time("Timestamp of annotation"),
    "position": _point2(f"Bottom-left origin of the text label {_PIXELS}"),
    "text": {"type": "string", "description": "Text to display"},
    "font_size": {"type": "number", "description": "Font size in pixels"},
    "text_color": _color("Text color"),
    "background_color": _color("Background fill color"),
})

IMAGE_ANNOTATIONS = _object("foxglove.ImageAnnotations", "Array of annotations for a 2D image", {
    "circles": {"type": "array", "items": _CIRCLE_ANNOTATION, "description": "Circle annotations"},
    "points": {"type": "array", "items": _POINTS_ANNOTATION, "description": "Points annotations"},
    "texts": {"type": "array", "items": _TEXT_ANNOTATION, "description": "Text annotations"},
})

FRAME_TRANSFORM = _object(
    "foxglove.FrameTransform",
    "A transform between two reference frames in 3D space. The transform defines the position "
    "and orientation of a child frame within a parent frame.",
    {
        "timestamp": _time("Timestamp of transform"),
        "parent_frame_id": {"type": "string", "description": "Name of the parent frame"},
        "child_frame_id": {"type": "string", "description": "Name of the child frame"},
        "translation": _numbers("foxglove.Vector3", "Translation component of the transform",
                                {a: f"{a} coordinate length" for a in "xyz"}),
        "rotation": _numbers("foxglove.Quaternion", "Rotation component of the transform",
                             {a: f"{a} value" for a in "xyzw"}),
    },
)

FRAME_TRANSFORMS = _object("foxglove.FrameTransforms", "An array of FrameTransform messages", {
    "transforms": {"type": "array", "items": FRAME_TRANSFORM, "description": "Array of transforms"},
})

LOG_LEVELS = {"UNKNOWN": 0, "DEBUG": 1, "INFO": 2, "WARNING": 3, "ERROR": 4, "FATAL": 5}
"""foxglove.LogLevel values."""

LOG = _object("foxglove.Log", "A log message", {
    "timestamp": _time("Timestamp of log message"),
    "level": {"title": "foxglove.LogLevel", "description": "Log level",
              "oneOf": [{"title": k, "const": v} for k, v in LOG_LEVELS.items()]},
    "message": {"type": "string", "description": "Log message"},
    "name": {"type": "string", "description": "Process or node name"},
    "file": {"type": "string", "description": "Filename"},
    "line": {"type": "integer", "minimum": 0, "description": "Line number in the file"},
})


def _flat(title: str, description: str, fields: dict[str, tuple[str | list[str], str]]) -> Schema:
    """A flat object: ``fields`` maps name -> (JSON type or types, description with units);
    the type ``"base64"`` is a string of base64 bytes."""
    def field(kind: str | list[str], text: str) -> Schema:
        if kind == "base64":
            return {"type": "string", "contentEncoding": "base64", "description": text}
        return {"type": kind, "description": text}

    return _object(title, description, {name: field(*spec) for name, spec in fields.items()})


_STAMP = ("integer", "capture time of the data, ns (the loop's clock)")

SERVO_STATE = _flat("vmnav.ServoState", "One mission cycle of the robot "
                    "(robot.mission_run.CycleRecord; robot.field_log.servo_state)", {
    "stamp_ns": _STAMP,
    "mode": ("string", "teach, repeat, idle, ..."),
    "mission_state": ("string", "the mission state after the cycle (robot.mission.MissionState: "
                      "idle, localizing, following, lost, arrived, aborted, failed)"),
    "target_index": ("integer", "index of the key image headed for among the route's targets "
                     "(its key images, junction crossings merged; their count on the cycle "
                     "that arrives); -1 when not following"),
    "key_image_id": (["integer", "null"], "id of that key image (the goal on the cycle that "
                     "arrives); null when not following"),
    "lateral_error_m": (["number", "null"], "y: lateral offset from the taught path, m "
                        "(filtered, what the control law used)"),
    "angular_error_rad": (["number", "null"], "theta: heading error to the taught path, rad "
                          "(filtered)"),
    "progress_m": (["number", "null"], "s: distance along the current segment, m (filtered)"),
    "v_m_s": ("number", "commanded forward speed, m/s (0 when not following)"),
    "omega_rad_s": ("number", "commanded turn rate, rad/s, counter-clockwise (0 when not "
                    "following)"),
    "matched_points": ("integer", "points matched to the key images (when not following: by "
                       "the localization)"),
    "inliers": (["integer", "null"], "matches consistent with the estimated geometry"),
    "lost": ("boolean", "the estimator declared the robot lost this cycle"),
    "switch_reason": (["string", "null"], "the key image switch this cycle completed: "
                      "image_error or passed (robot.switching.SWITCH_REASONS); null: none"),
    "err_image_max_px": (["number", "null"], "errImageMax: largest image distance between "
                         "matched points, px; null when not computed or without matches"),
    "err_points_px": (["number", "null"], "errPoints: mean image distance between matched "
                      "points, px; null when not computed or without matches"),
    "lateral_error_raw_m": (["number", "null"], "y as the vision estimated it this cycle, "
                            "before filtering, m; null without a usable estimate"),
    "angular_error_raw_rad": (["number", "null"], "theta as the vision estimated it, rad; null "
                              "without a usable estimate"),
    "progress_raw_m": (["number", "null"], "s as the vision estimated it, m; null without a "
                       "usable estimate"),
    "compute_ms": ("number", "the cycle's processing time, frame in to command out, ms of "
                   "wall time"),
})

COMMAND = _flat("vmnav.Command", "A velocity command sent to the base", {
    "stamp_ns": _STAMP,
    "linear_x_m_s": ("number", "forward speed, m/s"),
    "angular_z_rad_s": ("number", "turn rate, rad/s, counter-clockwise"),
    "source": ("string", "who commanded it: servo, teleop, stop, ..."),
})

SIP = _flat("vmnav.Sip", "A Pioneer server information packet (shared.aria.sip.Sip), flattened", {
    "stamp_ns": _STAMP,
    "moving": ("boolean", "SIP type 0x33 (moving) rather than 0x32 (stopped)"),
    "x_counts": ("integer", "XPOS, 15-bit position counter"),
    "y_counts": ("integer", "YPOS, 15-bit position counter"),
    "th_counts": ("integer", "THPOS, heading in AngleConvFactor units"),
    "left_vel_m_s": ("number", "left wheel velocity, m/s"),
    "right_vel_m_s": ("number", "right wheel velocity, m/s"),
    "battery_v": ("number", "battery, V"),
    "left_stalled": ("boolean", "left motor stalled"),
    "right_stalled": ("boolean", "right motor stalled"),
    "front_bumpers": ("integer", "front bumper segments pressed, bit mask"),
    "rear_bumpers": ("integer", "rear bumper segments pressed, bit mask"),
    "flags": ("integer", "FLAGS bits (SipFlags)"),
    "motors_enabled": ("boolean", "FLAGS bit 0"),
    "compass_rad": ("number", "compass heading, rad (0 without a compass)"),
    "sonar_count": ("integer", "new sonar readings in this SIP"),
    "sonar_min_m": (["number", "null"], "nearest of the new sonar readings, m"),
    "rot_vel_rad_s": (["number", "null"], "ROTVEL, rad/s, when the robot sends it"),
    "real_battery_v": (["number", "null"], "BATTERYX10, V, when the robot sends it"),
    "temperature_c": (["integer", "null"], "TEMPERATURE, degC, when the robot sends it"),
    "state_of_charge_pct": (["integer", "null"], "STATE_OF_CHARGE, %, when the robot sends it"),
})

MISSION_EVENT = _flat("vmnav.MissionEvent", "A mission event: goal set, started, reached, failed", {
    "stamp_ns": _STAMP,
    "event": ("string", "what happened, e.g. goal_received, started, reached, lost, aborted"),
    "state": ("string", "the mission state after the event"),
    "goal_key_image_id": (["integer", "null"], "the goal's key image"),
    "detail": ("string", "free text for the operator"),
})

RANGE_READING = _flat("vmnav.RangeReading", "One range sensor's latest echo "
                      "(shared.interfaces.RangeReading), flattened", {
    "sensor": ("integer", "the sensor's number on the base (P3-AT: 0-7 front, 8-15 rear)"),
    "sensor_x_m": ("number", "the sensor in base_link: x, m"),
    "sensor_y_m": ("number", "the sensor in base_link: y, m"),
    "sensor_heading_rad": ("number", "the sensor's axis in base_link, rad, counter-clockwise"),
    "range_m": ("number", "distance along the axis to the echo, m (the maximum: no echo)"),
    "stamp_ns": ("integer", "when the reading arrived, ns (the loop's clock)"),
    "odom_x_m": ("number", "base_link in odom when it arrived: x, m"),
    "odom_y_m": ("number", "base_link in odom when it arrived: y, m"),
    "odom_yaw_rad": ("number", "base_link in odom when it arrived: heading, rad"),
})

BASE_STATE = _object("vmnav.BaseState", "What the mobile base reported "
                     "(shared.interfaces.BaseState), flattened but for its range readings", {
    **_flat("", "", {
        "stamp_ns": _STAMP,
        "x_m": ("number", "odometry: x of base_link in odom, m"),
        "y_m": ("number", "odometry: y of base_link in odom, m"),
        "yaw_rad": ("number", "odometry: heading of base_link in odom, rad, counter-clockwise"),
        "odom_distance_m": ("number", "distance driven since the odometry started, m"),
        "bumped": ("boolean", "a bumper is pressed"),
        "bumped_rear_only": ("boolean", "the bumpers pressed are all at the rear"),
        "stalled": ("boolean", "a motor is stalled"),
        "battery_v": (["number", "null"], "battery, V (null when not a number)"),
        "motors_enabled": ("boolean", "the motors accept velocity commands"),
        "blocked_cause": (["string", "null"], "why the safety layer holds the robot "
                          "(obstacle, sonar_silent, pushed, bumper, e_stop); null: the way "
                          "is clear"),
        "blocked_distance_m": (["number", "null"], "the obstacle ahead of the front, m"),
        "blocked_since_ns": (["integer", "null"], "when the hold began, ns"),
    })["properties"],
    "ranges": {"type": "array", "items": RANGE_READING,
               "description": "each range sensor's latest reading"},
})

MISSION_START = _object("vmnav.MissionStart", "A mission run starts: what replay needs to "
                        "rebuild it (robot.mission_run.MissionRun)", {
    "stamp_ns": {"type": "integer", "description": "start time, ns (the loop's clock)"},
    "goal_key_image_id": {"type": "integer", "description": "the goal key image"},
    "rng_state": {"type": "object", "description": "the mission's numpy bit generator state "
                  "(numpy.random.Generator.bit_generator.state)"},
    "config": {"type": "object", "description": "the whole configuration "
               "(dataclasses.asdict of robot.config.VmnavConfig)"},
})

MAVLINK_RAW = _flat("mavlink.Raw", "One MAVLink frame as it crossed the link", {
    "direction": ("string", "in (received) or out (sent)"),
    "msgid": ("integer", "message id"),
    "name": ("string", "message name"),
    "sysid": ("integer", "sender system id"),
    "compid": ("integer", "sender component id"),
    "seq": ("integer", "packet sequence number, 0-255"),
    "frame": ("base64", "the whole packet, header to checksum"),
})

SCHEMAS: dict[str, Schema] = {s["title"]: s for s in (
    COMPRESSED_IMAGE, IMAGE_ANNOTATIONS, FRAME_TRANSFORM, FRAME_TRANSFORMS, LOG,
    SERVO_STATE, COMMAND, SIP, MISSION_EVENT, BASE_STATE, MISSION_START, MAVLINK_RAW)}
"""Every fixed schema by name; MAVLink message schemas come from :func:`mavlink_schema`."""

_MAVLINK_TYPES = {"float": "number", "double": "number"}


@functools.cache
def mavlink_schema(message_class: type) -> Schema:
    """The JSON Schema ``mavlink.<NAME>`` of one pymavlink message class.

    Built from the class's ``fieldnames`` / ``fieldtypes`` / ``array_lengths``: ``char``
    arrays are strings, other arrays lists of numbers, integers stay integers.
    """
    properties: dict[str, Schema] = {}
    for name, ctype, length in zip(message_class.fieldnames, message_class.fieldtypes,
                                   message_class.array_lengths, strict=True):
        kind = _MAVLINK_TYPES.get(ctype, "string" if ctype == "char" else "integer")
        if length and ctype != "char":
            properties[name] = {"type": "array", "items": {"type": kind}, "maxItems": length}
        else:
            properties[name] = {"type": kind}
    return _object(f"mavlink.{message_class.msgname}", f"MAVLink {message_class.msgname}",
                   properties)
