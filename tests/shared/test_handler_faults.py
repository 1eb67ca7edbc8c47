"""HandlerFaults: counted per kind, each kind logged once with its traceback, kinds bounded."""

from __future__ import annotations

import logging

import pytest

from shared.handler_faults import MAX_KINDS, OTHER_KIND, HandlerFaults

logger = logging.getLogger("tests.handler_faults")


def test_each_kind_is_counted_and_logged_once_with_its_traceback(
        caplog: pytest.LogCaptureFixture) -> None:
    faults = HandlerFaults(logger, "vehicle")
    with caplog.at_level(logging.ERROR, logger=logger.name):
        for _ in range(3):
            faults.record("MISSION_ITEM", ValueError("cannot convert float NaN to integer"))
        faults.record("MISSION_ITEM", OverflowError("cannot convert float infinity"))
        faults.record("I/O round", ValueError("x"))
    assert faults.counts() == {"MISSION_ITEM: ValueError": 3, "MISSION_ITEM: OverflowError": 1,
                               "I/O round: ValueError": 1}
    assert faults.total == 5
    assert [r.getMessage().split(" (")[0] for r in caplog.records] == [
        "vehicle: MISSION_ITEM: ValueError: cannot convert float NaN to integer",
        "vehicle: MISSION_ITEM: OverflowError: cannot convert float infinity",
        "vehicle: I/O round: ValueError: x"]
    assert all(r.exc_info is not None for r in caplog.records)


def test_kinds_beyond_the_limit_count_as_other(caplog: pytest.LogCaptureFixture) -> None:
    faults = HandlerFaults(logger, "vehicle")
    with caplog.at_level(logging.ERROR, logger=logger.name):
        for i in range(MAX_KINDS + 10):
            faults.record(f"UNKNOWN_{i}", KeyError(i))
    counts = faults.counts()
    assert len(counts) == MAX_KINDS + 1 and counts[OTHER_KIND] == 10
    assert faults.total == MAX_KINDS + 10
    assert len(caplog.records) == MAX_KINDS + 1
