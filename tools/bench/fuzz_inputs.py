"""Seeded input mutators for ``vmnav bench fuzz``: bytes, ARIA frames, PNG, JSON, npz, MAVLink.

Every function takes the input's ``numpy.random.Generator`` and nothing else random,
so an input is a pure function of (seed, target, index) (:mod:`tools.bench.fuzz`).
The mutations are those of AFL and libFuzzer (bit flips, interesting integers, byte
insertion, deletion and duplication, truncation) plus structure-aware ones that keep
an outer check intact so that the mutated field reaches the decoder behind it: an ARIA
or PNG checksum recomputed, a zip member's CRC rewritten, a JSON number swapped for
an extreme one, a MAVLink message with random field values packed (and signed) by a
real codec.
"""

from __future__ import annotations

import io
import math
import re
import struct
import zipfile
import zlib
from typing import Any

import numpy as np

from shared.aria.framing import MAX_DATA_LEN, encode_packet
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.ftp.payload import MAX_DATA, FtpPayload, Opcode

#: Integers AFL calls interesting, as (value, byte width): boundaries of every width.
INTERESTING_INTS: tuple[tuple[int, int], ...] = (
    (0, 1), (1, 1), (0x7F, 1), (0x80, 1), (0xFF, 1),
    (0, 2), (0x7FFF, 2), (0x8000, 2), (0xFFFF, 2), (0xFFFE, 2), (1000, 2),
    (0x7FFFFFFF, 4), (0x80000000, 4), (0xFFFFFFFF, 4), (0x40000000, 4), (30000, 4),
    (0x7FFFFFFFFFFFFFFF, 8), (0x8000000000000000, 8), (0xFFFFFFFFFFFFFFFF, 8),
)
#: Floats that break arithmetic: non-finite, extreme, denormal, negative zero.
INTERESTING_FLOATS = (math.nan, math.inf, -math.inf, 0.0, -0.0, 1.0, -1.0, 1000.0,
                      3.4028235e38, -3.4028235e38, 1e-45, 1e300, -1e300)
#: JSON texts swapped for a number in a JSON file: overflow, wrong types, deep nesting.
INTERESTING_JSON = ("1e400", "-1e400", "1" + "0" * 400, "-1", "0", "1.5", "NaN", "Infinity",
                    "null", "true", '"x"', "[]", "{}", "[" * 50_000 + "]" * 50_000, "4294967296",
                    "9223372036854775808")


def mutate_bytes(data: bytes, rng: np.random.Generator, max_ops: int = 4) -> bytes:
    """``data`` after 1..``max_ops`` random byte-level mutations (module docstring)."""
    buf = bytearray(data)
    for _ in range(int(rng.integers(1, max_ops + 1))):
        op = int(rng.integers(8))
        at = int(rng.integers(len(buf))) if buf else 0
        if op == 0 and buf:
            buf[at] ^= 1 << int(rng.integers(8))
        elif op == 1 and buf:
            buf[at] = int(rng.integers(256))
        elif op == 2:
            buf[at:at] = rng.bytes(int(rng.integers(1, 17)))
        elif op == 3 and buf:
            del buf[at:at + int(rng.integers(1, 17))]
        elif op == 4 and buf:
            buf[at:at] = buf[at:at + int(rng.integers(1, 33))]
        elif op == 5 and buf:
            value, width = INTERESTING_INTS[int(rng.integers(len(INTERESTING_INTS)))]
            order = "little" if rng.integers(2) else "big"
            buf[at:at + width] = value.to_bytes(width, order)
        elif op == 6 and buf:
            value = INTERESTING_FLOATS[int(rng.integers(len(INTERESTING_FLOATS)))]
            buf[at:at + 4] = struct.pack("<f" if abs(value) < 3.5e38 else "<d", value)
        elif op == 7 and buf:
            del buf[int(rng.integers(len(buf) + 1)):]
    return bytes(buf)


# -- ARIA ---------------------------------------------------------------------------------


def aria_stream(frames: list[tuple[int, bytes]], rng: np.random.Generator) -> bytes:
    """Frame ``(packet id, data)`` pairs as one ARIA byte stream, mutated.

    Each frame's data is mutated and checksummed afresh (so it reaches the decoder) with
    probability 1/2, sent as is otherwise; then the whole stream gets byte-level
    mutations (mostly caught by the checksum) with probability 1/4.
    """
    out = bytearray()
    for packet_id, data in frames:
        if rng.random() < 0.5:
            data = mutate_bytes(data, rng, max_ops=3)[:MAX_DATA_LEN]
        out += encode_packet(packet_id, data)
    return mutate_bytes(bytes(out), rng) if rng.random() < 0.25 else bytes(out)


