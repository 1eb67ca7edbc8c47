"""UdpLink: real datagrams on 127.0.0.1 ephemeral ports, connection strings, errors."""

from __future__ import annotations

import os
import select
import socket
from collections.abc import Iterator

import pytest

from shared.byte_link import LinkClosedError
from shared.errors import TransportError
from shared.mavlink.dialect import make_codec, mavlink
from shared.udp_link import UdpLink, UdpMode, parse_udp_url


@pytest.fixture
def pair() -> Iterator[tuple[UdpLink, UdpLink]]:
    """A listening link and a sending link aimed at it."""
    server = UdpLink.open("udpin:127.0.0.1:0")
    client = UdpLink.open(f"udpout:127.0.0.1:{server.local_port}")
    yield server, client
    client.close()
    server.close()


def wait_receive(link: UdpLink, count: int = 1) -> list[tuple[bytes, tuple[str, int]]]:
    """Receive until ``count`` datagrams arrived (loopback delivers at once; 1 s cap)."""
    got: list[tuple[bytes, tuple[str, int]]] = []
    while len(got) < count:
        assert select.select([link], [], [], 1.0)[0], f"only {len(got)} of {count} datagrams"
        got += link.receive()
    return got


class TestConnectionStrings:
    @pytest.mark.parametrize(("url", "expected"), [
        ("udpin:0.0.0.0:14550", (UdpMode.IN, "0.0.0.0", 14550)),
        ("udp:127.0.0.1:0", (UdpMode.IN, "127.0.0.1", 0)),
        ("udpout:localhost:14550", (UdpMode.OUT, "localhost", 14550)),
    ])
    def test_forms(self, url: str, expected: tuple[UdpMode, str, int]) -> None:
        assert parse_udp_url(url) == expected

    @pytest.mark.parametrize(("url", "problem"), [
        ("tcp:127.0.0.1:5760", "tcp:HOST:PORT cannot be used here"),
        ("udpin:14550", "expected udpin:HOST:PORT (a host and a port)"),
        ("udpin::14550", "expected udpin:HOST:PORT (a host and a port)"),
        ("udpin:127.0.0.1:port", "port 'port' is not an integer in 0..65535"),
        ("udpin:127.0.0.1:65536", "not an integer in 0..65535"),
        ("udpout:127.0.0.1:0", "port '0' is not an integer in 1..65535"),
        ("udpin:127.0.0.1:-5", "not an integer"),
    ])
    def test_bad_strings_are_one_line_errors(self, url: str, problem: str) -> None:
        with pytest.raises(TransportError) as info:
            UdpLink.open(url)
        message = str(info.value)
        assert message.startswith(f"{url}: ") and problem in message and "\n" not in message

    def test_a_port_in_use_is_a_transport_error(self) -> None:
        with UdpLink.open("udpin:127.0.0.1:0") as first:
            url = f"udpin:127.0.0.1:{first.local_port}"
            with pytest.raises(TransportError, match=r"cannot bind 127\.0\.0\.1:\d+: "
                                                     r"Address already in use"):
                UdpLink.open(url)


class TestReach:
    def test_udpout_to_loopback_binds_loopback(self, pair: tuple[UdpLink, UdpLink]) -> None:
        server, client = pair
        with socket.socket(fileno=os.dup(client.fileno())) as bound:
            assert bound.getsockname() == ("127.0.0.1", client.local_port)
        assert client.send(b"ping")
        assert [data for data, _ in wait_receive(server)] == [b"ping"]


class TestDatagrams:
    def test_port_0_picks_a_free_port(self, pair: tuple[UdpLink, UdpLink]) -> None:
        server, client = pair
        assert server.local_port > 0 and client.local_port > 0
        assert server.local_port != client.local_port
        assert client.peer == ("127.0.0.1", server.local_port)

    def test_mavlink_packets_travel_both_ways(self, pair: tuple[UdpLink, UdpLink]) -> None:
        server, client = pair
        ground, vehicle = make_codec(255, 190), make_codec(1, 1)
        assert server.send(b"early") is False  # udpin: no peer before the first datagram
        packet = ground.pack(mavlink.MAVLink_param_request_list_message(1, 1))
        assert client.send(packet)
        [(data, sender)] = wait_receive(server)
        assert sender == ("127.0.0.1", client.local_port) == server.peer
        assert [m.get_type() for m in vehicle.parse(data)] == ["PARAM_REQUEST_LIST"]
        reply = vehicle.pack(mavlink.MAVLink_param_value_message(b"X", 1.0, 9, 1, 0))
        assert server.send(reply)
        [(data, _)] = wait_receive(client)
        assert ground.parse(data)[0].param_id == "X"

    def test_udpin_replies_to_the_last_sender(self, pair: tuple[UdpLink, UdpLink]) -> None:
        server, client = pair
        with UdpLink.open(f"udpout:127.0.0.1:{server.local_port}") as other:
            client.send(b"a")
            other.send(b"b")
            assert [d for d, _ in wait_receive(server, 2)] == [b"a", b"b"]
            assert server.peer == ("127.0.0.1", other.local_port)
            server.send(b"to other")
            assert wait_receive(other)[0][0] == b"to other"
            assert client.receive() == []

    def test_receive_never_blocks(self, pair: tuple[UdpLink, UdpLink]) -> None:
        assert pair[0].receive() == [] and pair[1].receive() == []

    def test_several_datagrams_keep_their_boundaries(self, pair: tuple[UdpLink, UdpLink]) -> None:
        server, client = pair
        for i in range(5):
            client.send(bytes([i]) * (i + 1))
        assert [d for d, _ in wait_receive(server, 5)] == [bytes([i]) * (i + 1) for i in range(5)]

    def test_a_refused_send_is_counted_not_raised(self) -> None:
        with UdpLink.open("udpout:127.0.0.1:9") as link:
            assert link.send(b"x" * 70_000) is False  # larger than any datagram
            assert link.send_errors == 1

    def test_closed_link_raises_link_closed(self, pair: tuple[UdpLink, UdpLink]) -> None:
        client = pair[1]
        client.close()
        client.close()  # idempotent
        with pytest.raises(LinkClosedError, match="closed"):
            client.send(b"x")
        with pytest.raises(LinkClosedError):
            client.receive()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.bind(("127.0.0.1", client.local_port))  # the port was released


def test_drain_keeps_the_trusted_and_a_budget_of_others(pair: tuple[UdpLink, UdpLink]) -> None:
    server, friend = pair
    with UdpLink.open(f"udpout:127.0.0.1:{server.local_port}") as stranger:
        for i in range(50):
            stranger.send(b"s%d" % i)
        friend.send(b"hello")
        assert select.select([server], [], [], 1.0)[0]
        friend_address = ("127.0.0.1", friend.local_port)
        drained = server.drain({friend_address}, budget=10)
    assert drained.trusted == [(b"hello", friend_address)]
    assert [data for data, _ in drained.others] == [b"s%d" % i for i in range(10)]
    assert drained.shed == 40 and server.peer is None  # the owner picks whom to answer
    assert server.receive_buffer_bytes >= 200_000
