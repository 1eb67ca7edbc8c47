"""SIGTERM closes the driver cleanly: the robot receives stop and CLOSE."""

from __future__ import annotations

import os
import signal

import pytest

from robot.pioneer.shutdown import close_on_sigterm
from robot.pioneer.status import LinkState
from shared.aria.commands import ClientCommand, Command
from tests.robot.pioneer.responder import Rig


def test_sigterm_closes_the_driver_and_exits_143() -> None:
    rig = Rig()
    rig.connect()
    rig.driver.command(0.2, 0.0)
    rig.step()
    previous = signal.getsignal(signal.SIGTERM)
    restore = close_on_sigterm(rig.driver)
    try:
        with pytest.raises(SystemExit) as info:
            os.kill(os.getpid(), signal.SIGTERM)
            signal.sigtimedwait([], 1.0)  # the handler runs before this returns
    finally:
        restore()
    assert signal.getsignal(signal.SIGTERM) is previous
    assert info.value.code == 143
    assert rig.driver.status().link is LinkState.CLOSED
    rig.responder.service(rig.clock.now_ns())
    host = [e for _, e in rig.responder.received if isinstance(e, ClientCommand)]
    assert host[-4:] == [ClientCommand(Command.VEL, 0), ClientCommand(Command.RVEL, 0),
                         ClientCommand(Command.ENABLE, 0), ClientCommand(Command.CLOSE, 1)]
