"""``vmnav pioneer``: connect to a Pioneer (or ``vmnav sim serve``), report it, optionally drive.

The link check a user runs first with a real robot: it opens the ARIA link through
:class:`robot.pioneer.driver.PioneerDriver` (``serial:DEVICE[:BAUD]``, ``pty:PATH`` or
``tcp:HOST:PORT``; a device path or ``socket://HOST:PORT`` also work), waits until the
motors are enabled, prints the robot's
identity and state, optionally drives at a fixed speed and turn rate for a while
(printing the odometry every second), then stops and closes the link with CLOSE
(also on Ctrl-C and SIGTERM). Exit status: 0 when connected (and the drive done),
1 with a one-line error otherwise: a bad address at once, a missing device, an unknown
host or a refused or unanswered connect in under 2 s (``PioneerDriver.open_transport``).
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from typing import TYPE_CHECKING

from shared.errors import InputError, TransportError
from tools.harness.arg_types import FINITE, POSITIVE, POSITIVE_COUNT

if TYPE_CHECKING:
    from robot.pioneer.driver import PioneerDriver

def add_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav pioneer``."""
    parser = sub.add_parser(
        "pioneer",
        help="connect to a Pioneer over ARIA, report it, optionally drive",
        description="Connect to a Pioneer 3-AT (or vmnav sim serve, or MobileSim) with "
        "vmnav's ARIA driver, print its identity, battery and odometry, optionally drive "
        "at a fixed speed and turn rate, then stop and close the link.",
    )
    parser.add_argument("--config", metavar="FILE", help="vmnav TOML config file ([pioneer])")
    parser.add_argument("--aria", metavar="ADDRESS",
                        help="the Pioneer: serial:DEVICE[:BAUD], pty:PATH or tcp:HOST:PORT "
                             "(a device path or socket://HOST:PORT also work) [default: the "
                             "config's pioneer.url]")
    parser.add_argument("--baud", type=POSITIVE_COUNT, metavar="N",
                        help="serial rate after the 9600 baud attempt [default: 38400]")
    parser.add_argument("--drive", nargs=2, type=FINITE, metavar=("V_M_S", "OMEGA_DEG_S"),
                        help="drive at this speed (m/s) and turn rate (deg/s, left +)")
    parser.add_argument("--duration", type=POSITIVE, default=2.0, metavar="S",
                        help="how long to drive, s [default: 2]")
    parser.set_defaults(run=run_pioneer)


def run_pioneer(args: argparse.Namespace) -> int:
    """Connect, report, drive, close (see the module docstring)."""
    from robot.config import load_config
    from robot.pioneer.connection import CONNECT_TIMEOUT_S, why_not_connected
    from robot.pioneer.driver import PioneerDriver
    from robot.pioneer.serial_link import aria_address
    from robot.pioneer.shutdown import close_on_sigterm
    from shared.clock import WallClock

    config = load_config(args.config).pioneer
    overrides: dict[str, object] = {}
    if args.aria is not None:
        overrides["url"] = args.aria
    if args.baud is not None:
        overrides["baud"] = args.baud
    config = dataclasses.replace(config, **overrides)
    option = "--aria" if args.aria is not None else "[pioneer] url"
    aria_address(config.url, option)
    if args.drive is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise InputError("--duration", f"must be > 0 seconds, got {args.duration}")
    clock = WallClock()
    driver = PioneerDriver.from_config(config, clock)
    restore = close_on_sigterm(driver)
    try:
        try:
            driver.open_transport()
        except TransportError as e:
            raise TransportError(f"{option} {config.url}", e.problem) from None
        driver.start_thread()
        if not driver.wait_connected(round(CONNECT_TIMEOUT_S * 1e9)):
            raise TransportError(config.url, why_not_connected(driver))
        identity = driver.status().identity
        assert identity is not None  # set by the handshake
        print(f"connected to {identity.name!r} ({identity.robot_class} {identity.subclass}) "
              f"on {config.url}")
        _print_state(driver, 0.0)
        if args.drive is not None:
            v_m_s, omega_deg_s = args.drive
            start_ns = clock.now_ns()
            for second in range(1, math.ceil(args.duration) + 1):
                end_ns = start_ns + round(min(second, args.duration) * 1e9)
                while clock.now_ns() < end_ns:
                    driver.command(v_m_s, math.radians(omega_deg_s))
                    clock.sleep_until_ns(min(end_ns, clock.now_ns() + 100_000_000))
                _print_state(driver, min(second, args.duration))
            driver.stop()
    finally:
        driver.close()
        restore()
    counters = driver.counters()
    print(f"closed: {counters.sips} SIPs, {counters.bad_checksums} bad checksums, "
          f"{counters.dropped_commands} commands dropped")
    return 0


def _print_state(driver: PioneerDriver, t_s: float) -> None:
    s = driver.status()
    x, y, yaw = s.odom_pose
    print(f"  t {t_s:4.1f} s: odometry x {x:+.3f} m, y {y:+.3f} m, yaw {math.degrees(yaw):+.1f} "
          f"deg, {s.odom_distance_m:.3f} m driven; battery {s.battery_v:.1f} V; motors "
          f"{'on' if s.motors_enabled else 'off'}; bumpers {s.front_bumpers:#x}/"
          f"{s.rear_bumpers:#x}; stalled {'yes' if s.left_stalled or s.right_stalled else 'no'}")
