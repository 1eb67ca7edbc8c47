"""The emulated Pioneer against a hostile client: out-of-range arguments, fuzzed packets,
the BATTEST packet that used to end ``vmnav sim serve``; and a handler that fails."""

from __future__ import annotations

import contextlib
import logging
import socket

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.aria import Command, ConnState, encode_packet
from sim.pioneer import PioneerServer, StreamLink, TcpListener
from sim.pioneer.links import READ_LIMIT
from tests.sim.pioneer.rig import OPEN_STATES, Rig
from tests.sim.pioneer.test_server import (
    PATIENCE_S,
    connect,
    make_emulator,
    pump,
    serving,
    tcp_client,
)

BATTEST_25_6_V = bytes.fromhex("fafb06fa3b0001fa3c")
"""BATTEST 256 decivolts, one more than the SIP's u8 BATTERY holds (issue 15)."""


def test_battest_above_25_5_v_over_tcp_keeps_the_sips_coming() -> None:
    listener = TcpListener("127.0.0.1", 0)
    server = PioneerServer(make_emulator(), listeners=[listener])
    with serving(server):
        host = tcp_client(listener.port)
        connect(host)
        host.link.write(BATTEST_25_6_V)
        start = len(host.sips)
        assert pump(host, PATIENCE_S, lambda: len(host.sips) - start >= 3)
        sip = host.sips[-1][1]
        assert sip.battery_v == pytest.approx(25.5)  # u8 decivolts, clamped
        assert sip.real_battery_v == pytest.approx(25.6)  # u16 BATTERYX10 carries it all
        host.link.close()
    assert server.emulator.stats.handler_errors == 0


def drive_at(rig: Rig, arg: int) -> float:
    """Send VEL ``arg`` (mm/s) to a connected, enabled robot; its forward speed after 1 s, m/s."""
    rig.command(Command.VEL, arg)
    rig.run_for(1.0)
    return rig.sim.body.odom_velocity[0]


class TestArguments:
    def test_an_int_outside_a_c_short_is_refused(self) -> None:
        rig = Rig()
        rig.connect()
        rig.command(Command.ENABLE, 1)
        assert drive_at(rig, 40000) == 0.0
        assert drive_at(rig, -40000) == 0.0
        assert rig.emulator.stats.refused_commands == 2
        assert drive_at(rig, 32767) > 0.2  # in range: obeyed, clamped to the SETV maximum

    def test_enable_and_sonar_take_only_0_or_1(self) -> None:
        rig = Rig()
        rig.connect()
        rig.command(Command.ENABLE, 2)
        rig.command(Command.SONAR, 7)
        rig.run_for(0.3)
        assert not rig.emulator.motors_enabled
        assert rig.emulator.stats.refused_commands == 2

    def test_e_stop_with_any_argument_stops(self) -> None:
        rig = Rig()
        rig.connect()
        rig.command(Command.ENABLE, 1)
        assert drive_at(rig, 300) > 0.25
        rig.command(Command.E_STOP, 65535)
        rig.run_for(0.5)
        assert not rig.emulator.motors_enabled
        assert rig.emulator.stats.refused_commands == 0


def test_an_exception_in_a_handler_is_counted_logged_once_and_the_sips_go_on(
        caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch) -> None:
    rig = Rig()
    rig.connect()

    def broken(voltage_v: float) -> None:
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr(rig.emulator, "_set_battest", broken)
    rig.emulator._handlers = rig.emulator._command_handlers()  # rebuilt with the broken one
    with caplog.at_level(logging.WARNING, logger="sim.pioneer.emulator"):
        for _ in range(3):
            rig.command(Command.BATTEST, 120)
            rig.run_for(0.2)
    sips = len(rig.host.sips)
    rig.run_for(0.5)
    assert len(rig.host.sips) >= sips + 4
    assert rig.emulator.stats.handler_errors == 3
    logged = [r.getMessage() for r in caplog.records]
    assert len(logged) == 1 and "command BATTEST: ZeroDivisionError: a bug" in logged[0]



def test_a_session_that_fails_is_counted_and_tried_again_at_the_next_tick(
        monkeypatch: pytest.MonkeyPatch) -> None:
    rig = Rig()
    rig.connect()
    session = rig.emulator._session
    healthy = session.next_event
    failures = iter([RuntimeError("a bug in the session")])

    def failing_once() -> object:
        for error in failures:
            raise error
        return healthy()

    monkeypatch.setattr(session, "next_event", failing_once)
    sips = len(rig.host.sips)
    rig.run_for(0.5)
    assert rig.emulator.stats.handler_errors == 1
    assert len(rig.host.sips) >= sips + 4


ARGS = st.one_of(
    st.none(),
    st.integers(-0xFFFF, 0xFFFF).map(
        lambda v: bytes((0x3B if v >= 0 else 0x1B,)) + abs(v).to_bytes(2, "little")),
    st.binary(max_size=24),
)
PACKETS = st.tuples(
    st.one_of(st.sampled_from([int(c) for c in Command]), st.integers(0, 255)),
    ARGS,
).map(lambda p: encode_packet(p[0], b"" if p[1] is None else p[1]))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(PACKETS, min_size=1, max_size=40))
def test_fuzzed_packets_never_raise_and_a_new_client_is_served(packets: list[bytes]) -> None:
    rig = Rig()
    rig.connect()
    rig.command(Command.ENABLE, 1)
    for packet in packets:
        rig.host_end.write(packet)
        rig.server.pump()  # no simulation step: many packets per SIP cycle
    rig.run_for(0.3)
    assert rig.emulator.stats.handler_errors == 0  # nothing raised, nothing was caught
    rig.new_host()  # whatever state the fuzz left, a client connects and gets SIPs
    rig.run_for(2.5)  # past the watchdog, as a client that reconnects after a while
    rig.connect(timeout_s=3.0)
    assert rig.host.session.state in OPEN_STATES
    assert rig.emulator.state in (*OPEN_STATES, ConnState.CONNECTED)


def test_a_link_returns_at_most_read_limit_bytes_per_read() -> None:
    ours, theirs = socket.socketpair()
    link = StreamLink.from_socket(ours, "test")
    theirs.setblocking(False)
    sent = 0
    with contextlib.suppress(BlockingIOError):
        while sent < 3 * READ_LIMIT:
            sent += theirs.send(b"\xfa" * 4096)
    try:
        first = link.read_available()
        assert len(first) == READ_LIMIT < sent
        assert len(first) + len(link.read_available()) <= sent
    finally:
        link.close()
        theirs.close()
