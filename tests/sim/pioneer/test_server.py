"""The server: links, one client at a time, and real transports (a pty, TCP) in real time."""

from __future__ import annotations

import os
import socket
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from shared.aria import Command, ConnState
from shared.byte_link import LinkClosedError, pipe_pair
from shared.clock import WallClock
from shared.errors import TransportError
from sim.config import EmulatorConfig, SimConfig
from sim.pioneer import EmulatedPioneer, PioneerServer, PtyLink, StreamLink, TcpListener
from sim.sim_clock import SimClock
from sim.simulation import Simulation
from tests.sim.pioneer.aria_host import AriaHost
from tests.sim.pioneer.rig import OPEN_STATES, Rig
from tests.sim.rooms import box_room

CLOCK = WallClock()
POLL_NS = 5_000_000


def make_emulator() -> EmulatedPioneer:
    sim = Simulation(box_room((12.0, 6.0)), SimConfig(seed=2))
    return EmulatedPioneer(sim, EmulatorConfig(), np.random.default_rng(2))


@contextmanager
def serving(server: PioneerServer) -> Iterator[PioneerServer]:
    """``server`` running in real time on a thread; stopped, joined and closed after."""
    thread = threading.Thread(target=server.run, args=(CLOCK,), name="pioneer-server")
    thread.start()
    try:
        yield server
    finally:
        server.stop()
        thread.join(timeout=5.0)
        server.close()
        assert not thread.is_alive()


def pump(host: AriaHost, seconds: float, until: Callable[[], bool] | None = None) -> bool:
    """Poll ``host`` in real time for ``seconds`` or until ``until()``; returns whether it held."""
    end = CLOCK.now_ns() + round(seconds * 1e9)
    while CLOCK.now_ns() < end:
        host.poll(CLOCK.now_ns())
        if until is not None and until():
            return True
        CLOCK.sleep_until_ns(CLOCK.now_ns() + POLL_NS)
    return until is None


#: Upper bound on a wait for the emulated robot, s: reached only when it hangs (it serves
#: in real time, and a loaded machine may run it late, never this late).
PATIENCE_S = 20.0


def connect(host: AriaHost) -> None:
    """Handshake and OPEN, until the first SIP."""
    host.connect(CLOCK.now_ns())
    assert pump(host, PATIENCE_S, lambda: bool(host.sips)), host.events
    assert host.session.identity is not None and host.session.identity.subclass == "p3at-sh"


def connect_and_drive(host: AriaHost) -> None:
    """Handshake, OPEN, ENABLE, VEL 200 mm/s for 6 SIPs (0.6 s of the robot's time); the
    SIPs show the motion."""
    connect(host)
    host.command(Command.ENABLE, 1, CLOCK.now_ns())
    host.command(Command.VEL, 200, CLOCK.now_ns())
    start = len(host.sips)
    assert pump(host, PATIENCE_S, lambda: len(host.sips) - start >= 6)
    assert host.sips[-1][1].motors_enabled and host.sips[-1][1].x_counts > 20
    assert host.configs and host.configs[0].trans_vel_max_m_s > 0


def tcp_client(port: int) -> AriaHost:
    sock = socket.create_connection(("127.0.0.1", port), timeout=2.0)
    return AriaHost(StreamLink.from_socket(sock, "test client"))


def closed_by_server(link: StreamLink, seconds: float = 2.0) -> bool:
    end = CLOCK.now_ns() + round(seconds * 1e9)
    while CLOCK.now_ns() < end:
        try:
            link.read_available()
        except LinkClosedError:
            return True
        CLOCK.sleep_until_ns(CLOCK.now_ns() + POLL_NS)
    return False


class TestOneClientAtATime:
    def test_a_client_on_another_link_takes_over_and_the_robot_stops(self) -> None:
        rig = Rig()
        other_robot_end, other_host_end = pipe_pair()
        rig.server.links.append(other_robot_end)
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 300)
        rig.run_for(1.5)
        first = rig.host
        rig.host = AriaHost(other_host_end)
        rig.connect()
        assert rig.emulator.stats.sessions == 2
        rig.run_for(1.0)
        assert not rig.host.sips[-1][1].motors_enabled
        assert rig.host.sips[-1][1].left_vel_m_s == 0
        sips_of_first = len(first.sips)
        first.poll(rig.now_ns)
        assert len(first.sips) == sips_of_first  # replies go to the active link only

    def test_a_closed_link_is_dropped_and_the_robot_stops(self) -> None:
        rig = Rig()
        rig.connect()
        rig.command(Command.ENABLE, 1)
        rig.command(Command.VEL, 300)
        rig.run_for(1.0)
        rig.host_end.close()
        for _ in range(100):
            rig.server.tick()
        assert rig.server.links == [] and rig.emulator.stats.sessions == 2
        assert rig.sim.body.velocity_base[0] == pytest.approx(0.0, abs=1e-3)


    def test_pumped_by_a_step_hook_under_a_sim_clock(self) -> None:
        emulator = make_emulator()
        robot_end, host_end = pipe_pair()
        server = PioneerServer(emulator, links=[robot_end])
        emulator.simulation.add_step_hook(lambda now_ns, dt_ns: server.pump())
        clock, host = SimClock(emulator.simulation), AriaHost(host_end)
        host.connect(clock.now_ns())
        for _ in range(50):  # a client's loop: poll, then sleep (the clock steps the world)
            host.poll(clock.now_ns())
            clock.sleep_until_ns(clock.now_ns() + 20_000_000)
        assert host.session.state in OPEN_STATES and len(host.sips) == 10


