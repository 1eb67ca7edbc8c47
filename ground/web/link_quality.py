"""Link quality per vehicle: the share of its packets that arrived, from their sequence numbers
(pure).

Rules:

1. Every MAVLink packet carries a ``seq`` that its sending component increments, modulo 256.
   A jump of ``k`` > 1 means ``k - 1`` packets were lost on the way (MAVLink's own
   "packet drop" count, as QGroundControl shows it).
2. A jump backwards or of more than :data:`MAX_GAP` is a restart of the sender or a
   reordering, not a loss: it counts nothing.
3. The quality is the share received among the last :data:`WINDOW` packets expected,
   summed over the system's components; None before any packet.
"""

from __future__ import annotations

from collections import deque

#: Packets expected over which the quality is computed (the last ones).
WINDOW = 200
#: Largest seq jump read as losses (rule 2).
MAX_GAP = 128


class LinkQuality:
    """Received share per system (module rules)."""

    def __init__(self, window: int = WINDOW) -> None:
        self._last_seq: dict[tuple[int, int], int] = {}
        self._window = window
        self._events: dict[int, deque[tuple[int, int]]] = {}  # system -> (received, lost)

    def packet(self, system_id: int, component_id: int, seq: int) -> None:
        """Count one packet received from ``(system_id, component_id)`` with ``seq``."""
        last = self._last_seq.get((system_id, component_id))
        self._last_seq[(system_id, component_id)] = seq
        lost = 0
        if last is not None:
            gap = (seq - last) % 256
            lost = gap - 1 if 1 <= gap <= MAX_GAP else 0
        events = self._events.setdefault(system_id, deque())
        events.append((1, lost))
        expected = sum(r + n for r, n in events)
        while expected > self._window and len(events) > 1:
            received, dropped = events.popleft()
            expected -= received + dropped

    def received_share(self, system_id: int) -> float | None:
        """The share of ``system_id``'s packets received lately, 0..1 (rule 3)."""
        events = self._events.get(system_id)
        if not events:
            return None
        received = sum(r for r, _ in events)
        return received / (received + sum(n for _, n in events))
