"""``vmnav sweep report``: a sweep's results as Markdown with PNG plots.

What it says, over all cases and per value of each axis that varies:

* the success rate (goal reached) with its 95 % Wilson interval (:func:`wilson_interval`);
* the distance driven per failure (km per intervention: a case that did not reach its
  goal is one intervention) with its exact Poisson interval (:func:`distance_per_failure`);
* the lateral error's distribution: the empirical CDF of each case's lateral RMS and max
  after settling (``tools.figures.demo_report.track_metrics``);
* the safety layer, from the simulator's truth: contacts with a person the robot moved
  towards, people walking into it, waits for an obstacle; where the ``people`` axis
  varies, the lateral RMS with people minus the same case without;
* the worst cases (not reached first, then by lateral max) with the ``vmnav demo``
  command that reruns each alone, with video.

Crashed cases (status ``crashed``: the harness failed, not the robot) are left out of the
rates and listed with their error's last line.
"""

from __future__ import annotations

import math
import shlex
from collections.abc import Sequence
from pathlib import Path
from statistics import median
from typing import Any

from tools.sweep.plan import AXES
from tools.sweep.stats import distance_per_failure, empirical_cdf, wilson_interval

Row = dict[str, Any]
#: Worst cases listed.
WORST = 10
#: Where a rerun writes (``vmnav demo --out``), under the working directory.
RERUN_FOLDER = "out/rerun"


def rerun_command(row: Row) -> str:
    """The command that reruns a case alone, with video."""
    folder = shlex.quote(f"{RERUN_FOLDER}/{row['case_id']}")
    return " ".join(part for part in ("vmnav demo", row["options"], "--out", folder) if part)


def varying_axes(rows: Sequence[Row]) -> list[str]:
    """The axes with more than one value among ``rows``, in :data:`AXES` order."""
    return [name for name in AXES if len({repr(row.get(name)) for row in rows}) > 1]


def group_figures(rows: Sequence[Row]) -> dict[str, Any]:
    """Figures of a group of completed cases: runs, reached, rate and interval, distance,
    km per failure and interval, lateral RMS median, lateral max worst."""
    reached = sum(bool(row["reached_goal"]) for row in rows)
    rate = wilson_interval(reached, len(rows))
    km = sum(float(row["distance_m"] or 0.0) for row in rows) / 1000.0
    per_failure = distance_per_failure(km, len(rows) - reached)
    rms = [float(r["lateral_rms_m"]) for r in rows if r["lateral_rms_m"] is not None]
    worst = [float(r["lateral_max_m"]) for r in rows if r["lateral_max_m"] is not None]
    judged = [r for r in rows if r.get("contacts_moving") is not None]
    return {"runs": len(rows), "reached": reached, "rate": rate, "km": km,
            "km_per_failure": per_failure,
            "lateral_rms_median_m": median(rms) if rms else None,
            "lateral_max_worst_m": max(worst) if worst else None,
            "judged": len(judged),
            "contacts_moving": sum(int(r["contacts_moving"]) for r in judged),
            "contacts_still": sum(int(r["contacts_still"]) for r in judged),
            "obstacle_waits": sum(int(r["obstacle_waits"]) for r in judged)}


def people_rms_deltas(rows: Sequence[Row]) -> list[float]:
    """Lateral RMS with people minus without, m: each case with people paired with the case
    of the same other axes and no people (``people`` 0 or the default), where both reached
    the goal (a run cut short has the RMS of its start, not of the route)."""
    def others(row: Row) -> tuple[str, ...]:
        return tuple(repr(row.get(name)) for name in AXES if name != "people")

    def followed(row: Row) -> bool:
        return bool(row["reached_goal"]) and row["lateral_rms_m"] is not None

    without = {others(r): r["lateral_rms_m"] for r in rows
               if not r.get("people") and followed(r)}
    return [float(r["lateral_rms_m"]) - float(without[others(r)]) for r in rows
            if r.get("people") and followed(r) and others(r) in without]


def write_report(rows: Sequence[Row], plan: dict[str, Any], cases_planned: int,
                 out: Path) -> Path:
    """Write ``out/report.md`` and its plots (``out/*.png``); returns the report's path.

    Args:
        rows: the results table's rows.
        plan: the plan's data (``sweep.json``).
        cases_planned: the plan's case count (the report says how many are missing).
        out: the report's folder (exists).

    Raises:
        InputError: a file cannot be written.
    """
    from shared.atomic_file import write_text_atomic

    done = [row for row in rows if row["status"] == "ok"]
    crashed = [row for row in rows if row["status"] != "ok"]
    axes = varying_axes(done)
    lines = ["# Sweep report", "",
             f"{len(rows)} of {cases_planned} cases ran ({len(done)} completed, "
             f"{len(crashed)} crashed). Plan: "
             + ", ".join(f"{name} {_values_text(values)}"
                         for name, values in plan["axes"].items()) + ".",
             "", "Code: " + "; ".join(sorted({str(r["code_version"]) for r in rows})) + ".", ""]
    if done:
        lines += ["## All cases", "", *_table([("all", group_figures(done))]), ""]
    for name in axes:
        groups = _groups(done, name)
        lines += [f"## By {name}", "",
                  *_table([(value, group_figures(group)) for value, group in groups]), "",
                  f"![success rate by {name}](success_{name}.png) "
                  f"![lateral error by {name}](lateral_{name}.png)", ""]
        deltas = sorted(people_rms_deltas(done)) if name == "people" else []
        if deltas:
            lines += [f"Lateral RMS with people minus the same case without (both reached): median "
                      f"{_cm(median(deltas))}, largest {_cm(deltas[-1])} "
                      f"({len(deltas)} pairs).", ""]
        _plot_rates(out / f"success_{name}.png", name, groups)
        _plot_lateral(out / f"lateral_{name}.png", name, groups)
    lines += _worst_lines(done) + _crashed_lines(crashed)
    path = out / "report.md"
    write_text_atomic(path, "\n".join(lines) + "\n")
    return path


