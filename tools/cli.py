"""The ``vmnav`` command line.

Each subcommand lives in its own module under ``tools/`` with two functions:
``add_parser(subparsers)`` declares its arguments, ``run(args) -> int`` turns them
into config objects and calls package code that knows nothing about argparse: robot/,
ground/, sim/, shared/, or the packages of tools/ (``harness``: what wires two of
robot/, sim/ and ground/ together; ``bench``: the benchmarks; ``figures``: reports and
plots). Subcommand modules do not import each other, except that a command registers
its own nested subcommands' modules (``sim serve``, ``memory localize``, ``ground
memory``/``teach``/``params``). Heavy imports (OpenCV, pymunk) happen inside ``run``
so ``vmnav --help`` is fast.

A :class:`~shared.errors.VmnavError` prints as one line on stderr with exit code 1;
anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import importlib.metadata
import logging
import os
import signal
import sys
from collections.abc import Sequence
from typing import NoReturn

from shared.errors import VmnavError
from tools import (
    bench_cmd,
    calibrate,
    demo_cmd,
    ground_cmd,
    log_cmd,
    memory_cmd,
    pioneer_cmd,
    replay_cmd,
    robot_cmd,
    sim_cmd,
    sweep_cmd,
    teach_cmd,
    vision_cmd,
)

COMMANDS = (sim_cmd, calibrate, bench_cmd, memory_cmd, teach_cmd, demo_cmd, pioneer_cmd, robot_cmd,
            log_cmd, replay_cmd, ground_cmd, vision_cmd, sweep_cmd)


class _Parser(argparse.ArgumentParser):
    """argparse with a usage error in one line, as every other error of vmnav (the usage is
    one ``--help`` away); exit status 2, argparse's."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every working subcommand."""
    parser = _Parser(
        prog="vmnav",
        description="Visual teach-and-repeat navigation with a fisheye camera "
        "(Courbon et al. 2008).",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    parser.add_argument("--version", action="version",
                        version=f"%(prog)s {importlib.metadata.version('vmnav')}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in COMMANDS:
        module.add_parser(sub)
    _describe(parser)
    return parser


def _describe(parser: argparse.ArgumentParser) -> None:
    """Give every subcommand without a description its one-line help as one, so that each
    ``--help`` says what the command does."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {choice.dest: choice.help for choice in action._choices_actions}
            for name, subparser in action.choices.items():
                text = str(helps.get(name) or "")
                if not subparser.description and text:
                    subparser.description = text[:1].upper() + text[1:] + "."
                _describe(subparser)


#: Environment that keeps OpenCV's and FFmpeg's own warnings off the output (a camera URL
#: that does not open printed two lines of theirs before ours); set them to see them.
_QUIET_LIBRARIES = {"OPENCV_LOG_LEVEL": "ERROR", "OPENCV_FFMPEG_LOGLEVEL": "-8"}
#: Libraries whose INFO lines are their own business (matplotlib's "generated new
#: fontManager" on a first plot): warnings only, unless --verbose.
_QUIET_LOGGERS = ("matplotlib",)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``vmnav`` console script; returns the exit code."""
    for name, value in _QUIET_LIBRARIES.items():  # before anything imports cv2
        os.environ.setdefault(name, value)
    args = build_parser().parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.INFO,
        format="%(levelname)s %(name)s: %(message)s",
    )
    if not args.verbose:
        for name in _QUIET_LOGGERS:
            logging.getLogger(name).setLevel(logging.WARNING)
    # SIGTERM (a service manager, `kill`) unwinds like Ctrl-C: finally blocks close
    # logs and links; commands that need more install their own handler.
    signal.signal(signal.SIGTERM, _exit_on_sigterm)
    try:
        return int(args.run(args))
    except VmnavError as e:
        print(f"vmnav {args.command}: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"vmnav {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # the reader went away (``vmnav log info X | head``): not an error
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 (stdout stays open until exit)
        return 0


def _exit_on_sigterm(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)


if __name__ == "__main__":
    sys.exit(main())
