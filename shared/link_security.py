"""The secure default of both entry points, ``vmnav robot`` and ``vmnav ground``.

Rules:

1. Without a signing key the default link listens on loopback only
   (``udpin:127.0.0.1:14550``); with one, on every interface (``udpin:0.0.0.0:14550``,
   where a robot and QGroundControl on the network find each other).
2. An unsigned link open to the network (:func:`reaches_network`: a socket another
   machine can reach, or a connection to another machine; not a serial device or pty,
   a wire such as a telemetry radio) lets anyone on the network arm, drive and upload:
   it is refused with one line that says how to sign it, unless the user asked for it
   (``--insecure``); then :func:`check_link` returns the warning line the entry
   point prints at start (the robot also tells each ground station that connects:
   :data:`INSECURE_NOTICE`).
3. The unsigned default (no link given) gets one line saying how to open it to the
   network with a key.
"""

from __future__ import annotations

from typing import NamedTuple

from shared.errors import InputError
from shared.ipv4 import is_loopback, resolve_ipv4
from shared.link_address import LinkAddress, parse_link_address

#: MAVLink's ground-station UDP port.
MAVLINK_PORT = 14550
#: The robot's STATUSTEXT to each ground station that connects over an insecure link.
INSECURE_NOTICE = "link unsigned and open to the network (--insecure)"
#: How to sign a link, for the messages.
HOW_TO_SIGN = ("make a key with `vmnav ground keygen FILE` and give it to both ends "
               "(--key FILE)")


def default_url(signed: bool) -> str:
    """The default link (rule 1): every interface when ``signed``, else loopback only."""
    return f"udpin:{'0.0.0.0' if signed else '127.0.0.1'}:{MAVLINK_PORT}"


def reaches_network(address: LinkAddress) -> bool:
    """Whether the link of ``address`` is open to the network: a listening socket
    (``udpin``, ``tcpin``) bound to an address other than a loopback one, or a link to a
    host other than this machine (``udpout``, whose socket then listens on every
    interface, and ``tcp``). A serial device or pty is a wire: never.

    Raises:
        TransportError: an unknown host.
    """
    if address.serial:
        return False
    # The address a listener is bound to, or the peer's: either way, a non-loopback one
    # puts the link on the network.
    return not is_loopback(resolve_ipv4(address.text, address.host, address.port)[0])


class LinkCheck(NamedTuple):
    """What :func:`check_link` found."""

    url: str  #: the connection string to open
    line: str | None  #: one line for the user at start, or None
    insecure: bool  #: unsigned and open to the network, as asked (``--insecure``)


def check_link(url: str | None, option: str, signed: bool, insecure: bool) -> LinkCheck:
    """Apply rules 1 to 3 to ``url``.

    Args:
        url: the connection string; None for the default (rule 1).
        option: the command-line option it came from, for the message (``--mavlink``).
        signed: the link is signed (a key was given).
        insecure: the user asked for an unsigned link open to the network.

    Returns:
        The link to open, the line to print (a warning for an insecure link, how to
        open the unsigned default to the network) and whether the link is insecure.

    Raises:
        InputError: not a link address, or an unsigned link open to the network without
            ``insecure`` (one line naming ``option``).
        TransportError: an unknown host.
    """
    if url is None:
        url = default_url(signed)
        if not signed:
            return LinkCheck(url, f"{url} is unsigned, for this machine only; to reach it "
                                  f"from the network, {HOW_TO_SIGN}", False)
    address = parse_link_address(url, option)
    if signed or not reaches_network(address):
        return LinkCheck(url, None, False)
    if not insecure:
        raise InputError(f"{option} {url}", "an unsigned link open to the network lets "
                         f"anyone drive the robot: {HOW_TO_SIGN}, or add --insecure")
    return LinkCheck(url, f"WARNING: {url} is unsigned and open to the network "
                          f"(--insecure): anyone who can reach it can drive the robot; "
                          f"{HOW_TO_SIGN}", True)
