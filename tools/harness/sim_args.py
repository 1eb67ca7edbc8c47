"""Command-line options shared by the commands that build a simulated world."""

from __future__ import annotations

import argparse
import dataclasses
import math
from typing import TYPE_CHECKING

from robot.config import load_config
from shared.calibration import load_camera
from shared.camera_model import CameraModel
from shared.errors import ConfigError, InputError
from shared.pose import Pose2
from sim.config import SimConfig, load_sim_config
from tools.harness.arg_types import COUNT, SEED

if TYPE_CHECKING:
    from sim.simulation import Simulation
    from sim.world import World


def add_sim_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--config``, ``--world``, ``--seed``, ``--people`` and ``--camera``."""
    parser.add_argument(
        "--config", metavar="FILE",
        help="vmnav TOML config file (its [sim] table, and the robot's [camera.mount])"
    )
    parser.add_argument(
        "--world", help="built-in world (lab, campus) or a world TOML file [default: lab]"
    )
    parser.add_argument("--seed", type=SEED, help="seed of every random draw [default: 1]")
    parser.add_argument(
        "--people", type=COUNT, metavar="N", help="number of people walking about [default: 0]"
    )
    parser.add_argument(
        "--calibration", metavar="FILE",
        help="camera calibration JSON of the simulated lens [default: 800x600, 185 deg]"
    )


def sim_config_from_args(args: argparse.Namespace) -> tuple[SimConfig, CameraModel]:
    """The simulation config (file, then command-line overrides) and the simulated camera.

    The camera sits at the robot's mount (the file's ``[camera.mount]``), as on the
    robot the same file configures.

    Raises:
        ConfigError: a bad config file or value.
        CalibrationError: a bad camera file.
    """
    config = load_sim_config(args.config, load_config(args.config).camera.mount)
    overrides: dict[str, object] = {}
    if args.world is not None:
        overrides["world"] = args.world
    if args.seed is not None:
        overrides["seed"] = args.seed
    if args.calibration is not None:
        overrides["camera_file"] = args.calibration
    if args.people is not None:
        overrides["people"] = dataclasses.replace(config.people, count=args.people)
    config = dataclasses.replace(config, **overrides)
    return config, load_camera(config.camera_file)


def parse_start(text: str) -> Pose2:
    """A ``--start`` value ``X,Y,YAW`` (m, m, degrees) as a floor-plan pose.

    Raises:
        argparse.ArgumentTypeError: not three finite numbers.
    """
    parts = text.split(",")
    try:
        x, y, yaw_deg = (float(part) for part in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r} is not X,Y,YAW (metres, metres, degrees)") from None
    if not all(math.isfinite(v) for v in (x, y, yaw_deg)):
        raise argparse.ArgumentTypeError(f"{text!r}: X, Y and YAW must be finite")
    return Pose2(x, y, math.radians(yaw_deg))


def start_pose(args: argparse.Namespace, world: World) -> Pose2 | None:
    """The robot's start from ``--start`` or ``--route-start`` (None: the world's own).

    Raises:
        InputError: ``--route-start`` names no route of ``world``.
    """
    if args.route_start is None:
        return args.start
    routes = {route.name: route for route in world.routes}
    if args.route_start not in routes:
        raise InputError("--route-start", f"world '{world.name}' has no route "
                         f"{args.route_start!r} (routes: {', '.join(routes) or 'none'})")
    return routes[args.route_start].start_pose()


def add_start_arguments(parser: argparse.ArgumentParser) -> None:
    """``--start X,Y,YAW`` and ``--route-start NAME`` (read by :func:`start_pose`)."""
    start = parser.add_mutually_exclusive_group()
    start.add_argument(
        "--start", type=parse_start, metavar="X,Y,YAW",
        help="where the robot starts: x and y on the floor plan, m, and its heading, degrees "
        "CCW from +x [default: the world's start]")
    start.add_argument(
        "--route-start", metavar="NAME",
        help="the robot starts where the world's route NAME starts, facing along it (a "
        "memory taught on that route localizes there)")


def place_at_start(args: argparse.Namespace, sim: Simulation) -> None:
    """Put the robot where ``--start`` or ``--route-start`` says (nowhere else when neither).

    Raises:
        InputError: no such route, or a start outside the world or on an obstacle (naming
            the option).
    """
    start = start_pose(args, sim.world)
    if start is None:
        return
    try:
        sim.place_robot(start)
    except ConfigError as error:
        option = "--start" if args.route_start is None else "--route-start"
        raise InputError(option, error.problem) from None
