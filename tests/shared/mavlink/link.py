"""An in-memory MAVLink link between a ground station and a vehicle, for protocol tests.

Both ends are our real cores; every message is packed to bytes by the sender's
codec and parsed by the receiver's, one datagram per message, as over UDP. A
seeded relay drops each datagram with probability ``loss`` in each direction.
Time is virtual: when nothing is in flight, the clock jumps to the earliest
deadline of any core and its timers run (one *round*).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from shared.mavlink.address import Address
from shared.mavlink.dialect import Message, make_codec

GCS = Address(255, 190)
VEHICLE = Address(1, 1)


class Endpoint:
    """One side of the link: a codec and the cores fed with every received message."""

    def __init__(self, address: Address, *cores: Any) -> None:
        self.address = address
        self.codec = make_codec(address.system_id, address.component_id)
        self.cores = list(cores)
        self.received: list[Message] = []  # every message delivered here, in order


class Link:
    """Ground station <-> vehicle through a lossy relay.

    Args:
        ground, vehicle: the two ends.
        loss: probability that a datagram is dropped, each direction.
        seed: the relay's RNG seed.
    """

    def __init__(self, ground: Endpoint, vehicle: Endpoint, loss: float = 0.0,
                 seed: int = 0) -> None:
        self.ground, self.vehicle = ground, vehicle
        self.loss = loss
        self.rng = np.random.default_rng(seed)
        self.now_ns = 0
        self.rounds = 0
        self.dropped = 0
        self.drop_next: dict[str, int] = {}  # message type -> datagrams of it to drop
        self._queues: dict[int, deque[bytes]] = {id(ground): deque(), id(vehicle): deque()}

    def _peer(self, end: Endpoint) -> Endpoint:
        return self.vehicle if end is self.ground else self.ground

    def send(self, sender: Endpoint, messages: list[Message]) -> None:
        """Pack ``messages`` with the sender's codec and put them in flight."""
        for msg in messages:
            data = sender.codec.pack(msg)
            if self.drop_next.get(msg.get_type(), 0) > 0:
                self.drop_next[msg.get_type()] -= 1
                self.dropped += 1
            elif self.loss and self.rng.random() < self.loss:
                self.dropped += 1
            else:
                self._queues[id(self._peer(sender))].append(data)

    def deliver(self) -> None:
        """Deliver everything in flight, and whatever the answers put in flight."""
        while any(self._queues.values()):
            for end in (self.ground, self.vehicle):
                queue = self._queues[id(end)]
                if queue:
                    for msg in end.codec.parse(queue.popleft()):
                        end.received.append(msg)
                        for core in end.cores:
                            self.send(end, core.handle_message(msg, self.now_ns))

    def run(self, done: Callable[[], bool], max_rounds: int = 200) -> int:
        """Deliver and run timers until ``done()``; return the timer rounds it took.

        Raises:
            AssertionError: not done after ``max_rounds``, or nothing left to do.
        """
        start = self.rounds
        while True:
            self.deliver()
            if done():
                return self.rounds - start
            assert self.rounds - start < max_rounds, f"not done after {max_rounds} timer rounds"
            cores = [(end, core) for end in (self.ground, self.vehicle) for core in end.cores]
            deadlines = [t for _, core in cores if (t := core.get_timer()) is not None]
            assert deadlines, "stalled: nothing in flight and no timer pending"
            self.now_ns = max(self.now_ns, min(deadlines))
            self.rounds += 1
            for end, core in cores:
                self.send(end, core.handle_timer(self.now_ns))


def events(core: Any) -> list[Any]:
    """Drain a core's events."""
    out = []
    while (event := core.next_event()) is not None:
        out.append(event)
    return out


def of_type(messages: list[Message], name: str) -> list[Any]:
    """The messages of MAVLink type ``name`` (e.g. ``"MISSION_ACK"``)."""
    return [m for m in messages if m.get_type() == name]
