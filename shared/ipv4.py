"""IPv4 names: resolving a host for a socket, and whether an address stays on this machine.

IPv4 only, like pymavlink's UDP and TCP links.
"""

from __future__ import annotations

import ipaddress
import socket

from shared.errors import TransportError

__all__ = ["Peer", "is_loopback", "resolve_ipv4"]

#: An IPv4 address and port, as ``socket`` gives them.
Peer = tuple[str, int]


def resolve_ipv4(where: str, host: str, port: int) -> Peer:
    """The IPv4 (address, port) of ``host``:``port``.

    Args:
        where: the address the user gave, for messages.
        host: a host name or IPv4 address.
        port: the port.

    Raises:
        TransportError: the host does not resolve to an IPv4 address (one line naming
            ``where``).
    """
    try:
        infos = socket.getaddrinfo(host, port, socket.AF_INET)
    except (socket.gaierror, UnicodeError) as e:
        raise TransportError(where, f"cannot resolve host {host!r}: {e}") from None
    address, resolved_port = infos[0][4][:2]
    return str(address), int(resolved_port)


def is_loopback(address: str) -> bool:
    """Whether the IPv4 ``address`` (dotted quad) is on this machine only (127.0.0.0/8)."""
    return ipaddress.ip_address(address).is_loopback
