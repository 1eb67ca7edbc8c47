"""Test helpers for the ARIA codec: golden frames, byte-stream tools, hypothesis strategies."""

from __future__ import annotations

import json
import math
from dataclasses import fields
from pathlib import Path

import numpy as np
from hypothesis import strategies as st

from shared.aria.commands import DATA_COMMANDS, ClientCommand, Command, DataArg
from shared.aria.config_packet import ConfigPacket
from shared.aria.framing import CorruptPacket, Packet, PacketBuffer
from shared.aria.sip import EncoderPacket, Sip, SipFlags, SipIo, SipType, SonarReading

GOLDEN_PATH = Path(__file__).resolve().parents[2] / "fixtures" / "aria_golden.json"


def golden() -> dict:
    """The golden frames of ``tests/fixtures/aria_golden.json``."""
    return json.loads(GOLDEN_PATH.read_text())


def hexbytes(text: str) -> bytes:
    return bytes.fromhex(text.replace(" ", ""))


def random_chunks(data: bytes, rng: np.random.Generator, max_chunk: int = 17) -> list[bytes]:
    """``data`` cut at random places into chunks of 1..max_chunk bytes."""
    chunks, at = [], 0
    while at < len(data):
        size = int(rng.integers(1, max_chunk + 1))
        chunks.append(data[at : at + size])
        at += size
    return chunks


def deframe(chunks: list[bytes]) -> tuple[list[Packet | CorruptPacket], PacketBuffer]:
    """Feed ``chunks`` one by one into a fresh buffer, draining it after each."""
    buffer, out = PacketBuffer(), []
    for chunk in chunks:
        buffer.feed(chunk)
        while (frame := buffer.next_frame()) is not None:
            out.append(frame)
    return out, buffer


def flip_checksum_byte(frame: bytes, which: int) -> bytes:
    """``frame`` with checksum byte ``which`` (0 = high, 1 = low) inverted."""
    at = len(frame) - 2 + which
    return frame[:at] + bytes((frame[at] ^ 0xFF,)) + frame[at + 1 :]


# -- strategies -------------------------------------------------------------------

u8 = st.integers(0, 0xFF)
u16 = st.integers(0, 0xFFFF)
s16 = st.integers(-0x8000, 0x7FFF)


def _mm(ints: st.SearchStrategy[int]) -> st.SearchStrategy[float]:
    return ints.map(lambda mm: mm / 1000)


def command_args(command: Command) -> st.SearchStrategy:
    """Arguments whose decoding is unambiguous: None, int, a string, or raw data."""
    options = [st.none(), st.integers(-0xFFFF, 0xFFFF)]
    if command in DATA_COMMANDS:
        # A 2-byte payload behind an int type byte would read back as an int.
        options.append(st.builds(DataArg, st.binary(min_size=3, max_size=40), u8))
    else:
        options.append(st.binary(max_size=60))
    return st.one_of(options)


client_commands = st.sampled_from(list(Command)).flatmap(
    lambda c: command_args(c).map(lambda arg: ClientCommand(c, arg))
)

sonar_readings = st.builds(SonarReading, u8, _mm(u16))
sip_ios = st.builds(SipIo, u8, u8, u8, u8, u8)
_TAIL_VALUES = (
    sip_ios,
    u16.map(lambda dv: dv / 10),
    u8,
    s16.map(lambda dd: math.radians(dd / 10)),
    u16,
    _mm(s16),
    st.integers(-128, 127),
    u8,
    st.integers(0, 2**32 - 1),
    st.integers(0, 2**32 - 1),
)
_TAIL_NAMES = (
    "io", "real_battery_v", "charge_state", "rot_vel_rad_s", "fault_flags", "lat_vel_m_s",
    "temperature_c", "state_of_charge_pct", "uc_time_us", "flags3",
)


@st.composite
def sips(draw: st.DrawFn) -> Sip:
    """SIPs with wire-representable values and any prefix of the optional groups."""
    groups = draw(st.integers(0, len(_TAIL_NAMES)))
    tail = {name: draw(values) for name, values in
            zip(_TAIL_NAMES[:groups], _TAIL_VALUES[:groups], strict=True)}
    return Sip(
        sip_type=draw(st.sampled_from(list(SipType))),
        x_counts=draw(st.integers(0, 0x7FFF)),
        y_counts=draw(st.integers(0, 0x7FFF)),
        th_counts=draw(s16),
        left_vel_m_s=draw(_mm(s16)),
        right_vel_m_s=draw(_mm(s16)),
        battery_v=draw(u8) / 10,
        left_stalled=draw(st.booleans()),
        right_stalled=draw(st.booleans()),
        rear_bumpers=draw(st.integers(0, 0x7F)),
        front_bumpers=draw(st.integers(0, 0x7F)),
        control_counts=draw(s16),
        flags=SipFlags(draw(u16)),
        compass_rad=math.radians(2 * draw(u8)),
        sonar=tuple(draw(st.lists(sonar_readings, max_size=16))),
        **tail,
    )


encoder_packets = st.builds(
    EncoderPacket, st.integers(-(2**31), 2**31 - 1), st.integers(-(2**31), 2**31 - 1)
)

_INT_FORMATS = {"B": (0, 0xFF), "b": (-128, 127), "H": (0, 0xFFFF), "h": (-0x8000, 0x7FFF),
                "I": (0, 2**32 - 1)}


def _config_value(fmt: str, unit: object) -> st.SearchStrategy:
    if fmt == "z":
        return st.text(st.characters(min_codepoint=1, max_codepoint=0xFF), max_size=10)
    ints = st.integers(*_INT_FORMATS[fmt])
    if unit == "ms":
        return ints.map(lambda ms: ms * 1_000_000)
    if unit is not None:
        return ints.map(unit.si)  # type: ignore[attr-defined]
    return ints


config_packets = st.builds(
    ConfigPacket,
    **{f.name: _config_value(f.metadata["fmt"], f.metadata["unit"]) for f in fields(ConfigPacket)},
)

