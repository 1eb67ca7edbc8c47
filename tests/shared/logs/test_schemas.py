"""The schemas carry Foxglove's names and fields, and the builders produce what they describe."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pytest

from shared.aria.sip import Sip, SipFlags, SipIo, SipType, SonarReading
from shared.logs import messages
from shared.logs.schemas import SCHEMAS, Schema, mavlink_schema
from shared.mavlink.dialect import make_codec, mavlink

_JSON_TYPES = {"integer": int, "number": (int, float), "string": str, "boolean": bool,
               "null": type(None), "array": list, "object": dict}


def conforms(value: Any, schema: Schema, where: str = "$") -> None:
    """Assert ``value`` matches ``schema``: exactly the declared keys (all are required in
    our schemas), the declared JSON types, recursively; enums by their ``const`` values."""
    if "oneOf" in schema:
        assert value in [option["const"] for option in schema["oneOf"]], where
        return
    kinds = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
    assert any(isinstance(value, _JSON_TYPES[k]) and not (k in ("integer", "number")
               and isinstance(value, bool)) for k in kinds), f"{where}: {value!r} not {kinds}"
    if isinstance(value, dict):
        assert set(value) == set(schema["properties"]), where
        assert set(schema.get("required", value)) == set(value), where  # time has none
        for key, item in value.items():
            conforms(item, schema["properties"][key], f"{where}.{key}")
    elif isinstance(value, list) and "items" in schema:
        for i, item in enumerate(value):
            conforms(item, schema["items"], f"{where}[{i}]")


class TestFoxgloveSchemas:
    """Field names as in foxglove-sdk's schemas/jsonschema/*.json (the Foxglove docs)."""

    @pytest.mark.parametrize(("name", "fields"), [
        ("foxglove.CompressedImage", ["timestamp", "frame_id", "data", "format"]),
        ("foxglove.ImageAnnotations", ["circles", "points", "texts"]),
        ("foxglove.FrameTransforms", ["transforms"]),
        ("foxglove.FrameTransform",
         ["timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"]),
        ("foxglove.Log", ["timestamp", "level", "message", "name", "file", "line"]),
    ])
    def test_names_and_fields(self, name: str, fields: list[str]) -> None:
        schema = SCHEMAS[name]
        assert schema["title"] == name
        assert list(schema["properties"]) == fields
        json.dumps(schema)  # serialisable as it is written into the file

    def test_nested_types_keep_foxglove_titles(self) -> None:
        points = SCHEMAS["foxglove.ImageAnnotations"]["properties"]["points"]["items"]
        assert points["title"] == "foxglove.PointsAnnotation"
        assert list(points["properties"]) == ["timestamp", "type", "points", "outline_color",
                                              "outline_colors", "fill_color", "thickness"]
        assert points["properties"]["points"]["items"]["title"] == "foxglove.Point2"
        rotation = SCHEMAS["foxglove.FrameTransform"]["properties"]["rotation"]
        assert (rotation["title"], list(rotation["properties"])) == ("foxglove.Quaternion",
                                                                     list("xyzw"))
        data = SCHEMAS["foxglove.CompressedImage"]["properties"]["data"]
        assert data == {"type": "string", "contentEncoding": "base64",
                        "description": "Compressed image data"}

    def test_flat_schemas_have_only_scalars_at_the_top(self) -> None:
        for name in ("vmnav.ServoState", "vmnav.Command", "vmnav.Sip", "vmnav.MissionEvent"):
            for key, prop in SCHEMAS[name]["properties"].items():
                kinds = prop["type"] if isinstance(prop["type"], list) else [prop["type"]]
                assert set(kinds) <= {"integer", "number", "string", "boolean", "null"}, key


class TestBuilders:
    def test_time_splits_ns(self) -> None:
        assert messages.time_from_ns(12_345_678_901) == {"sec": 12, "nsec": 345_678_901}
        with pytest.raises(ValueError, match="t_ns must be >= 0"):
            messages.time_from_ns(-1)

    def test_image_points_and_transforms_conform(self) -> None:
        pixels = np.array([[1.5, 2.5], [799.0, 599.0]])
        annotations = messages.image_points(5, pixels, (0, 1, 0, 1), 3.0, "key 4: 2 matches")
        conforms(annotations, SCHEMAS["foxglove.ImageAnnotations"])
        assert annotations["points"][0]["points"] == [{"x": 1.5, "y": 2.5},
                                                      {"x": 799.0, "y": 599.0}]
        tf = messages.FrameTransform.planar("odom", "base_link", 1.0, -2.0, math.pi / 2)
        transforms = messages.frame_transforms(7, [tf, messages.FrameTransform("base_link",
                                                                               "camera")])
        conforms(transforms, SCHEMAS["foxglove.FrameTransforms"])
        rotation = transforms["transforms"][0]["rotation"]
        assert rotation == pytest.approx({"x": 0, "y": 0, "z": math.sqrt(0.5),
                                          "w": math.sqrt(0.5)})

    def test_image_and_log_conform(self) -> None:
        conforms(messages.compressed_image(3, "camera", b"\xff\xd8"),
                 SCHEMAS["foxglove.CompressedImage"])
        entry = messages.log_entry(3, "WARNING", "low battery", "robot")
        conforms(entry, SCHEMAS["foxglove.Log"])
        assert entry["level"] == 3

    def test_sip_fields_conform(self) -> None:
        sip = Sip(sip_type=SipType.MOVING, x_counts=100, left_vel_m_s=0.2, battery_v=12.9,
                  flags=SipFlags.MOTORS_ENABLED,
                  sonar=(SonarReading(0, 1.2), SonarReading(3, 0.4)), io=SipIo(),
                  real_battery_v=13.1, charge_state=0, rot_vel_rad_s=0.1)
        fields = messages.sip_fields(42, sip)
        conforms(fields, SCHEMAS["vmnav.Sip"])
        assert (fields["moving"], fields["motors_enabled"], fields["sonar_min_m"],
                fields["real_battery_v"]) == (True, True, 0.4, 13.1)
        assert fields["temperature_c"] is None
        conforms(messages.sip_fields(0, Sip()), SCHEMAS["vmnav.Sip"])

    def test_mavlink_fields_and_raw_conform(self) -> None:
        vehicle = make_codec(1, 1)
        messages_sent = [mavlink.MAVLink_heartbeat_message(10, 8, 0, 0, 4, 3),
                         mavlink.MAVLink_statustext_message(6, b"goal reached", 0, 0),
                         mavlink.MAVLink_file_transfer_protocol_message(0, 1, 1,
                                                                        list(range(251)))]
        for msg in messages_sent:
            frame = vehicle.pack(msg)
            schema = mavlink_schema(type(msg))
            assert schema["title"] == f"mavlink.{msg.get_type()}"
            conforms(messages.mavlink_fields(msg), schema)
            raw = messages.mavlink_raw("out", msg, frame)
            conforms(raw, SCHEMAS["mavlink.Raw"])
            assert (raw["name"], raw["sysid"], raw["compid"]) == (msg.get_type(), 1, 1)

    def test_json_encoding_turns_non_finite_numbers_into_null(self) -> None:
        data = messages.encode_json({"a": math.nan, "b": [1.0, math.inf], "c": {"d": -math.inf}})
        assert json.loads(data) == {"a": None, "b": [1.0, None], "c": {"d": None}}
        assert messages.encode_json({"a": 1.5}) == b'{"a":1.5}'
