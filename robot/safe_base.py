"""The robot's base as every mission and the stick see it: the safety layer in front.

:class:`SafeBase` is a :class:`~shared.interfaces.MobileBase` around the real one (the
Pioneer's driver): each command passes :class:`robot.safety.SafetyGovernor` first, and
its :meth:`~SafeBase.state` carries the governor's hold (``BaseState.blocked``) for the
mission. The robot process builds it (``robot.process``), so nothing that drives the
robot can go around it. The emergency stop is the one call made from another thread
(the link's): it stops the base at once, with the Pioneer's own E_STOP where the base
has one, and holds until :meth:`~SafeBase.release`.

With ``SafetyConfig.enabled`` false (a developer's switch in the config file) commands
pass unchanged; the emergency stop still works.
"""

from __future__ import annotations

import dataclasses
import threading
from typing import Protocol, runtime_checkable

from robot.config import SafetyConfig
from robot.safety import Assessment, SafetyGovernor
from shared.clock import Clock
from shared.interfaces import BaseState, MobileBase


@runtime_checkable
class EmergencyStoppable(Protocol):
    """A base with its own emergency stop (the Pioneer's E_STOP command)."""

    def e_stop(self) -> None:
        """Stop at maximum deceleration and disable the motors."""
        ...

    def enable_motors(self) -> None:
        """Enable the motors again."""
        ...


class SafeBase:
    """A mobile base whose commands the safety layer bounds (module docstring).

    Args:
        base: the real base.
        clock: the application's clock (the readings' time base).
        config: the safety layer's settings.
    """

    def __init__(self, base: MobileBase, clock: Clock, config: SafetyConfig) -> None:
        self._base = base
        self._clock = clock
        self._governor = SafetyGovernor(config)
        self._lock = threading.Lock()
        self._asked = (0.0, 0.0)
        self._last: Assessment | None = None

    @property
    def enabled(self) -> bool:
        """The sonar and bumper rules apply (``SafetyConfig.enabled``)."""
        return self._governor.config.enabled

    @property
    def last_assessment(self) -> Assessment | None:
        """The governor's verdict on the latest command or state."""
        return self._last

    def configure(self, config: SafetyConfig) -> None:
        """New settings (the robot's parameters changed); holds in force stay."""
        with self._lock:
            self._governor.configure(config)

    def command(self, v_m_s: float, omega_rad_s: float) -> None:
        """Drive at what the safety layer allows of (v_m_s, omega_rad_s)."""
        with self._lock:
            self._asked = (v_m_s, omega_rad_s)
            bounded = self._assess(self._base.state())
            if bounded.v_m_s == 0.0 and bounded.omega_rad_s == 0.0:
                self._base.stop()
            else:
                self._base.command(bounded.v_m_s, bounded.omega_rad_s)

    def stop(self) -> None:
        """Command zero velocity."""
        with self._lock:
            self._asked = (0.0, 0.0)
            self._base.stop()

    def state(self) -> BaseState:
        """The base's state with the safety layer's hold (``blocked``)."""
        with self._lock:
            state = self._base.state()
            return dataclasses.replace(state, blocked=self._assess(state).blocked)

    def emergency_stop(self) -> None:
        """Stop now (E_STOP where the base has it) and hold until :meth:`release`;
        safe to call from any thread."""
        with self._lock:
            self._governor.emergency_stop(self._clock.now_ns())
            self._asked = (0.0, 0.0)
            if isinstance(self._base, EmergencyStoppable):
                self._base.e_stop()
            else:
                self._base.stop()

    def release(self) -> None:
        """End an emergency stop's or bumper's hold (the operator re-armed or changed mode);
        motors an E_STOP disabled are enabled again."""
        with self._lock:
            latched = self._governor.latched
            held = latched is not None and latched.cause == "e_stop"
            self._governor.release()
            if held and isinstance(self._base, EmergencyStoppable):
                self._base.enable_motors()

    def _assess(self, state: BaseState) -> Assessment:
        now_ns = self._clock.now_ns()
        assessed = self._governor.assess(now_ns, state, *self._asked)
        if not self.enabled:
            held = assessed.blocked if assessed.blocked is not None and (
                assessed.blocked.cause == "e_stop") else None
            assessed = (Assessment(0.0, 0.0, held, assessed.ahead_m) if held is not None
                        else Assessment(*self._asked, None, assessed.ahead_m))
        self._last = assessed
        return assessed