def _values_text(values: Sequence[object]) -> str:
    shown = ", ".join("default" if v is None else str(v) for v in values[:6])
    return f"[{shown}{', ...' if len(values) > 6 else ''}] ({len(values)})"


def _groups(rows: Sequence[Row], name: str) -> list[tuple[str, list[Row]]]:
    """Rows grouped by their value of axis ``name``, in the order the values appear."""
    groups: dict[str, list[Row]] = {}
    for row in rows:
        value = row.get(name)
        groups.setdefault("default" if value is None else str(value), []).append(row)
    return list(groups.items())


def _table(groups: list[tuple[str, dict[str, Any]]]) -> list[str]:
    lines = ["| value | runs | reached | success rate [95 % CI] | km driven | "
             "km per intervention [95 % CI] | lateral RMS median | lateral max worst | "
             "contacts: robot moving / person walking in | obstacle waits |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for value, f in groups:
        rate, per = f["rate"], f["km_per_failure"]
        # the safety columns count the cases judged (rows of sweeps run before: none)
        judged = f"{f['contacts_moving']} / {f['contacts_still']} | {f['obstacle_waits']}" + (
            f" ({f['judged']} of {f['runs']} runs judged)" if f["judged"] < f["runs"] else "")
        lines.append(
            f"| {value} | {f['runs']} | {f['reached']} | {100 * rate.value:.1f} % "
            f"[{100 * rate.low:.1f}, {100 * rate.high:.1f}] | {f['km']:.3f} | "
            f"{_km(per.value_km)} [{_km(per.low_km)}, {_km(per.high_km)}] | "
            f"{_cm(f['lateral_rms_median_m'])} | {_cm(f['lateral_max_worst_m'])} | "
            + (judged if f["judged"] else "- | -") + " |")
    return lines


def _km(value: float) -> str:
    return "∞" if math.isinf(value) else f"{value:.3g}"


def _cm(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f} cm"


def _worst_lines(done: Sequence[Row]) -> list[str]:
    def badness(row: Row) -> tuple[bool, float]:
        return (bool(row["reached_goal"]), -float(row["lateral_max_m"] or 0.0))

    lines = ["## Worst cases", "", "Not reached first, then by lateral max; each command "
             "reruns the case alone and writes its video (teaching its memory first).", ""]
    for row in sorted(done, key=badness)[:WORST]:
        outcome = "reached" if row["reached_goal"] else f"not reached ({row['reason']})"
        lines += [f"* `{row['case_id']}`: {outcome}, lateral max {_cm(row['lateral_max_m'])}, "
                  f"{row['lost_events']} LOST, {row['distance_m']} m",
                  f"  `{rerun_command(row)}`"]
    return [*lines, ""]


def _crashed_lines(crashed: Sequence[Row]) -> list[str]:
    if not crashed:
        return []
    lines = ["## Crashed cases", "", "The harness failed (tracebacks in results.csv).", ""]
    for row in crashed:
        last = str(row["error"] or "").strip().splitlines()[-1:] or ["no traceback"]
        lines += [f"* `{row['case_id']}`: {last[0]}", f"  `{rerun_command(row)}`"]
    return [*lines, ""]


def _plot_rates(path: Path, name: str, groups: list[tuple[str, list[Row]]]) -> None:
    """Success rate per value with its Wilson interval."""
    from tools.figures.log_plot import plt, save_figure

    rates = [group_figures(rows)["rate"] for _, rows in groups]
    fig, ax = plt.subplots(figsize=(max(4.0, 1.2 * len(groups)), 3.5))
    x = range(len(groups))
    values = [r.value for r in rates]
    ax.errorbar(x, values, yerr=[[v - r.low for v, r in zip(values, rates, strict=True)],
                                 [r.high - v for v, r in zip(values, rates, strict=True)]],
                fmt="o", capsize=5)
    ax.set_xticks(list(x), [value for value, _ in groups], rotation=20)
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel(name)
    ax.set_ylabel("goal reached (95 % Wilson)")
    ax.set_title(f"Success rate by {name}")
    save_figure(fig, path)


def _plot_lateral(path: Path, name: str, groups: list[tuple[str, list[Row]]]) -> None:
    """Empirical CDFs of each case's lateral RMS and max, one curve per value."""
    from tools.figures.log_plot import plt, save_figure

    fig, axes = plt.subplots(1, 2, figsize=(9, 3.5), sharey=True)
    for ax, key, label in ((axes[0], "lateral_rms_m", "lateral RMS"),
                           (axes[1], "lateral_max_m", "lateral max")):
        for value, rows in groups:
            found = [100 * float(r[key]) for r in rows if r[key] is not None]
            if found:
                x, y = empirical_cdf(found)
                ax.step(x, y, where="post", label=f"{value} ({len(found)})")
        ax.set_xlabel(f"{label} per case (cm)")
        ax.set_title(f"{label} by {name}")
        ax.legend(fontsize=7)
    axes[0].set_ylabel("fraction of cases")
    save_figure(fig, path)
