"""The Pioneer's byte link, opened from its address (``--aria``, ``[pioneer] url``).

Addresses (``shared.link_address``): ``serial:DEVICE[:BAUD]`` or a device path alone,
``pty:PATH``, ``tcp:HOST:PORT`` (MobileSim, ``vmnav sim serve``, a serial-to-TCP
bridge); also pyserial URLs as before: ``socket://HOST:PORT`` (the same as ``tcp:``) and
the others (``loop://``) as they are. A serial device opens through
:class:`shared.serial_port.SerialLink`, TCP through :func:`shared.stream_link.connect_tcp`,
whose short connect timeout makes an unreachable host an error in about a second rather
than pyserial's 5 s per attempt.

Baud rates (reference §9): ARCOS listens at 9600 after power-up, but an earlier
client may have left it at another rate with HOSTBAUD. :func:`serial_link_factory`
therefore alternates 9600 and the configured rate (the address's BAUD, else ``baud``)
between connect attempts on a device; TCP and pyserial URLs have no rate.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable

from shared.byte_link import ByteLink
from shared.link_address import ARIA_SCHEMES, LinkAddress, Scheme, parse_link_address
from shared.serial_port import SerialLink, is_device
from shared.stream_link import CONNECT_TIMEOUT_S, connect_tcp

__all__ = ["ARCOS_BAUD", "SerialLink", "aria_address", "is_device", "serial_link_factory"]

ARCOS_BAUD = 9600
"""The robot's serial rate after power-up (ArRobotConnector's default too)."""


def aria_address(text: str, option: str = "--aria") -> LinkAddress:
    """The Pioneer's address ``text`` (module docstring).

    Raises:
        InputError: not one (one line naming ``option`` and ``text``).
    """
    return parse_link_address(text, option, ARIA_SCHEMES, pyserial_urls=True)


def serial_link_factory(url: str | LinkAddress, baud: int, write_timeout_s: float = 0.5,
                        connect_timeout_s: float = CONNECT_TIMEOUT_S
                        ) -> Callable[[], ByteLink]:
    """A ``link_factory`` for :class:`~robot.pioneer.driver.PioneerDriver`.

    Each call opens the link anew. On a serial device the rate alternates 9600, the
    configured rate, 9600, ... (just 9600 if that is 9600); pyserial URLs open at the
    configured rate every time; TCP connects with ``connect_timeout_s``.

    Args:
        url: the address (module docstring).
        baud: the configured rate when the address gives none, baud.
        write_timeout_s: serial write timeout, s.
        connect_timeout_s: TCP connect timeout, s.

    Raises:
        InputError: ``url`` is not an address (at once, not at the first call).
    """
    address = aria_address(url, "[pioneer] url") if isinstance(url, str) else url
    if address.scheme is Scheme.TCP:
        return lambda: connect_tcp(address.text, address.host, address.port, connect_timeout_s)
    device = address.device
    rate = address.baud if address.baud is not None else baud
    rates = (itertools.cycle(dict.fromkeys((ARCOS_BAUD, rate))) if is_device(device)
             else itertools.repeat(rate))

    def open_next() -> SerialLink:
        return SerialLink.open(device, next(rates), write_timeout_s)

    return open_next
