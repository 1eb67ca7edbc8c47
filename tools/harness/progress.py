"""Progress of long commands on the terminal (rich), and nothing when stderr is not one.

A command that takes more than a few seconds (a demo's repeat, a benchmark's seeds, a
ground station waiting for its robot) shows a bar or a status line on stderr while it
works. When stderr is a file or a pipe (CI, ``2> log``), the bar is off: the command's
own lines are the record there.
"""

from __future__ import annotations

import sys
from types import TracebackType
from typing import IO, TYPE_CHECKING

if TYPE_CHECKING:
    from rich.progress import Progress as RichProgress
    from rich.progress import TaskID


class Progress:
    """One task's bar: what it does, how far (of ``total``, or a status line without one).

    Args:
        description: what the task does, e.g. ``"repeat"``.
        total: the count it runs to; None: no bar, a spinner with the detail.
        stream: where to draw (default stderr); nothing is drawn unless it is a terminal.
    """

    def __init__(self, description: str, total: float | None = None,
                 stream: IO[str] | None = None) -> None:
        self._description = description
        self._total = total
        self._stream = sys.stderr if stream is None else stream
        self._progress: RichProgress | None = None
        self._task: TaskID | None = None

    @property
    def shown(self) -> bool:
        """A bar is drawn (the stream is a terminal)."""
        return self._progress is not None

    def __enter__(self) -> Progress:
        if not self._stream.isatty():
            return self
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )
        from rich.progress import Progress as RichProgress

        columns = ([SpinnerColumn(), TextColumn("{task.description}"),
                    TextColumn("{task.fields[detail]}"), TimeElapsedColumn()]
                   if self._total is None else
                   [TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TextColumn("{task.fields[detail]}"), TimeElapsedColumn(),
                    TimeRemainingColumn()])
        progress = RichProgress(*columns, console=Console(file=self._stream), transient=True)
        progress.start()
        self._task = progress.add_task(self._description, total=self._total, detail="")
        self._progress = progress
        return self

    def update(self, completed: float | None = None, detail: str = "") -> None:
        """Move the bar to ``completed`` (None: leave it) and show ``detail`` beside it."""
        if self._progress is not None and self._task is not None:
            self._progress.update(self._task, completed=completed, detail=detail)

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        if self._progress is not None:
            self._progress.stop()
        self._progress = self._task = None
