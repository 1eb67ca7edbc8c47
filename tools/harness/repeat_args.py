"""The command-line options of one lock-step teach and repeat (``vmnav demo``, a sweep's
case) and what they set up.

A sweep's case is a ``vmnav demo`` command line without its outputs: both parse their
options here (with :mod:`tools.harness.sim_args` and :mod:`tools.harness.scene_args`),
so the command a sweep's report prints to rerun a case alone runs that very case.
"""

from __future__ import annotations

import argparse
import typing
from dataclasses import dataclass
from typing import TYPE_CHECKING

from robot.config import CONTROL_LAWS
from shared.errors import InputError
from tools.harness.arg_types import FINITE, KEY_IMAGE, POSITIVE

if TYPE_CHECKING:
    from robot.config import VmnavConfig
    from shared.camera_model import CameraModel
    from sim.config import SimConfig
    from sim.scene_change import SceneChange


@dataclass(frozen=True, eq=False)
class RepeatSetup:
    """What the options set up.

    Attributes:
        config: the robot's configs (law, turn-rate bound and speed applied).
        sim_config: the simulation (world, seed, people, camera file).
        camera: the simulated camera.
        change: what changed between teach and repeat.
        routes: routes taught, in order (None: all the world's).
        goal_id: the goal key image (None: :func:`tools.harness.demo.default_goal`).
        start_offset_m: the start's shift left of the first taught path, m.
    """

    config: VmnavConfig
    sim_config: SimConfig
    camera: CameraModel
    change: SceneChange
    routes: tuple[str, ...] | None
    goal_id: int | None
    start_offset_m: float


def add_repeat_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--routes``, ``--goal``, ``--max-omega-deg``, ``--law``, ``--speed`` and
    ``--start-offset``."""
    from tools.harness.demo import START_OFFSET_M

    parser.add_argument("--routes", default=None, metavar="A,B,...",
                        help="routes to teach, in order [default: all the world's, in its order]")
    parser.add_argument("--goal", type=KEY_IMAGE, default=None, metavar="ID",
                        help="goal key image [default: the middle of the second route]")
    parser.add_argument("--max-omega-deg", type=POSITIVE, default=None, metavar="DEG",
                        help="bound on the turn rate, deg/s [default: the config's, 25; the "
                        "paper's 10 cannot follow the lab's 0.8 m radius turns at 0.2 m/s]")
    parser.add_argument("--law", choices=CONTROL_LAWS, default=None,
                        help="control law: the paper's eq. (2), or with the teach path's "
                        "curvature fed forward [default: the config's, paper+ff]")
    parser.add_argument("--speed", type=POSITIVE, default=None, metavar="M/S",
                        help="servo speed, m/s [default: the config's, 0.2]")
    parser.add_argument("--start-offset", type=FINITE, default=START_OFFSET_M, metavar="M",
                        help="the robot starts this far left of the first route (negative: "
                        f"right), turned 10 degrees, m [default: {START_OFFSET_M}]")


def repeat_setup_from_args(args: argparse.Namespace) -> RepeatSetup:
    """The setup the options describe (the simulation options of
    :func:`tools.harness.sim_args.add_sim_arguments`, the change options of
    :func:`tools.harness.scene_args.add_change_arguments` and :func:`add_repeat_arguments`).

    Raises:
        InputError: a bad option, config, camera file or world, or a change the world
            cannot take (naming the option or file).
    """
    from robot.config import load_config
    from tools.harness.demo import follow_config
    from tools.harness.scene_args import check_change_fits, scene_change_from_args
    from tools.harness.sim_args import sim_config_from_args

    change = scene_change_from_args(args)
    routes = None if args.routes is None else tuple(
        name.strip() for name in args.routes.split(",") if name.strip())
    if routes is not None and not routes:
        raise InputError("--routes", "names no route")
    sim_config, camera = sim_config_from_args(args)
    check_change_fits(change, sim_config)
    config = follow_config(load_config(args.config), args.law, args.max_omega_deg, args.speed)
    return RepeatSetup(config=config, sim_config=sim_config, camera=camera, change=change,
                       routes=routes, goal_id=args.goal, start_offset_m=args.start_offset)


class _OptionsParser(argparse.ArgumentParser):
    """argparse raising :class:`InputError` instead of exiting."""

    def error(self, message: str) -> typing.NoReturn:
        raise InputError("options", message)


def parse_repeat_options(argv: list[str] | tuple[str, ...]) -> argparse.Namespace:
    """Parse the options of one teach and repeat (``vmnav demo``'s without its outputs):
    :func:`tools.harness.sim_args.add_sim_arguments`,
    :func:`tools.harness.scene_args.add_change_arguments` and :func:`add_repeat_arguments`.

    Raises:
        InputError: an unknown option or a malformed value (argparse's message).
    """
    from tools.harness.scene_args import add_change_arguments
    from tools.harness.sim_args import add_sim_arguments

    parser = _OptionsParser(prog="vmnav demo", add_help=False)
    add_sim_arguments(parser)
    add_repeat_arguments(parser)
    add_change_arguments(parser)
    return parser.parse_args(list(argv))
