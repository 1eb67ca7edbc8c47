"""The vehicles a ground station hears, by system id, from their own messages (pure).

Rules:

1. A vehicle is a system whose HEARTBEAT names an autopilot (``autopilot`` not
   ``MAV_AUTOPILOT_INVALID``): ground stations, cameras and gimbals beat with
   INVALID and are not vehicles. The component that beats is the one to talk to.
   A camera's HEARTBEAT from a known vehicle's system (``shared.mavlink.camera``) is
   kept as that vehicle's camera, by component id, with when it was heard.
2. Every other message from a known vehicle's system is kept as its last telemetry
   of that type (``telemetry["SYS_STATUS"]``...); messages from systems that have
   not beaten yet are ignored.
3. STATUSTEXT notices are joined from their chunks (common.xml: chunks share a
   non-zero ``id``; a chunk shorter than 50 characters ends the text) and kept in
   arrival order.
4. ``peer`` is the UDP address the vehicle's last datagram came from, so a station
   listening for several vehicles can answer each one.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from shared.mavlink.address import Address, source_of
from shared.mavlink.camera import is_camera_heartbeat
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.modes import Mode
from shared.mavlink.statustext import TEXT_LEN
from shared.udp_link import Peer


def mode_name(custom_mode: int) -> str:
    """Our name of a HEARTBEAT ``custom_mode`` (``"HOLD"``), or ``"mode 7"`` for another."""
    try:
        return Mode(custom_mode).name
    except ValueError:
        return f"mode {custom_mode}"


@dataclass(slots=True)
class VehicleState:
    """What the station knows of one vehicle.

    Attributes:
        address: the component that sends its HEARTBEAT.
        peer: where its last datagram came from (None when not over UDP).
        last_heartbeat_ns: when its last HEARTBEAT arrived, station clock, ns.
        custom_mode: HEARTBEAT ``custom_mode`` (ArduRover numbering).
        system_status: HEARTBEAT ``system_status``, a ``MAV_STATE``.
        armed: HEARTBEAT ``base_mode`` has ``MAV_MODE_FLAG_SAFETY_ARMED``.
        telemetry: message type -> the last message of that type from the system.
        notices: STATUSTEXT texts, chunks joined, oldest first.
        cameras: camera component id -> when its last HEARTBEAT arrived, station clock, ns.
    """

    address: Address
    peer: Peer | None
    last_heartbeat_ns: int
    custom_mode: int = 0
    system_status: int = 0
    armed: bool = False
    telemetry: dict[str, Any] = field(default_factory=dict)
    notices: list[str] = field(default_factory=list)
    cameras: dict[int, int] = field(default_factory=dict)
    _chunks: dict[int, str] = field(default_factory=dict)

    @property
    def system_id(self) -> int:
        """The vehicle's MAVLink system id."""
        return self.address.system_id

    @property
    def mode(self) -> Mode | None:
        """The mode in our numbering; None for a number we do not know."""
        try:
            return Mode(self.custom_mode)
        except ValueError:
            return None

    @property
    def mode_name(self) -> str:
        """E.g. ``"HOLD"`` (:func:`mode_name`)."""
        return mode_name(self.custom_mode)

    def add_statustext(self, msg: Any) -> None:
        """Keep one STATUSTEXT chunk, joining a long notice's chunks (rule 3)."""
        chunk = msg.text
        if msg.id == 0:
            self.notices.append(chunk)
            return
        joined = (self._chunks.pop(msg.id, "") if msg.chunk_seq > 0 else "") + chunk
        if len(chunk) < TEXT_LEN:
            self.notices.append(joined)
        else:
            self._chunks[msg.id] = joined


class Fleet:
    """Vehicles by system id (module rules)."""

    def __init__(self) -> None:
        self.vehicles: dict[int, VehicleState] = {}

    def handle(self, msg: Message, peer: Peer | None, now_ns: int) -> VehicleState | None:
        """Record one received message.

        Returns:
            The vehicle it came from, or None when it came from no known vehicle.
        """
        source = source_of(msg)
        vehicle = self.vehicles.get(source.system_id)
        if isinstance(msg, mavlink.MAVLink_heartbeat_message):
            if is_camera_heartbeat(msg) and vehicle is not None:
                vehicle.cameras[source.component_id] = now_ns
            if msg.autopilot == mavlink.MAV_AUTOPILOT_INVALID:
                return None
            if vehicle is None:
                vehicle = VehicleState(source, peer, now_ns)
                self.vehicles[source.system_id] = vehicle
            vehicle.address, vehicle.last_heartbeat_ns = source, now_ns
            vehicle.custom_mode, vehicle.system_status = msg.custom_mode, msg.system_status
            vehicle.armed = bool(msg.base_mode & mavlink.MAV_MODE_FLAG_SAFETY_ARMED)
        if vehicle is None:
            return None
        vehicle.peer = peer if peer is not None else vehicle.peer
        vehicle.telemetry[msg.get_type()] = msg
        if isinstance(msg, mavlink.MAVLink_statustext_message):
            vehicle.add_statustext(msg)
        return vehicle