def aria_int_arg(rng: np.random.Generator) -> bytes:
    """An ARIA int argument (sign byte, u16 magnitude LE): a boundary or a random value."""
    magnitude = int(rng.choice([0, 1, 255, 256, 0x7FFF, 0x8000, 0xFFFF, int(rng.integers(65536))]))
    sign = 0x3B if rng.random() < 0.6 else 0x1B
    return bytes((sign,)) + magnitude.to_bytes(2, "little")


# -- files --------------------------------------------------------------------------------


def mutate_png(png: bytes, rng: np.random.Generator) -> bytes:
    """A PNG with one chunk's length or content mutated and its CRC recomputed (3 times in
    4; IHDR's width, height, depth and colour type are the usual victims), else raw
    byte-level mutations."""
    if rng.random() < 0.25 or not png.startswith(b"\x89PNG\r\n\x1a\n"):
        return mutate_bytes(png, rng)
    chunks: list[list[Any]] = []  # [length, type, data]
    at = 8
    while at + 8 <= len(png):
        length, kind = struct.unpack_from(">I4s", png, at)
        chunks.append([length, kind, png[at + 8:at + 8 + length]])
        at += 12 + length
    victim = chunks[0] if rng.random() < 0.5 else chunks[int(rng.integers(len(chunks)))]
    if rng.random() < 0.2:
        victim[0] = int(rng.choice([0, 1, 0x7FFFFFFF, 0xFFFFFFFF, int(rng.integers(1 << 31))]))
    else:
        victim[2] = mutate_bytes(victim[2], rng, max_ops=2)
        victim[0] = len(victim[2])
    out = bytearray(png[:8])
    for length, kind, data in chunks:
        out += struct.pack(">I4s", length, kind) + data
        out += struct.pack(">I", zlib.crc32(kind + data))
    return bytes(out)


def mutate_json(text: bytes, rng: np.random.Generator) -> bytes:
    """A JSON text with one number (or string) replaced by an interesting JSON value (3
    times in 4), else raw byte-level mutations."""
    tokens = [m.span() for m in re.finditer(rb'-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?|"[^"]*"', text)]
    if rng.random() < 0.25 or not tokens:
        return mutate_bytes(text, rng)
    start, end = tokens[int(rng.integers(len(tokens)))]
    value = INTERESTING_JSON[int(rng.integers(len(INTERESTING_JSON)))].encode()
    return text[:start] + value + text[end:]


def mutate_npz(npz: bytes, rng: np.random.Generator) -> bytes:
    """An .npz with one member's bytes mutated (its .npy header and shape included) and
    re-zipped with valid CRCs (3 times in 4), else raw byte-level mutations."""
    if rng.random() < 0.25:
        return mutate_bytes(npz, rng)
    with zipfile.ZipFile(io.BytesIO(npz)) as archive:
        members = {name: archive.read(name) for name in archive.namelist()}
    name = sorted(members)[int(rng.integers(len(members)))]
    member = members[name]
    header_end = member.find(b"\n") + 1
    if rng.random() < 0.5 and header_end > 0:  # a shape or dtype the header cannot mean
        header = re.sub(rb"\((\d+), ?(\d+)\)", lambda m: b"(%d, %s)" % (
            int(rng.choice([0, 1, 10**6, 2**31, 2**40, 2**62])), m.group(2)), member[:header_end])
        member = header + member[header_end:]
    else:
        member = mutate_bytes(member, rng, max_ops=2)
    members[name] = member
    out = io.BytesIO()
    compression = zipfile.ZIP_DEFLATED if rng.random() < 0.3 else zipfile.ZIP_STORED
    with zipfile.ZipFile(out, "w", compression) as archive:
        for member_name, content in members.items():
            archive.writestr(member_name, content)
    return out.getvalue()


# -- MAVLink ------------------------------------------------------------------------------

_INT_RANGES = {"int8_t": (-128, 127), "uint8_t": (0, 255), "int16_t": (-(1 << 15), (1 << 15) - 1),
               "uint16_t": (0, (1 << 16) - 1), "int32_t": (-(1 << 31), (1 << 31) - 1),
               "uint32_t": (0, (1 << 32) - 1), "int64_t": (-(1 << 63), (1 << 63) - 1),
               "uint64_t": (0, (1 << 64) - 1)}
#: Fields whose useful values are few: (0 = broadcast, 1 = the vehicle) most of the time.
_ADDRESS_FIELDS = ("target_system", "target_component", "target")


def random_int(kind: str, rng: np.random.Generator, name: str = "") -> int:
    """A value of C integer type ``kind``: a boundary, a small number or any value."""
    low, high = _INT_RANGES[kind]
    pick = rng.random()
    if name in _ADDRESS_FIELDS and pick < 0.8:
        return int(rng.integers(2))
    if pick < 0.3:
        boundaries = (low, high, 0, 1, high - 1)
        return boundaries[int(rng.integers(len(boundaries)))]
    if pick < 0.7:
        return int(rng.integers(max(low, -2), min(high, 10) + 1))
    return int(rng.integers(low, high, endpoint=True, dtype=np.uint64 if low == 0 else np.int64))


