"""The README and docs/: every relative link leads to a file, and every ``vmnav`` command
they show is one the command line takes (its options exist and its values parse)."""

from __future__ import annotations

import argparse
import re
import shlex
from collections.abc import Iterator
from pathlib import Path

import pytest

from tools.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: ``[text](target)`` with a relative target (not a URL, not an anchor alone).
LINK = re.compile(r"\]\((?!https?://|#|mailto:)([^)\s]+)\)")
#: Fenced code blocks.
FENCE = re.compile(r"```[a-z]*\n(.*?)```", re.S)


def shown_commands(text: str) -> list[str]:
    """The ``vmnav ...`` command lines of ``text``'s code blocks (continuations joined,
    comments and a trailing ``&`` removed; pipelines and ``&&`` chains split). In a block
    with ``$`` prompts only the prompted lines are commands (the others are their output);
    a synopsis with ``[--option ...]`` or an elided command (``...``) is not one."""
    commands = []
    for block in FENCE.findall(text):
        lines = re.sub(r"\\\n\s*", " ", block).splitlines()
        if any(line.startswith("$ ") for line in lines):
            lines = [line.removeprefix("$ ") for line in lines if line.startswith("$ ")]
        for line in lines:
            if " [-" in line or "..." in line:  # a synopsis, an elided command
                continue
            for part in re.split(r"\s*(?:&&|\|)\s*", line.strip()):
                part = re.sub(r"\s+#\s.*$", "", part).strip().removesuffix("&").strip()
                if part.startswith("vmnav "):
                    commands.append(part)
    return commands


COMMANDS = sorted({(doc.name, command) for doc in DOCS
                   for command in shown_commands(doc.read_text())})


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_relative_links_lead_to_files(doc: Path) -> None:
    missing = [target for target in LINK.findall(doc.read_text())
               if not (doc.parent / target.split("#")[0]).exists()]
    assert missing == []


def test_the_docs_show_commands() -> None:
    assert len([c for doc, c in COMMANDS if doc == "README.md"]) > 10


@pytest.mark.parametrize(("doc", "command"), COMMANDS, ids=[f"{d}: {c}" for d, c in COMMANDS])
def test_every_command_shown_parses(doc: str, command: str,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    argv = shlex.split(command)[1:]
    try:
        build_parser().parse_args(argv)
    except SystemExit as exited:  # --help and --version exit 0; a usage error exits 2
        assert exited.code == 0, capsys.readouterr().err


def test_every_subcommand_says_what_it_does() -> None:
    def walk(parser: argparse.ArgumentParser, path: str) -> Iterator[str]:
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, subparser in action.choices.items():
                    if not subparser.description:
                        yield f"{path} {name}"
                    yield from walk(subparser, f"{path} {name}")

    assert list(walk(build_parser(), "vmnav")) == []
