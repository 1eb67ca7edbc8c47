"""The vehicle's ground link from its address (``--mavlink``): UDP or a stream.

:func:`open_vehicle_transport` opens the transport, so that the entry point finds a bad
address, a port in use or a missing device before it starts anything else (before the
Pioneer's motors are enabled); :func:`vehicle_on` puts the endpoint on it:
:class:`~robot.vehicle.udp_vehicle.UdpVehicle` for ``udpin``/``udpout``,
:class:`~robot.vehicle.stream_vehicle.StreamVehicle` for ``tcp``, ``tcpin``, ``serial``
and ``pty`` (``shared.link_address``).

At start: a serial device or pty must open (it is the robot's own radio); a ``tcp``
host must resolve (its ground station may start later: the connect is retried); a
``tcpin`` or ``udpin`` port must be free.
"""

from __future__ import annotations

from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.stream_vehicle import StreamVehicle
from robot.vehicle.udp_vehicle import UdpVehicle
from robot.vehicle.vehicle_io import VehicleIo
from shared.clock import Clock
from shared.ipv4 import resolve_ipv4
from shared.link_address import Scheme, parse_link_address
from shared.stream_port import StreamPort
from shared.udp_link import UdpLink

__all__ = ["VehicleTransport", "open_vehicle_transport", "transport_address", "vehicle_on"]

#: The transport of a vehicle's ground link.
VehicleTransport = UdpLink | StreamPort


def open_vehicle_transport(url: str, option: str = "--mavlink") -> VehicleTransport:
    """Open the transport of ``url`` (module docstring).

    Raises:
        InputError: ``url`` is not an address (one line naming ``option``).
        TransportError: a port in use, a missing device, an unknown host (one line).
    """
    address = parse_link_address(url, option)
    if not address.stream:
        return UdpLink.open(url)
    if address.scheme is Scheme.TCP:
        resolve_ipv4(address.text, address.host, address.port)
    port = StreamPort.open(address)
    if address.serial:
        try:
            port.connect()
        except BaseException:
            port.close()
            raise
    return port


def transport_address(transport: VehicleTransport) -> str:
    """``transport``'s address as opened: a listener given port 0 shows the port it got."""
    if isinstance(transport, StreamPort) or not transport.listening:
        return transport.url
    return f"udpin:{transport.url.split(':')[-2]}:{transport.local_port}"


def vehicle_on(transport: VehicleTransport, endpoint: VehicleEndpoint,
               clock: Clock) -> VehicleIo:
    """``endpoint`` on ``transport``; the vehicle owns both from now on."""
    if isinstance(transport, StreamPort):
        return StreamVehicle(endpoint, transport, clock)
    return UdpVehicle(endpoint, transport, clock)
