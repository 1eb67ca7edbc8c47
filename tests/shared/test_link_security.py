"""The secure default of vmnav robot and vmnav ground: no unsigned link open to the network
unless asked."""

from __future__ import annotations

import pytest

from shared.errors import InputError, TransportError
from shared.link_address import parse_link_address
from shared.link_security import check_link, default_url, reaches_network


def test_the_default_is_loopback_unless_signed() -> None:
    assert default_url(signed=False) == "udpin:127.0.0.1:14550"
    assert default_url(signed=True) == "udpin:0.0.0.0:14550"
    url, line, insecure = check_link(None, "--mavlink", signed=False, insecure=False)
    assert url == "udpin:127.0.0.1:14550" and not insecure
    assert line is not None and "for this machine only" in line and "keygen" in line
    assert check_link(None, "--mavlink", signed=True, insecure=False) == (
        "udpin:0.0.0.0:14550", None, False)


@pytest.mark.parametrize(("url", "reaches"), [
    ("udpin:0.0.0.0:14550", True),
    ("udpin:127.0.0.1:14550", False),
    ("udpin:localhost:0", False),
    ("udpout:127.0.0.1:14550", False),
    ("udpout:192.0.2.7:14550", True),  # bound to every interface to reach its peer
    ("tcpin:0.0.0.0:5760", True),
    ("tcpin:127.0.0.1:5760", False),
    ("tcp:127.0.0.1:5760", False),
    ("tcp:192.0.2.7:5760", True),  # the link crosses the network
    ("serial:/dev/ttyUSB0:57600", False),  # a telemetry radio is a wire
    ("pty:/tmp/vmnav-radio", False),
])
def test_reaches_network(url: str, reaches: bool) -> None:
    assert reaches_network(parse_link_address(url, "--mavlink")) is reaches


@pytest.mark.parametrize("url", ["udpin:127.0.0.1:14550", "udpin:localhost:0",
                                 "udpout:127.0.0.1:14550", "udp:127.0.0.2:9",
                                 "tcpin:127.0.0.1:5760", "tcp:127.0.0.1:5760",
                                 "serial:/dev/ttyUSB0:57600", "pty:/tmp/vmnav-radio"])
def test_unsigned_links_on_loopback_are_fine(url: str) -> None:
    assert check_link(url, "--mavlink", signed=False, insecure=False) == (url, None, False)


@pytest.mark.parametrize("url", ["udpin:0.0.0.0:14550", "udpout:192.0.2.7:14550",
                                 "tcpin:0.0.0.0:5760", "tcp:192.0.2.7:5760"])
def test_an_unsigned_link_open_to_the_network_needs_insecure(url: str) -> None:
    with pytest.raises(InputError, match=r"unsigned link open to the network .* keygen .* "
                                         r"or add --insecure") as e:
        check_link(url, "--mavlink", signed=False, insecure=False)
    assert e.value.where == f"--mavlink {url}" and "\n" not in str(e.value)
    url_out, line, insecure = check_link(url, "--mavlink", signed=False, insecure=True)
    assert url_out == url and insecure and line is not None and line.startswith("WARNING: ")
    assert check_link(url, "--mavlink", signed=True, insecure=False) == (url, None, False)


def test_a_bad_address_is_one_line_naming_the_option() -> None:
    with pytest.raises(InputError) as e:
        check_link("tcp:5760", "--connect", signed=False, insecure=False)
    assert str(e.value) == "--connect: 'tcp:5760': expected tcp:HOST:PORT (a host and a port)"


def test_an_unknown_host_is_a_transport_error() -> None:
    with pytest.raises(TransportError, match="cannot resolve host"):
        check_link("tcp:vmnav.invalid:5760", "--connect", signed=False, insecure=False)
