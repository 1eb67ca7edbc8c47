"""Command-line options shared by the commands that build a simulated world."""

from __future__ import annotations

import argparse
import dataclasses

from robot.config import load_config
from shared.calibration import load_camera
from shared.camera_model import CameraModel
from sim.config import SimConfig, load_sim_config
from tools.harness.arg_types import COUNT, SEED


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
        "--camera", metavar="FILE", help="camera calibration JSON [default: 800x600, 185 deg]"
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
    if args.camera is not None:
        overrides["camera_file"] = args.camera
    if args.people is not None:
        overrides["people"] = dataclasses.replace(config.people, count=args.people)
    config = dataclasses.replace(config, **overrides)
    return config, load_camera(config.camera_file)
