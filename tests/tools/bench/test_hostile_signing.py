"""The signing hostile-input benchmark: a short run meets its targets and reports every case."""

from __future__ import annotations

import json

from tools.bench.hostile_signing import CAPTURED, measure


def test_a_short_run_meets_the_targets() -> None:
    figures = measure(seed=1, wrong_key_packets=600, old_timestamp_packets=50)
    json.dumps(figures)  # JSON-serialisable
    assert figures["wrong_key_packets_sent"] == 600
    assert figures["old_timestamp_packets_sent"] == 50
    assert figures["replay_packets_sent"] >= 2 * CAPTURED
    assert figures["replay_after_restart_packets_sent"] >= CAPTURED
    assert figures["packets_not_parsed"] == 0
    assert figures["targets_met"] is True, figures
