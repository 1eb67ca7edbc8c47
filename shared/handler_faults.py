"""HandlerFaults: exceptions of message handlers, counted per kind instead of ending a thread.

An I/O loop that hands received messages to handlers must outlive a handler's bug:
one hostile or unlucky packet must not end the thread that also sends heartbeats and
obeys the next HOLD (issue 15). The loop catches the exception, gives it to
:meth:`HandlerFaults.record`, drops what it was handling and goes on. A fault is a
bug, so the first of each kind goes to the log with its traceback; the same kind
again is only counted, so a peer repeating the packet cannot fill the log.

A kind is where it happened and the exception's class, e.g.
``"MISSION_ITEM: OverflowError"``. At most :data:`MAX_KINDS` kinds are kept apart;
later new kinds count under :data:`OTHER_KIND` (the kinds come from the code, so
the limit only matters if a caller puts peer-chosen text in ``where``).

Loops whose faults may be the peer's doing rather than a bug (an HTTP client hanging up)
log at WARNING without the traceback (``level``, ``traceback``). :meth:`record` may be
called from several threads.
"""

from __future__ import annotations

import logging
import threading

#: Kinds kept apart; further kinds count as :data:`OTHER_KIND`.
MAX_KINDS = 64
#: The kind that collects faults beyond :data:`MAX_KINDS` kinds.
OTHER_KIND = "other"


class HandlerFaults:
    """Counts of handler exceptions by kind, each kind logged once (module docstring).

    Args:
        logger: where the first fault of each kind goes.
        owner: names the loop in the log line, e.g. ``"vehicle"``.
        level: the log level of that line.
        traceback: whether the line carries the traceback.
    """

    def __init__(self, logger: logging.Logger, owner: str, *, level: int = logging.ERROR,
                 traceback: bool = True) -> None:
        self._logger = logger
        self._owner = owner
        self._level = level
        self._traceback = traceback
        self._lock = threading.Lock()
        self._counts: dict[str, int] = {}
        self.total = 0
        """Faults recorded so far."""

    def record(self, where: str, error: Exception) -> None:
        """Count ``error``, raised while handling ``where`` (e.g. a message type), and log
        it with its traceback if it is the first of its kind."""
        kind = f"{where}: {type(error).__name__}"
        with self._lock:
            if kind not in self._counts and len(self._counts) >= MAX_KINDS:
                kind = OTHER_KIND
            self.total += 1
            count = self._counts.get(kind, 0) + 1
            self._counts[kind] = count
        if count == 1:
            self._logger.log(self._level, "%s: %s: %s (this kind is only counted from now on)",
                             self._owner, kind, error,
                             exc_info=error if self._traceback else None)

    def counts(self) -> dict[str, int]:
        """Faults so far by kind, in the order the kinds first happened."""
        with self._lock:
            return dict(self._counts)
