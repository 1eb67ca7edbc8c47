"""A latency list's summary as the web benchmark prints it."""

from __future__ import annotations

import statistics


def percentile_summary(values: list[float]) -> dict[str, float | int | None]:
    """``n``, ``median``, ``p95`` (the value at rank 0.95 n) and ``max`` of ``values``,
    rounded to 0.01 (None each when empty)."""
    if not values:
        return {"n": 0, "median": None, "p95": None, "max": None}
    ordered = sorted(values)
    return {"n": len(values), "median": round(statistics.median(ordered), 2),
            "p95": round(ordered[min(len(ordered) - 1, int(0.95 * len(ordered)))], 2),
            "max": round(ordered[-1], 2)}
