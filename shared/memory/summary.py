"""What a visual memory holds, as plain data and as text (``vmnav memory info``).

Spacing is the teach odometric distance between consecutive key images of a
path, m; key images per metre is its inverse mean (intervals per metre of path),
so a path of n key images over L metres has (n - 1) / L.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

from shared.memory.graph import VisualMemory


def memory_summary(memory: VisualMemory) -> dict[str, Any]:
    """Paths, key images, spacing, junctions and connectivity, JSON-ready.

    Returns:
        ``{"camera": {width_px, height_px, fov_deg}, "keyframe_count", "path_count",
        "length_m", "spacing_m": {mean, min, max} | None, "keyframes_per_m",
        "paths": [{id, name, keyframe_count, first_id, last_id, length_m,
        spacing_m, keyframes_per_m}], "junctions": [{from_id, to_id, matches,
        from_path_id, to_path_id}], "connectivity": {strongly_connected,
        component_count, unreachable_ids, not_reachable_from_main,
        cannot_reach_main}}``; lengths in m; ``spacing_m`` and
        ``keyframes_per_m`` are ``None`` where undefined (fewer than two key
        images, or zero length).
    """
    keyframes = memory.keyframes
    paths = []
    all_steps_m: list[float] = []
    for path in sorted(memory.paths.values(), key=lambda p: p.id):
        distances_m = [keyframes[i].distance_m for i in path.keyframe_ids]
        steps_m = np.diff(distances_m).tolist()
        all_steps_m += steps_m
        paths.append(
            {
                "id": path.id,
                "name": path.name,
                "keyframe_count": len(path.keyframe_ids),
                "first_id": path.keyframe_ids[0],
                "last_id": path.keyframe_ids[-1],
                "length_m": distances_m[-1],
                **_spacing(steps_m),
            }
        )
    report = memory.connectivity()
    return {
        "camera": {
            "width_px": memory.camera.width,
            "height_px": memory.camera.height,
            "fov_deg": memory.camera.fov_deg,
        },
        "keyframe_count": len(keyframes),
        "path_count": len(paths),
        "length_m": float(sum(p["length_m"] for p in paths)),
        **_spacing(all_steps_m),
        "paths": paths,
        "junctions": [
            {
                "from_id": j.from_id,
                "to_id": j.to_id,
                "matches": j.matches,
                "from_path_id": keyframes[j.from_id].path_id,
                "to_path_id": keyframes[j.to_id].path_id,
            }
            for j in memory.junctions
        ],
        "connectivity": {
            "strongly_connected": report.strongly_connected,
            "component_count": len(report.components),
            "unreachable_ids": list(report.unreachable),
            "not_reachable_from_main": list(report.not_reachable_from_main),
            "cannot_reach_main": list(report.cannot_reach_main),
        },
    }


def summary_text(summary: dict[str, Any]) -> str:
    """Human-readable lines for a :func:`memory_summary` result (no trailing newline)."""
    camera = summary["camera"]
    lines = [
        f"{summary['keyframe_count']} key images on {summary['path_count']} paths, "
        f"{summary['length_m']:.2f} m taught; camera {camera['width_px']}x{camera['height_px']} "
        f"px, {camera['fov_deg']:g} deg",
        f"spacing {_spacing_text(summary)}",
        "paths:",
    ]
    lines += [
        f"  {p['id']} {p['name']!r}: {p['keyframe_count']} key images "
        f"({p['first_id']}..{p['last_id']}), {p['length_m']:.2f} m, spacing {_spacing_text(p)}"
        for p in summary["paths"]
    ] or ["  none"]
    lines.append("junctions:")
    lines += [
        f"  {j['from_id']} (path {j['from_path_id']}) <-> {j['to_id']} (path {j['to_path_id']}), "
        f"{j['matches']} matches"
        for j in summary["junctions"]
    ] or ["  none"]
    connectivity = summary["connectivity"]
    if connectivity["strongly_connected"]:
        lines.append("strongly connected: yes")
    else:
        lines += [
            f"strongly connected: no ({connectivity['component_count']} components)",
            f"  not reachable from the main component: "
            f"{id_ranges(connectivity['not_reachable_from_main'])}",
            f"  cannot reach the main component: {id_ranges(connectivity['cannot_reach_main'])}",
        ]
    return "\n".join(lines)


def id_ranges(ids: Iterable[int]) -> str:
    """E.g. ``[0, 1, 2, 5, 7, 8]`` -> ``"0-2, 5, 7-8"``; ``"none"`` if empty."""
    runs: list[list[int]] = []
    for i in sorted(ids):
        if runs and i == runs[-1][1] + 1:
            runs[-1][1] = i
        else:
            runs.append([i, i])
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs) or "none"


def _spacing(steps_m: list[float]) -> dict[str, Any]:
    if not steps_m:
        return {"spacing_m": None, "keyframes_per_m": None}
    total_m = float(np.sum(steps_m))
    return {
        "spacing_m": {
            "mean": total_m / len(steps_m),
            "min": float(np.min(steps_m)),
            "max": float(np.max(steps_m)),
        },
        "keyframes_per_m": len(steps_m) / total_m if total_m > 0.0 else None,
    }


def _spacing_text(entry: dict[str, Any]) -> str:
    spacing = entry["spacing_m"]
    if spacing is None:
        return "n/a (no path has two key images)"
    per_m = entry["keyframes_per_m"]
    density = f"{per_m:.2f} key images/m" if per_m is not None else "no distance travelled"
    return (
        f"mean {spacing['mean']:.3f} m, min {spacing['min']:.3f} m, "
        f"max {spacing['max']:.3f} m ({density})"
    )
