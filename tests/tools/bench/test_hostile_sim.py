"""``tools.bench.hostile_sim``: one real run against ``vmnav sim serve`` meets its targets."""

from __future__ import annotations

import json

import pytest

from tools.bench import hostile_sim


@pytest.mark.slow
def test_the_served_simulator_survives_the_hostile_run() -> None:
    result = hostile_sim.measure(seed=1)
    json.dumps(result, allow_nan=False)  # plain JSON
    assert result["aria_server_alive_after_batch"] is True, result
    assert result["aria_handler_errors"] == 0, result
    assert result["aria_battery_v_after_battest"] == pytest.approx(25.6), result
    assert result["control_bad_requests_refused"] == result["control_bad_requests"], result
    assert result["targets_met"] is True, result