def driving_rig() -> Rig:
    """A lock-step rig connected, motors on, VEL 300 mm/s for 1 s."""
    rig = Rig()
    rig.connect()
    rig.command(Command.ENABLE, 1)
    rig.command(Command.VEL, 300)
    rig.run_for(1.0)
    assert rig.sim.body.velocity_base[0] > 0.25
    return rig


class TestFaults:
    def test_a_cut_loses_every_byte_and_the_watchdog_stops_the_robot(self) -> None:
        rig = driving_rig()
        rig.server.cut(3_000_000_000)
        sips = len(rig.host.sips)
        rig.run_for(1.4)  # the client's last packet came <= 0.5 s before the cut
        assert len(rig.host.sips) == sips and rig.sim.body.velocity_base[0] > 0.25
        rig.run_for(1.1)  # the watchdog trips 2 s after it; 0.3 m/s brakes to 0 in 0.3 s
        assert rig.emulator.stats.watchdog_trips == 1
        assert rig.sim.body.velocity_base[0] == pytest.approx(0.0, abs=1e-3)
        rig.run_for(2.0)  # the cable is back at 3 s: the session and the motion resume
        assert len(rig.host.sips) > sips and rig.host.session.state in OPEN_STATES
        assert rig.sim.body.velocity_base[0] > 0.25 and rig.emulator.stats.sessions == 1

    def test_a_zero_cut_mends_the_cable(self) -> None:
        rig = driving_rig()
        rig.server.cut(10_000_000_000)
        rig.run_for(0.5)
        sips = len(rig.host.sips)
        rig.server.cut(0)
        rig.run_for(0.5)
        assert len(rig.host.sips) > sips

    def test_injected_bytes_reach_the_client_and_the_sips_go_on(self) -> None:
        rig = driving_rig()
        noise = bytes(np.random.default_rng(5).integers(0, 256, 500, dtype=np.uint8))
        rig.server.inject(noise)
        sips = len(rig.host.sips)
        rig.run_for(1.0)
        session = rig.host.session
        assert session.skipped_bytes + session.bad_checksums > 0
        assert len(rig.host.sips) >= sips + 8 and session.state in OPEN_STATES


class TestTcp:
    def test_drive_then_close_closes_the_socket(self) -> None:
        listener = TcpListener("127.0.0.1", 0)
        with serving(PioneerServer(make_emulator(), listeners=[listener])):
            host = tcp_client(listener.port)
            connect_and_drive(host)
            host.command(Command.CLOSE, 1, CLOCK.now_ns())
            assert closed_by_server(host.link)  # type: ignore[arg-type]
            host.link.close()
            again = tcp_client(listener.port)  # the next client is welcome
            connect(again)
            again.link.close()

    def test_a_second_client_is_refused_while_one_is_connected(self) -> None:
        listener = TcpListener("127.0.0.1", 0)
        server = PioneerServer(make_emulator(), listeners=[listener])
        with serving(server):
            first = tcp_client(listener.port)
            connect_and_drive(first)
            second = tcp_client(listener.port)
            assert closed_by_server(second.link)  # type: ignore[arg-type]
            count = len(first.sips)
            pump(first, 0.3)
            assert len(first.sips) > count and first.session.state in OPEN_STATES
            first.link.close()
            second.link.close()
        assert server.refused_clients == 1

    def test_a_client_that_vanishes_mid_motion_stops_the_robot(self) -> None:
        listener = TcpListener("127.0.0.1", 0)
        server = PioneerServer(make_emulator(), listeners=[listener])
        with serving(server):
            first = tcp_client(listener.port)
            connect_and_drive(first)
            first.link.close()  # no CLOSE: the process died
            second = tcp_client(listener.port)
            connect(second)
            assert second.stale_closes == 0  # a fresh session, not ARIA's stale-link recovery
            pump(second, 0.6)  # a robot at 0.2 m/s brakes to a stop in 0.33 s
            sip = second.sips[-1][1]
            assert not sip.motors_enabled and sip.left_vel_m_s == sip.right_vel_m_s == 0
            second.link.close()
        assert server.emulator.stats.sessions >= 2

    def test_port_in_use_is_a_transport_error(self) -> None:
        listener = TcpListener("127.0.0.1", 0)
        try:
            with pytest.raises(TransportError, match=f"tcp:127.0.0.1:{listener.port}: cannot"):
                TcpListener("127.0.0.1", listener.port)
        finally:
            listener.close()


class TestPty:
    def test_a_client_on_the_pty_connects_and_drives(self, tmp_path: Path) -> None:
        symlink = tmp_path / "pioneer"
        pty = PtyLink(symlink)
        assert os.path.realpath(symlink) == pty.path
        server = PioneerServer(make_emulator(), links=[pty])
        with serving(server):
            fd = os.open(symlink, os.O_RDWR | os.O_NOCTTY)
            host = AriaHost(StreamLink.from_fd(fd, pty.path))
            host.link.write(b"WMS2\r")
            connect_and_drive(host)
            host.command(Command.CLOSE, 1, CLOCK.now_ns())
            pump(host, 0.3)
            assert server.emulator.state is ConnState.CLOSED  # a pty stays open after CLOSE
            host.link.close()
        assert not symlink.exists()

    def test_an_existing_file_is_not_replaced_by_the_symlink(self, tmp_path: Path) -> None:
        path = tmp_path / "taken"
        path.write_text("mine")
        with pytest.raises(TransportError, match="taken"):
            PtyLink(path)
        assert path.read_text() == "mine"