def random_float(rng: np.random.Generator) -> float:
    """A float32-representable value: an interesting one, a small integer or a random one."""
    pick = rng.random()
    if pick < 0.3:
        value = INTERESTING_FLOATS[int(rng.integers(len(INTERESTING_FLOATS)))]
        return value if not math.isfinite(value) or abs(value) < 3.5e38 else math.copysign(
            math.inf, value)
    if pick < 0.7:
        return float(rng.integers(-2, 11))
    return float(np.float32(rng.normal(0.0, 1000.0)))


def random_message(cls: type[Message], rng: np.random.Generator,
                   overrides: dict[str, Any] | None = None) -> Message:
    """A ``cls`` message with random field values (``overrides`` fixes some by name)."""
    lengths = dict(zip(cls.ordered_fieldnames, cls.array_lengths, strict=True))
    values: list[Any] = []
    for name, kind in zip(cls.fieldnames, cls.fieldtypes, strict=True):
        length = lengths[name]
        if overrides is not None and name in overrides:
            values.append(overrides[name])
        elif kind == "char":
            size = int(rng.integers(max(length, 1) + 1))
            values.append(bytes(rng.integers(1, 256 if rng.random() < 0.2 else 128, size,
                                             dtype=np.uint8)))
        elif kind in ("float", "double"):
            values.append([random_float(rng) for _ in range(length)] if length
                          else random_float(rng))
        elif length:
            values.append([random_int(kind, rng) for _ in range(length)])
        else:
            values.append(random_int(kind, rng, name))
    return cls(*values)


def _goal_fields(rng: np.random.Generator) -> dict[str, Any]:
    """Three times in four, the fields that make an item a goal the vehicle may accept
    (``shared.mavlink.mission.goal``: the goal command, param1 a key image id 0..7), so
    that the other fields' values go on to the mission in force and its download."""
    if rng.random() < 0.25:
        return {}
    return {"command": mavlink.MAV_CMD_WAYPOINT_USER_1, "param1": float(rng.integers(8)),
            "param2": 0.0, "param3": 0.0, "param4": 0.0}


def mission_upload(rng: np.random.Generator, legacy: bool) -> list[Message]:
    """MISSION_COUNT of 1..3 items then the items in order (MISSION_ITEM when ``legacy``,
    else MISSION_ITEM_INT), target the vehicle, random fields otherwise; half the time
    followed by the download of the mission (MISSION_REQUEST_LIST, MISSION_REQUEST_INT
    of each item), which sends the items back."""
    count = int(rng.integers(1, 4))
    item = mavlink.MAVLink_mission_item_message if legacy else \
        mavlink.MAVLink_mission_item_int_message
    target = {"target_system": 1, "target_component": 1, "mission_type": 0}
    upload = [random_message(mavlink.MAVLink_mission_count_message, rng,
                             {**target, "count": count}),
              *(random_message(item, rng, {**target, "seq": seq, **_goal_fields(rng)})
                for seq in range(count))]
    if rng.random() < 0.5:
        return upload
    return [*upload, mavlink.MAVLink_mission_request_list_message(1, 1, 0),
            *(mavlink.MAVLink_mission_request_int_message(1, 1, seq, 0) for seq in range(count))]


#: Paths an FTP request names: the served memory, the upload area, escapes and junk.
FTP_PATHS = (b"/memory/manifest.json", b"/memory", b"/upload/1.png", b"/upload", b"/",
             b"/upload/../../etc/passwd", b"/memory/images/0.png", b"", b"\xff\xfe", b"/" * 200)


def ftp_request(rng: np.random.Generator) -> Message:
    """A FILE_TRANSFER_PROTOCOL request to the vehicle: a real opcode, random session,
    offset and size, a path or random data."""
    opcode = int(rng.choice([int(op) for op in Opcode])) if rng.random() < 0.9 else \
        int(rng.integers(256))
    data = FTP_PATHS[int(rng.integers(len(FTP_PATHS)))] if rng.random() < 0.7 else \
        rng.bytes(int(rng.integers(MAX_DATA + 1)))
    payload = FtpPayload(
        seq=int(rng.integers(0x10000)), session=int(rng.choice([0, 1, 255])), opcode=opcode,
        size=int(rng.choice([0, len(data), 239, 255])) if rng.random() < 0.8 else len(data),
        offset=random_int("uint32_t", rng), data=data)
    return mavlink.MAVLink_file_transfer_protocol_message(0, 1, 1, list(payload.to_bytes()))
