"""``vmnav sim ...``: the simulator on its own."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from tools import sim_serve_cmd
from tools.harness.arg_types import FINITE
from tools.harness.scene_args import add_change_arguments, scene_change_from_args
from tools.harness.sim_args import add_sim_arguments, sim_config_from_args


def add_parser(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Register ``vmnav sim`` and its subcommands."""
    sim = subparsers.add_parser(
        "sim", help="the simulator: snapshot a world, serve an emulated Pioneer"
    )
    sim_sub = sim.add_subparsers(dest="sim_command", metavar="SUBCOMMAND", required=True)

    snap = sim_sub.add_parser(
        "snapshot",
        help="write the fisheye frame, a top-down map and the ground truth of one simulated view",
        description="Render one fisheye frame of a simulated world and write frame.png, map.png "
        "and snapshot.json (robot pose, visible landmarks with their pixel positions).",
    )
    add_sim_arguments(snap)
    snap.add_argument(
        "--out", required=True, type=Path, metavar="DIR", help="output folder (created)"
    )
    snap.add_argument(
        "--x", type=FINITE, metavar="M", help="robot x on the floor plan, m [default: world start]"
    )
    snap.add_argument(
        "--y", type=FINITE, metavar="M", help="robot y on the floor plan, m [default: world start]"
    )
    snap.add_argument(
        "--yaw",
        type=FINITE,
        metavar="DEG",
        help="robot heading, degrees CCW from +x [default: 0 with --x/--y]",
    )
    add_change_arguments(snap)
    snap.set_defaults(run=run_snapshot)
    sim_serve_cmd.add_parser(sim_sub)


def run_snapshot(args: argparse.Namespace) -> int:
    """Write the snapshot files and print a one-paragraph summary."""
    from shared.errors import ConfigError, InputError
    from shared.pose import Pose2
    from sim.snapshot import take_snapshot
    from sim.world import load_world
    from tools.harness.demo import changed_world

    change = scene_change_from_args(args)
    config, camera = sim_config_from_args(args)
    pose = None
    if args.x is not None or args.y is not None or args.yaw is not None:
        if args.x is None or args.y is None:
            raise InputError("--x/--y", "give both --x and --y to place the robot")
        pose = Pose2(args.x, args.y, math.radians(args.yaw) if args.yaw is not None else 0.0)
    world = load_world(config.world)
    if not change.is_none:  # as a repeat would see it, nothing moved onto the robot
        at = world.start if pose is None else pose
        world = changed_world(world, change, config.seed, (at.x_m, at.y_m)).world
    try:
        snap = take_snapshot(config, camera, args.out, pose, world)
    except ConfigError as error:
        if error.where != "robot pose":
            raise
        raise InputError("--x/--y/--yaw", error.problem) from None
    s = snap.summary
    p = s["pose_w"]
    print(
        f"world {s['world']} (seed {s['seed']}): robot at x={p['x_m']:.2f} m, y={p['y_m']:.2f} m, "
        f"yaw={p['yaw_deg']:.1f} deg; "
        f"{s['visible_landmarks']} of {s['landmarks_total']} landmarks visible"
    )
    for path in (snap.frame_path, snap.map_path, snap.json_path):
        print(f"  wrote {path}")
    return 0
