"""``tools.harness.progress``: a bar on a terminal, nothing elsewhere."""

from __future__ import annotations

import io
import os
import pty
import select

from tools.harness.progress import Progress


def read_all(leader: int) -> str:
    """Everything written to the terminal so far (rich writes in several chunks)."""
    chunks = []
    while select.select([leader], [], [], 0.5)[0]:
        chunks.append(os.read(leader, 65536))
    return b"".join(chunks).decode("utf-8", "replace")


def test_nothing_is_drawn_when_the_stream_is_not_a_terminal() -> None:
    stream = io.StringIO()
    with Progress("repeat", 10, stream) as bar:
        bar.update(3, "key image 4")
        assert not bar.shown
    assert stream.getvalue() == ""


def test_a_bar_is_drawn_on_a_terminal_and_cleared_after() -> None:
    leader, follower = pty.openpty()
    try:
        with open(follower, "w", encoding="utf-8", closefd=False) as terminal:
            with Progress("bench follow", 4, terminal) as bar:
                assert bar.shown
                bar.update(1, "seed 2: repeating")
            terminal.flush()
        drawn = read_all(leader)
    finally:
        os.close(leader)
        os.close(follower)
    assert "bench follow" in drawn and "1/4" in drawn and "seed 2: repeating" in drawn


def test_a_status_line_without_a_total() -> None:
    leader, follower = pty.openpty()
    try:
        with open(follower, "w", encoding="utf-8", closefd=False) as terminal:
            with Progress("vehicle 1", None, terminal) as bar:
                bar.update(detail="FOLLOWING: key 4 -> 5 (goal 9)")
            terminal.flush()
        drawn = read_all(leader)
    finally:
        os.close(leader)
        os.close(follower)
    assert "vehicle 1" in drawn and "FOLLOWING: key 4 -> 5 (goal 9)" in drawn
