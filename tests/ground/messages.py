"""Messages as the ground receives them: packed by a vehicle's codec, parsed by the ground's."""

from __future__ import annotations

from typing import Any

from shared.mavlink.dialect import Message, make_codec


def from_system(system_id: int, *messages: Message, component_id: int = 1) -> list[Any]:
    """``messages`` sent by (``system_id``, ``component_id``), decoded."""
    sender, receiver = make_codec(system_id, component_id), make_codec(255, 190)
    return receiver.parse(b"".join(sender.pack(msg) for msg in messages))
