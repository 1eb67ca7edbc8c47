from __future__ import annotations

import threading

import pytest

from shared.clock import Clock, ManualClock, WallClock, ns_from_s, s_from_ns, service_loop


class TestManualClock:
    def test_starts_where_told_and_advances_exactly(self) -> None:
        clock = ManualClock(start_ns=5)
        clock.advance(0.1)
        clock.advance(0.1)
        clock.advance(0.1)
        assert clock.now_ns() == 5 + 300_000_000  # no float drift across three 0.1 s steps

    def test_sleep_until_jumps_to_deadline_and_never_back(self) -> None:
        clock = ManualClock()
        clock.sleep_until_ns(1_000)
        assert clock.now_ns() == 1_000
        clock.sleep_until_ns(500)
        assert clock.now_ns() == 1_000

    def test_refuses_to_go_backwards(self) -> None:
        clock = ManualClock()
        with pytest.raises(ValueError, match="backwards"):
            clock.advance_ns(-1)

    def test_deadline_loop_runs_instantly(self, manual_clock: ManualClock) -> None:
        deadline = manual_clock.now_ns()
        ticks = []
        for _ in range(15):
            deadline += 66_666_667
            manual_clock.sleep_until_ns(deadline)
            ticks.append(manual_clock.now_ns())
        assert ticks[-1] == 15 * 66_666_667


class TestWallClock:
    def test_is_a_clock_and_monotonic(self) -> None:
        clock: Clock = WallClock()
        a = clock.now_ns()
        clock.sleep_until_ns(a + 2_000_000)
        assert clock.now_ns() >= a + 2_000_000

    def test_past_deadline_returns_at_once(self) -> None:
        clock = WallClock()
        now = clock.now_ns()
        clock.sleep_until_ns(now - 10**9)
        assert clock.now_ns() - now < 10**8


def test_conversions_round_trip() -> None:
    assert ns_from_s(1.5) == 1_500_000_000
    assert s_from_ns(ns_from_s(0.066666667)) == pytest.approx(0.066666667)


class TestServiceLoop:
    def test_rounds_on_period_deadlines_until_stopped(self) -> None:
        clock, stop, seen = ManualClock(), threading.Event(), []

        def service(now_ns: int) -> None:
            seen.append(now_ns)
            if len(seen) == 4:
                stop.set()

        service_loop(service, clock, 10, stop, "test")
        assert seen == [0, 10, 20, 30]

    def test_a_failing_round_is_logged_and_raised(self, caplog) -> None:
        def service(now_ns: int) -> None:
            raise RuntimeError("bug")

        with pytest.raises(RuntimeError, match="bug"):
            service_loop(service, ManualClock(), 10, threading.Event(), "io")
        assert "io: I/O thread died" in caplog.text
