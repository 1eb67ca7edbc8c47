"""This process's memory figures from ``/proc/self/status`` (Linux), for benchmarks that
measure a child's peak: ``VmHWM`` is the peak of the process's own address space, unlike
``wait4``'s ``ru_maxrss``, which Linux carries over fork and exec from a big parent."""

from __future__ import annotations

from pathlib import Path


def status_kb(field: str) -> int:
    """``field`` of ``/proc/self/status`` (``"VmRSS"``, ``"VmHWM"``...), KiB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(f"{field}:"):
            return int(line.split()[1])
    raise RuntimeError(f"/proc/self/status has no {field}")
