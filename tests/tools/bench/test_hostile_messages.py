"""tools/bench/hostile_messages.py: the attack on a real vehicles process, run once.

The heartbeat rate is the benchmark's figure, not checked here (a loaded machine may
starve the vehicle process); the mechanism is: every issue packet refused with its
MISSION_ACK error, the upload during the mission denied before any item is requested,
no handler exception, and the vehicle still beating and obeying HOLD afterwards.
"""

from __future__ import annotations

import json

import pytest

from tools.bench.hostile_messages import ISSUE_ITEMS, RANDOM_MESSAGES, measure


@pytest.mark.slow
def test_the_vehicle_refuses_every_issue_packet_and_survives_the_random_ones() -> None:
    result = measure(seed=1)
    json.dumps(result)  # the CLI prints it as JSON
    assert result["issue_cases"] == {name: case[3] for name, case in ISSUE_ITEMS.items()}
    assert result["upload_while_running"] == "MAV_MISSION_DENIED"
    assert result["requests_after_denied"] == 0
    assert result["packets_sent"] == RANDOM_MESSAGES + 2 * len(ISSUE_ITEMS) + 1
    assert result["handler_exceptions"] == 0
    assert isinstance(result["messages_refused"], int) and result["messages_refused"] > 0
    assert result["thread_alive"] and result["hold_obeyed"]
