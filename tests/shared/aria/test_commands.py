"""Client commands: argument encoding, robot-side decoding, SI helpers (reference §2, §4)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given

from shared.aria.commands import (
    WIRE_UNITS,
    ClientCommand,
    Command,
    DataArg,
    battest,
    dchead,
    dhead,
    enable,
    head,
    move,
    rotate,
    rvel,
    seta,
    setra,
    setrv,
    setrvdir,
    setv,
    sim_set_pose,
    vel,
    vel2,
    vel2_wheels,
)
from shared.aria.framing import CorruptPacket, Packet, decode_packet
from shared.errors import ChecksumError, LocalProtocolError, RemoteProtocolError
from tests.shared.aria.helpers import (
    client_commands,
    deframe,
    flip_checksum_byte,
    golden,
    hexbytes,
    random_chunks,
)


def _decode(frame: bytes) -> ClientCommand:
    return ClientCommand.from_packet(decode_packet(frame))


@given(client_commands)
def test_round_trip(command: ClientCommand) -> None:
    frame = command.to_packet().to_bytes()
    assert _decode(frame) == command
    assert _decode(frame).to_packet().to_bytes() == frame


@pytest.mark.parametrize("case", golden()["commands"], ids=lambda c: f"{c['command']} {c['arg']}")
def test_golden_frames(case: dict) -> None:
    command = ClientCommand(Command[case["command"]], case["arg"])
    assert command.to_packet().to_bytes() == hexbytes(case["frame"])
    assert _decode(hexbytes(case["frame"])) == command


def test_random_chunking(rng) -> None:
    sent = [vel(0.2), rvel(math.radians(10)), enable(True), ClientCommand(Command.SAY, b"\x05\x40"),
            sim_set_pose(1.0, -2.0, math.pi / 2), ClientCommand(Command.PULSE)] * 20
    stream = b"".join(c.to_packet().to_bytes() for c in sent)
    received, _ = deframe(random_chunks(stream, rng))
    assert [ClientCommand.from_packet(p) for p in received] == sent


@pytest.mark.parametrize("which", [0, 1])
def test_flipped_checksum(which: int, rng) -> None:
    frames = [c.to_packet().to_bytes() for c in (vel(0.1), vel(-0.1), enable(False))]
    frames[1] = flip_checksum_byte(frames[1], which)
    with pytest.raises(ChecksumError):
        decode_packet(frames[1])
    received, buffer = deframe(random_chunks(b"".join(frames), rng))
    assert isinstance(received[1], CorruptPacket) and buffer.bad_checksums == 1
    assert [ClientCommand.from_packet(received[k]) for k in (0, 2)] == [vel(0.1), enable(False)]


def test_helpers_convert_si_to_wire_units() -> None:
    assert vel(0.2) == ClientCommand(Command.VEL, 200)
    assert vel(-0.2).to_packet().to_bytes() == hexbytes("FA FB 06 0B 1B C8 00 D3 1B")
    assert rvel(math.radians(10)) == ClientCommand(Command.RVEL, 10)
    assert rotate(-math.radians(30)) == ClientCommand(Command.ROTATE, -30)
    assert move(-1.5) == ClientCommand(Command.MOVE, -1500)
    assert dhead(math.radians(-45)) == ClientCommand(Command.DHEAD, -45)
    assert dchead(math.radians(90)) == ClientCommand(Command.DCHEAD, 90)
    assert setv(1.2) == ClientCommand(Command.SETV, 1200)
    assert setrv(math.radians(300)) == ClientCommand(Command.SETRV, 300)
    assert setrvdir(math.radians(-50)) == ClientCommand(Command.SETRVDIR, -50)
    assert seta(0.3) == ClientCommand(Command.SETA, 300)
    assert seta(-0.3) == ClientCommand(Command.SETA, -300)
    assert setra(math.radians(-100)) == ClientCommand(Command.SETRA, -100)
    assert battest(12.8) == ClientCommand(Command.BATTEST, 128)
    assert enable(False) == ClientCommand(Command.ENABLE, 0)


def test_head_is_normalized_to_0_359() -> None:
    assert head(math.radians(-90)) == ClientCommand(Command.HEAD, 270)
    assert head(math.radians(360)) == ClientCommand(Command.HEAD, 0)
    assert head(math.radians(179.6)) == ClientCommand(Command.HEAD, 180)


def test_helpers_clamp_to_int16_and_reject_non_finite() -> None:
    assert vel(100.0) == ClientCommand(Command.VEL, 32767)
    assert vel(-100.0) == ClientCommand(Command.VEL, -32767)
    assert setv(-1.0) == ClientCommand(Command.SETV, 0)
    with pytest.raises(LocalProtocolError, match="vel: v_m_s: must be finite, got nan"):
        vel(math.nan)
    with pytest.raises(LocalProtocolError, match="rvel: omega_rad_s"):
        rvel(math.inf)
    with pytest.raises(LocalProtocolError, match="head: heading_rad: must be finite"):
        head(math.nan)


def test_vel2_packs_as_aria_and_unpacks_as_mobilesim() -> None:
    assert vel2(-0.1, 0.1, divisor_m_s=0.02) == ClientCommand(Command.VEL2, -1275)
    assert vel2(0.1, -0.1, divisor_m_s=0.02) == ClientCommand(Command.VEL2, 1531)
    assert vel2_wheels(-1275) == (-5, 5)
    assert vel2_wheels(1531) == (5, -5)
    assert vel2(9.0, -9.0, divisor_m_s=0.02) == ClientCommand(Command.VEL2, 0x7F80)
    with pytest.raises(LocalProtocolError, match="divisor_m_s must be > 0"):
        vel2(0.1, 0.1, divisor_m_s=0.0)


def test_si_value_for_the_robot_role() -> None:
    assert ClientCommand(Command.VEL, -200).si_value == pytest.approx(-0.2)
    assert ClientCommand(Command.RVEL, 90).si_value == pytest.approx(math.pi / 2)
    assert ClientCommand(Command.SETA, -300).si_value == pytest.approx(-0.3)
    assert ClientCommand(Command.BATTEST, 128).si_value == pytest.approx(12.8)
    for command, unit in WIRE_UNITS.items():
        assert ClientCommand(command, 7).si_value == pytest.approx(unit.si(7))
    with pytest.raises(ValueError, match="ENABLE carries no physical unit"):
        _ = enable(True).si_value
    with pytest.raises(RemoteProtocolError, match="VEL: expected an int argument"):
        _ = ClientCommand(Command.VEL, b"x").si_value


def test_aria_string_with_uncounted_nul_and_sim_set_pose() -> None:
    # ARIA's comStr appends a NUL that the length byte does not count (reference §2).
    packet = Packet(Command.SIM_MESSAGE, b"\x2b\x02hi\x00")
    assert ClientCommand.from_packet(packet).arg == b"hi"
    pose = ClientCommand.from_packet(sim_set_pose(1.0, -2.0, math.pi).to_packet())
    assert isinstance(pose.arg, DataArg)
    assert pose.arg.payload == hexbytes("E8 03 00 00 30 F8 FF FF B4 00 00 00")


def test_no_argument_and_p2os_open_without_argument() -> None:
    assert _decode(hexbytes("FA FB 03 01 00 01")) == ClientCommand(Command.OPEN)
    assert ClientCommand(Command.E_STOP).to_packet() == Packet(55)


def test_malformed_argument_decodes_as_data_never_fails() -> None:
    assert ClientCommand.from_packet(Packet(Command.VEL, b"\x3b\x01")).arg == DataArg(b"\x01", 0x3B)


def test_unknown_or_invalid_commands_are_refused() -> None:
    with pytest.raises(RemoteProtocolError, match="unknown command number 147"):
        ClientCommand.from_packet(Packet(147))
    with pytest.raises(LocalProtocolError, match="unknown command number 147"):
        ClientCommand(147)  # type: ignore[arg-type]
    with pytest.raises(LocalProtocolError, match="VEL: int argument 70000 is outside ±65535"):
        ClientCommand(Command.VEL, 70000)
    with pytest.raises(LocalProtocolError, match="string argument of 251 bytes exceeds 250"):
        ClientCommand(Command.SAY, bytes(251))
    with pytest.raises(LocalProtocolError, match="argument must be int, bytes, DataArg or None"):
        ClientCommand(Command.SAY, "text")  # type: ignore[arg-type]
