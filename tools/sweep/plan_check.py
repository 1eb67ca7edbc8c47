"""Refuse a plan that cannot run, before any case runs: each value of each axis is parsed
as its ``vmnav demo`` option, worlds and camera files are loaded, the routes looked up in
every world, the laws and speeds applied to the config, and every scene change fitted to
every world. The error names the plan entry at fault in one line.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from contextlib import contextmanager

from shared.errors import InputError
from tools.sweep.plan import AXES, SweepPlan

#: The axes saying what changed between teach and repeat (fitted to each world together).
CHANGE_AXES = ("lighting", "moved", "removed", "doors")


@contextmanager
def naming(where: str) -> Iterator[None]:
    """Re-raise an :class:`InputError` as one naming ``where`` (the plan entry) first."""
    try:
        yield
    except InputError as e:
        problem = e.problem if e.where == "options" else str(e)
        raise InputError(where, problem) from None


def check_plan(plan: SweepPlan) -> None:
    """Check every value of ``plan`` (see the module docstring).

    Raises:
        InputError: ``<plan>: [axes] NAME = VALUE: what is wrong`` (or ``[sweep] KEY``).
    """
    from robot.config import load_config
    from shared.calibration import load_camera
    from sim.world import load_world
    from tools.harness.demo import follow_config
    from tools.harness.repeat_args import parse_repeat_options, repeat_setup_from_args
    from tools.harness.scene_args import scene_change_from_args
    from tools.harness.teach import find_route

    shared = plan.shared_argv()
    with naming(f"{plan.source}: [sweep]"):
        parse_repeat_options(shared)
    with naming(f"{plan.source}: [sweep] config"):
        config = load_config(plan.config)
    axes = dict(plan.axes)
    for name, values in plan.axes:
        for value in values:
            if value is None:
                continue
            with naming(f"{plan.source}: [axes] {name} = {value!r}"):
                args = parse_repeat_options([*shared, AXES[name][0], str(value)])
                if name == "world":
                    world = load_world(str(value))
                    for route in plan.routes or ():
                        find_route(world, route)
                elif name == "calibration":
                    load_camera(str(value))
                elif name in CHANGE_AXES:
                    scene_change_from_args(args)
                elif name in ("law", "speed_m_s"):
                    follow_config(config, args.law, plan.max_omega_deg, args.speed)
    names = [name for name in CHANGE_AXES if name in axes]
    for world in axes.get("world", (None,)):
        for combination in itertools.product(*(axes[name] for name in names)):
            argv = list(shared)
            entry = []
            for name, value in zip(names, combination, strict=True):
                if value is not None:
                    argv += [AXES[name][0], str(value)]
                    entry.append(f"{name} = {value!r}")
            if world is not None:
                argv += ["--world", str(world)]
            with naming(f"{plan.source}: [axes] world = {world or 'lab'!r}"
                        + "".join(f" with {e}" for e in entry)):
                repeat_setup_from_args(parse_repeat_options(argv))
