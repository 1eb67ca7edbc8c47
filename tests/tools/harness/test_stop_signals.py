"""tools.harness.stop_signals: a signal asks to stop, a second one interrupts, handlers
come back after."""

from __future__ import annotations

import os
import signal

import pytest

from tools.harness.stop_signals import StopRequest, stopped_by_signals


@pytest.mark.parametrize(("sig", "status", "name"), [(signal.SIGINT, 130, "SIGINT"),
                                                    (signal.SIGTERM, 143, "SIGTERM")])
def test_a_signal_calls_stop_once_and_names_itself(sig: int, status: int, name: str) -> None:
    calls: list[None] = []
    with stopped_by_signals(lambda: calls.append(None)) as request:
        assert request.exit_status == 0 and request.name == ""
        os.kill(os.getpid(), sig)  # the handler runs before kill() returns to Python
        assert calls == [None]
        assert (request.signum, request.exit_status, request.name) == (sig, status, name)


def test_a_second_signal_interrupts_at_once() -> None:
    with pytest.raises(KeyboardInterrupt), stopped_by_signals(lambda: None):
        os.kill(os.getpid(), signal.SIGINT)
        os.kill(os.getpid(), signal.SIGTERM)


def test_the_previous_handlers_are_back_after() -> None:
    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    with stopped_by_signals(lambda: None):
        assert signal.getsignal(signal.SIGINT) is not before[signal.SIGINT]
    assert {sig: signal.getsignal(sig) for sig in before} == before


def test_no_signal_is_status_zero() -> None:
    assert StopRequest().exit_status == 0
