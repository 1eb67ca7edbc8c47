"""MAVLink addresses: who sent a message, and whether a message is meant for us.

A MAVLink 2 header carries the sender's (system id, component id); requests
carry ``target_system`` / ``target_component`` fields for the receiver. Target
0 means "every system" / "every component" (devguide routing.md).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True, slots=True)
class Address:
    """One MAVLink component: a system id and a component id, each 0-255."""

    system_id: int
    component_id: int

    def __post_init__(self) -> None:
        for name in ("system_id", "component_id"):
            value = getattr(self, name)
            if not 0 <= value <= 255:
                raise ValueError(f"{name} must be in 0..255, got {value}")


def source_of(msg: Any) -> Address:
    """The sender of a decoded message (its header's system and component ids)."""
    return Address(msg.get_srcSystem(), msg.get_srcComponent())


def is_for(msg: Any, address: Address) -> bool:
    """Whether ``msg`` is addressed to ``address`` (or broadcast).

    Messages without target fields (HEARTBEAT, PARAM_VALUE...) are broadcasts and
    count as addressed to everyone. A message with only ``target_system``
    (SET_MODE) is checked on that field alone.
    """
    system = getattr(msg, "target_system", 0)
    component = getattr(msg, "target_component", 0)
    return system in (0, address.system_id) and component in (0, address.component_id)
