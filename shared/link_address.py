"""Link addresses: one syntax for every link of every command, parsed by pure functions.

=========================  ==================================================================
``udpin:HOST:PORT``        UDP, listening on HOST:PORT (``0.0.0.0``: every interface); answers
                           whoever sent last (MAVLink only)
``udpout:HOST:PORT``       UDP, sending to HOST:PORT (MAVLink only)
``tcp:HOST:PORT``          TCP, connecting to HOST:PORT
``tcpin:HOST:PORT``        TCP, listening on HOST:PORT, one peer at a time (MAVLink only)
``serial:DEVICE[:BAUD]``   a serial device at BAUD baud (a SiK telemetry radio, the Pioneer's
                           port); without BAUD, the command's default
``pty:PATH``               a pseudo-terminal, e.g. the one ``vmnav sim serve --aria pty:PATH``
                           made: a serial device whose rate does not matter
=========================  ==================================================================

Also accepted, as other tools spell them: ``udp:HOST:PORT`` (pymavlink's ``udpin``), a
device path alone (``/dev/ttyUSB0``: ``serial:/dev/ttyUSB0``) and, where pyserial URLs
were taken (``--aria``), ``socket://HOST:PORT`` (``tcp:HOST:PORT``) and any other
pyserial URL (``loop://``, ``rfc2217://HOST:PORT``) as it is.

Rules:

1. Parsing is pure: no name lookup, no file system. A host that does not resolve, a
   device that is missing, a port in use are found when the link is opened, by the
   adapter (``shared.udp_link``, ``shared.stream_link``, ``shared.serial_port``).
2. A listening address may use port 0 (any free port); a sending one may not.
3. Every bad address raises :class:`~shared.errors.InputError` naming the option and
   the value, in one line. Which forms an option takes is the ``allowed`` set its
   command passes (:data:`MAVLINK_SCHEMES`, :data:`ARIA_SCHEMES`).
4. ``serial:DEVICE:BAUD`` takes the text after the last colon as the rate when it is all
   digits; a device whose own name ends in ``:digits`` needs the rate written out.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Collection
from dataclasses import dataclass

from shared.errors import InputError

__all__ = ["ARIA_SCHEMES", "MAVLINK_SCHEMES", "LinkAddress", "Scheme", "parse_link_address"]

#: Slowest and fastest serial rates accepted, baud (POSIX B50 .. Linux B4000000).
MIN_BAUD, MAX_BAUD = 50, 4_000_000


class Scheme(enum.Enum):
    """The kind of link an address names (module table)."""

    UDPIN = "udpin"  #: UDP, listening on HOST:PORT
    UDPOUT = "udpout"  #: UDP, sending to HOST:PORT
    TCP = "tcp"  #: TCP client of HOST:PORT
    TCPIN = "tcpin"  #: TCP server on HOST:PORT, one peer at a time
    SERIAL = "serial"  #: serial DEVICE (or a pyserial URL) at ``baud``
    PTY = "pty"  #: a pseudo-terminal's PATH


#: How each scheme is written, for messages and help.
FORMS = {
    Scheme.UDPIN: "udpin:HOST:PORT", Scheme.UDPOUT: "udpout:HOST:PORT",
    Scheme.TCP: "tcp:HOST:PORT", Scheme.TCPIN: "tcpin:HOST:PORT",
    Scheme.SERIAL: "serial:DEVICE[:BAUD]", Scheme.PTY: "pty:PATH",
}
#: What ``--mavlink`` and ``--connect`` take.
MAVLINK_SCHEMES = frozenset(Scheme)
#: What ``--aria`` takes (the Pioneer is a serial device, or a TCP server such as
#: ``vmnav sim serve``, MobileSim or a serial-to-TCP bridge).
ARIA_SCHEMES = frozenset((Scheme.TCP, Scheme.SERIAL, Scheme.PTY))
_LISTENING = (Scheme.UDPIN, Scheme.TCPIN)
#: Makes the error for a problem with the address being parsed.
_Bad = Callable[[str], InputError]


@dataclass(frozen=True, slots=True)
class LinkAddress:
    """A parsed address (module table).

    Attributes:
        scheme: the kind of link.
        text: the address as given, for messages.
        host: the IPv4 address or host name (UDP, TCP); "" otherwise.
        port: the port (UDP, TCP; 0 for any free one when listening); 0 otherwise.
        device: the device path, pty path or pyserial URL (serial, pty); "" otherwise.
        baud: the serial rate given, baud; None when not given (or not serial).
    """

    scheme: Scheme
    text: str
    host: str = ""
    port: int = 0
    device: str = ""
    baud: int | None = None

    @property
    def stream(self) -> bool:
        """A byte stream (TCP, serial, pty), not datagrams (UDP)."""
        return self.scheme not in (Scheme.UDPIN, Scheme.UDPOUT)

    @property
    def listening(self) -> bool:
        """It waits for its peer (``udpin``, ``tcpin``)."""
        return self.scheme in _LISTENING

    @property
    def serial(self) -> bool:
        """A serial device or pty (a wire, not the network)."""
        return self.scheme in (Scheme.SERIAL, Scheme.PTY)

    @property
    def pyserial_url(self) -> bool:
        """The device is a pyserial URL (``loop://``...), not a path."""
        return "://" in self.device

    def __str__(self) -> str:
        """The address in this module's syntax."""
        if self.serial:
            if self.scheme is Scheme.PTY:
                return f"pty:{self.device}"
            if self.pyserial_url:
                return self.device
            return f"serial:{self.device}" + (f":{self.baud}" if self.baud is not None else "")
        return f"{self.scheme.value}:{self.host}:{self.port}"


def _expected(allowed: Collection[Scheme]) -> str:
    return ", ".join(FORMS[s] for s in Scheme if s in allowed)


def parse_link_address(text: str, option: str, allowed: Collection[Scheme] = MAVLINK_SCHEMES,
                       *, pyserial_urls: bool = False) -> LinkAddress:
    """Parse ``text`` (module table and rules).

    Args:
        text: the address as the user wrote it.
        option: where it came from, for messages (``--aria``, ``[pioneer] url``).
        allowed: the schemes this option takes.
        pyserial_urls: also take pyserial URLs (``socket://HOST:PORT`` as ``tcp``, others
            as serial devices), as ``--aria`` always did.

    Returns:
        The address.

    Raises:
        InputError: not an address of an allowed form, or a bad host, port or rate
            (one line naming ``option`` and ``text``).
    """
    def bad(problem: str) -> InputError:
        return InputError(option, f"{text!r}: {problem}")

    scheme_text, sep, rest = text.partition(":")
    if "://" in text:
        if not pyserial_urls:
            raise bad(f"a URL is not a link address here (expected {_expected(allowed)})")
        scheme, rest = _url_scheme(text)
        if scheme is Scheme.SERIAL:
            return _allowed(LinkAddress(Scheme.SERIAL, text, device=text), allowed, bad)
    elif text.startswith("/") or (not sep and text.startswith(".")):
        scheme, rest = Scheme.SERIAL, text  # a device path alone
    elif scheme_text == "udp":
        scheme = Scheme.UDPIN  # pymavlink's alias
    else:
        try:
            scheme = Scheme(scheme_text)
        except ValueError:
            raise bad(f"not a link address (expected {_expected(allowed)})") from None
        if not sep:
            raise bad(f"not a link address (expected {_expected(allowed)})")
    _allowed(LinkAddress(scheme, text), allowed, bad)
    if scheme is Scheme.PTY:
        if not rest:
            raise bad("no pty path (pty:PATH)")
        return LinkAddress(scheme, text, device=rest)
    if scheme is Scheme.SERIAL:
        return _serial(text, rest, bad)
    host, sep, port_text = rest.rpartition(":")
    if not sep or not host:
        raise bad(f"expected {FORMS[scheme]} (a host and a port)")
    if any(c.isspace() for c in host):
        raise bad(f"host {host!r} has spaces")
    low = 0 if scheme in _LISTENING else 1
    if not port_text.isdigit() or not low <= int(port_text) <= 65535:
        raise bad(f"port {port_text!r} is not an integer in {low}..65535")
    return LinkAddress(scheme, text, host=host, port=int(port_text))


def _url_scheme(text: str) -> tuple[Scheme, str]:
    """(scheme, rest) of a pyserial URL: ``socket://HOST:PORT`` is TCP, others serial."""
    if text.startswith("socket://"):
        return Scheme.TCP, text.removeprefix("socket://").split("?")[0].rstrip("/")
    return Scheme.SERIAL, text


def _allowed(address: LinkAddress, allowed: Collection[Scheme], bad: _Bad) -> LinkAddress:
    if address.scheme not in allowed:
        raise bad(f"{FORMS[address.scheme]} cannot be used here "
                  f"(expected {_expected(allowed)})")
    return address


def _serial(text: str, rest: str, bad: _Bad) -> LinkAddress:
    device, sep, baud_text = rest.rpartition(":")
    if not sep or not baud_text.isdigit():
        device, baud = rest, None
    else:
        baud = int(baud_text)
        if not MIN_BAUD <= baud <= MAX_BAUD:
            raise bad(f"baud rate {baud} is not in {MIN_BAUD}..{MAX_BAUD}")
    if not device:
        raise bad("no device (serial:DEVICE[:BAUD], e.g. serial:/dev/ttyUSB0:57600)")
    return LinkAddress(Scheme.SERIAL, text, device=device, baud=baud)
