"""Link addresses (shared/link_address.py): every form, the old ones, and one-line errors."""

from __future__ import annotations

import pytest

from shared.errors import InputError
from shared.link_address import (
    ARIA_SCHEMES,
    MAVLINK_SCHEMES,
    LinkAddress,
    Scheme,
    parse_link_address,
)


class TestForms:
    @pytest.mark.parametrize(("text", "expected"), [
        ("udpin:0.0.0.0:14550", LinkAddress(Scheme.UDPIN, "udpin:0.0.0.0:14550", "0.0.0.0", 14550)),
        ("udpin:127.0.0.1:0", LinkAddress(Scheme.UDPIN, "udpin:127.0.0.1:0", "127.0.0.1", 0)),
        ("udpout:gcs.local:14550", LinkAddress(Scheme.UDPOUT, "udpout:gcs.local:14550",
                                               "gcs.local", 14550)),
        ("tcp:127.0.0.1:5760", LinkAddress(Scheme.TCP, "tcp:127.0.0.1:5760", "127.0.0.1", 5760)),
        ("tcpin:0.0.0.0:5760", LinkAddress(Scheme.TCPIN, "tcpin:0.0.0.0:5760", "0.0.0.0", 5760)),
        ("tcpin:127.0.0.1:0", LinkAddress(Scheme.TCPIN, "tcpin:127.0.0.1:0", "127.0.0.1", 0)),
        ("serial:/dev/ttyUSB0:57600", LinkAddress(Scheme.SERIAL, "serial:/dev/ttyUSB0:57600",
                                                  device="/dev/ttyUSB0", baud=57600)),
        ("serial:/dev/ttyUSB0", LinkAddress(Scheme.SERIAL, "serial:/dev/ttyUSB0",
                                            device="/dev/ttyUSB0")),
        ("serial:/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0",
         LinkAddress(Scheme.SERIAL, "serial:/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0",
                     device="/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0")),
        ("pty:/tmp/vmnav-pioneer", LinkAddress(Scheme.PTY, "pty:/tmp/vmnav-pioneer",
                                               device="/tmp/vmnav-pioneer")),
    ])
    def test_each_form(self, text: str, expected: LinkAddress) -> None:
        address = parse_link_address(text, "--mavlink")
        assert address == expected
        assert str(address) == text

    @pytest.mark.parametrize(("text", "canonical"), [
        ("udp:127.0.0.1:14550", "udpin:127.0.0.1:14550"),  # pymavlink's alias
        ("/dev/ttyUSB0", "serial:/dev/ttyUSB0"),  # a device path alone
    ])
    def test_other_tools_spellings(self, text: str, canonical: str) -> None:
        assert str(parse_link_address(text, "--connect")) == canonical

    @pytest.mark.parametrize(("text", "canonical"), [
        ("socket://127.0.0.1:8101", "tcp:127.0.0.1:8101"),
        ("loop://", "loop://"),
        ("/dev/pts/3", "serial:/dev/pts/3"),
    ])
    def test_pyserial_urls_where_they_were_taken(self, text: str, canonical: str) -> None:
        address = parse_link_address(text, "--aria", ARIA_SCHEMES, pyserial_urls=True)
        assert str(address) == canonical

    def test_properties(self) -> None:
        def parse(text: str) -> LinkAddress:
            return parse_link_address(text, "--x", MAVLINK_SCHEMES, pyserial_urls=True)
        assert [parse(t).stream for t in ("udpin:h:1", "udpout:h:1", "tcp:h:1", "pty:/p")] == [
            False, False, True, True]
        assert [parse(t).listening for t in ("udpin:h:1", "tcpin:h:1", "tcp:h:1")] == [
            True, True, False]
        assert parse("serial:/dev/x").serial and parse("pty:/p").serial
        assert parse("loop://").pyserial_url and not parse("serial:/dev/x").pyserial_url


class TestErrors:
    @pytest.mark.parametrize(("text", "problem"), [
        ("", "not a link address (expected udpin:HOST:PORT, udpout:HOST:PORT, tcp:HOST:PORT, "
             "tcpin:HOST:PORT, serial:DEVICE[:BAUD], pty:PATH)"),
        ("14550", "not a link address"),
        ("http:127.0.0.1:80", "not a link address"),
        ("tcp:5760", "expected tcp:HOST:PORT (a host and a port)"),
        ("udpin::14550", "expected udpin:HOST:PORT (a host and a port)"),
        ("tcp:my host:1", "host 'my host' has spaces"),
        ("tcp:127.0.0.1:port", "port 'port' is not an integer in 1..65535"),
        ("tcp:127.0.0.1:0", "port '0' is not an integer in 1..65535"),
        ("udpout:127.0.0.1:0", "port '0' is not an integer in 1..65535"),
        ("tcpin:127.0.0.1:65536", "port '65536' is not an integer in 0..65535"),
        ("udpin:127.0.0.1:-5", "port '-5' is not an integer in 0..65535"),
        ("serial:", "no device"),
        ("serial::57600", "no device"),
        ("serial:/dev/ttyUSB0:0", "baud rate 0 is not in 50..4000000"),
        ("serial:/dev/ttyUSB0:9999999", "baud rate 9999999 is not in 50..4000000"),
        ("pty:", "no pty path (pty:PATH)"),
        ("socket://127.0.0.1:8101", "a URL is not a link address here"),
    ])
    def test_one_line_naming_the_option_and_value(self, text: str, problem: str) -> None:
        with pytest.raises(InputError) as info:
            parse_link_address(text, "--connect")
        assert info.value.where == "--connect"
        assert str(info.value) == f"--connect: {text!r}: {problem}" or problem in str(info.value)
        assert str(info.value).startswith(f"--connect: {text!r}: ")
        assert "\n" not in str(info.value)

    @pytest.mark.parametrize("text", ["udpin:127.0.0.1:8101", "udpout:127.0.0.1:8101",
                                      "tcpin:0.0.0.0:8101"])
    def test_aria_takes_no_udp_or_listener(self, text: str) -> None:
        with pytest.raises(InputError, match=r"cannot be used here \(expected tcp:HOST:PORT, "
                                             r"serial:DEVICE\[:BAUD\], pty:PATH\)"):
            parse_link_address(text, "--aria", ARIA_SCHEMES, pyserial_urls=True)
