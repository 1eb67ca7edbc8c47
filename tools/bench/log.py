"""The CPU cost of field logging for the control loop (``vmnav bench log``).

A loop paced by the wall clock produces what the robot logs (800x600 grey frames at
15 frames/s with 150 matched points each, servo state, command and odometry
transform at 50 Hz) in alternating phases with logging off and on. The cost is
the process CPU time per wall second with logging minus without: everything the
logging adds, the writer thread's JPEG encoding, JSON, compression and writes
included. Phases alternate (off, on, off, on) so drifts in machine load hit both.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from shared.clock import NS_PER_S, WallClock
from shared.config import LogConfig
from shared.logs import topics
from shared.logs.messages import FrameTransform
from shared.logs.writer import LogWriter

FRAME_SHAPE = (600, 800)
"""Bench frames: (H, W), grey, the robot camera's size."""


def synthetic_frames(count: int, rng: np.random.Generator) -> list[npt.NDArray[np.uint8]]:
    """``count`` (600, 800) uint8 frames of blurred noise: JPEG sizes near a real scene's
    (about 100 KB at quality 85; pure noise would be 400 KB, a flat image 20 KB)."""
    frames = []
    for _ in range(count):
        texture = cv2.GaussianBlur(rng.uniform(0, 255, FRAME_SHAPE).astype(np.float32), (0, 0),
                                   2.5)
        texture = (texture - texture.mean()) * 4 + 128 + rng.normal(0, 3, FRAME_SHAPE)
        frames.append(np.clip(texture, 0, 255).astype(np.uint8))
    return frames


@dataclasses.dataclass
class _Phase:
    wall_ns: int = 0
    process_cpu_ns: int = 0
    loop_cpu_ns: int = 0


def bench_log(seconds: float = 8.0, frame_rate_hz: float = 15.0, telemetry_hz: float = 50.0,
              out_dir: Path | None = None, config: LogConfig | None = None,
              seed: int = 0) -> dict[str, Any]:
    """Measure logging's CPU cost side by side with logging off.

    Args:
        seconds: total wall time, s, split into four phases (off, on, off, on).
        frame_rate_hz: camera frames per second logged.
        telemetry_hz: servo state, command and transform messages per second (each).
        out_dir: where the logs go (a temporary folder, deleted after, when None).
        config: logging settings (``output_dir`` is replaced); defaults otherwise.
        seed: of the synthetic frames.

    Returns:
        JSON-ready figures; ``log_overhead_core_fraction`` is the headline (cores).
    """
    base = dataclasses.replace(config or LogConfig(), frame_rate_hz=frame_rate_hz)
    frames = synthetic_frames(8, np.random.default_rng(seed))
    with tempfile.TemporaryDirectory(prefix="vmnav-bench-log-") as tmp:
        folder = Path(out_dir) if out_dir is not None else Path(tmp)
        log_config = dataclasses.replace(base, output_dir=str(folder))
        phases: dict[bool, _Phase] = {False: _Phase(), True: _Phase()}
        enqueue_ns: list[int] = []
        totals = {"written": 0, "dropped": 0, "lost": 0, "files": 0, "bytes": 0}
        for logging_on in (False, True, False, True):
            # The phase's times count from its start, about now.
            writer = (LogWriter(log_config, "bench", unix_offset_ns=time.time_ns())
                      if logging_on else None)
            _run_phase(seconds / 4, frames, frame_rate_hz, telemetry_hz, writer,
                       phases[logging_on], enqueue_ns)
            if writer is not None:
                stats = writer.stats()
                totals["written"] += stats.written
                totals["dropped"] += stats.dropped
                totals["lost"] += stats.lost
                totals["files"] += len(stats.files)
                totals["bytes"] += sum(path.stat().st_size for path in stats.files)
    off, on = phases[False], phases[True]
    jpeg_sizes = [len(cv2.imencode(".jpg", f, [cv2.IMWRITE_JPEG_QUALITY, base.jpeg_quality])[1])
                  for f in frames]
    return {
        "seconds": seconds, "frame_rate_hz": frame_rate_hz, "telemetry_hz": telemetry_hz,
        "frame_shape": list(FRAME_SHAPE), "jpeg_quality": base.jpeg_quality,
        "compression": base.compression, "jpeg_kb_mean": statistics.fmean(jpeg_sizes) / 1e3,
        "process_core_fraction_off": off.process_cpu_ns / off.wall_ns,
        "process_core_fraction_on": on.process_cpu_ns / on.wall_ns,
        "log_overhead_core_fraction": on.process_cpu_ns / on.wall_ns
        - off.process_cpu_ns / off.wall_ns,
        "loop_thread_overhead_core_fraction": on.loop_cpu_ns / on.wall_ns
        - off.loop_cpu_ns / off.wall_ns,
        "enqueue_us_median": statistics.median(enqueue_ns) / 1e3 if enqueue_ns else None,
        "enqueue_us_max": max(enqueue_ns) / 1e3 if enqueue_ns else None,
        "messages_written": totals["written"], "dropped": totals["dropped"],
        "lost": totals["lost"], "files": totals["files"],
        "log_mb_per_s": totals["bytes"] / 1e6 / (on.wall_ns / NS_PER_S),
    }


def _run_phase(seconds: float, frames: list[npt.NDArray[np.uint8]], frame_rate_hz: float,
               telemetry_hz: float, writer: LogWriter | None, phase: _Phase,
               enqueue_ns: list[int]) -> None:
    """One phase: the loop at ``telemetry_hz`` for ``seconds``; with a writer, close it
    inside the phase so its draining counts too."""
    clock = WallClock()
    period_ns = round(NS_PER_S / telemetry_hz)
    frame_period_ns = round(NS_PER_S / frame_rate_hz)
    rng = np.random.default_rng(1)
    wall0, cpu0, loop0 = clock.now_ns(), time.process_time_ns(), time.thread_time_ns()
    end_ns = wall0 + round(seconds * NS_PER_S)
    deadline_ns = next_frame_ns = wall0
    tick = 0

    def timed(log: Callable[..., bool], *args: Any, **kwargs: Any) -> None:
        start = time.perf_counter_ns()
        log(*args, **kwargs)
        enqueue_ns.append(time.perf_counter_ns() - start)

    while deadline_ns < end_ns:
        t_ns = deadline_ns - wall0
        state = {"stamp_ns": t_ns, "mode": "repeat", "mission_state": "following",
                 "target_index": tick // 100, "key_image_id": tick // 100,
                 "lateral_error_m": 0.01 * np.sin(tick / 50), "angular_error_rad": 0.02,
                 "progress_m": 0.01 * tick, "v_m_s": 0.3, "omega_rad_s": 0.05,
                 "matched_points": 150, "inliers": 120, "lost": False, "switch_reason": None,
                 "err_image_max_px": 24.5, "err_points_px": 11.2,
                 "lateral_error_raw_m": 0.012 * np.sin(tick / 50),
                 "angular_error_raw_rad": 0.021, "progress_raw_m": 0.01 * tick,
                 "compute_ms": 9.5}
        command = {"stamp_ns": t_ns, "linear_x_m_s": 0.3, "angular_z_rad_s": 0.05,
                   "source": "servo"}
        odom = [FrameTransform.planar(topics.FRAME_ODOM, topics.FRAME_BASE, 0.006 * tick, 0.0,
                                      0.001 * tick)]
        frame = None
        if deadline_ns >= next_frame_ns:
            next_frame_ns += frame_period_ns
            frame = frames[tick % len(frames)]
            pixels = rng.uniform((0, 0), (FRAME_SHAPE[1], FRAME_SHAPE[0]), (150, 2))
        if writer is not None:
            timed(writer.log_json, t_ns, topics.SERVO_STATE, "vmnav.ServoState", state)
            timed(writer.log_json, t_ns, topics.CMD_VEL, "vmnav.Command", command)
            timed(writer.log_transform, t_ns, odom)
            if frame is not None:
                timed(writer.log_image, t_ns, topics.CAMERA_IMAGE, frame)
                timed(writer.log_points, t_ns, topics.CAMERA_ANNOTATIONS, pixels,
                      label=f"key {tick // 100}")
        tick += 1
        deadline_ns += period_ns
        clock.sleep_until_ns(deadline_ns)
    if writer is not None:
        writer.close()
    phase.wall_ns += clock.now_ns() - wall0
    phase.process_cpu_ns += time.process_time_ns() - cpu0
    phase.loop_cpu_ns += time.thread_time_ns() - loop0


def run(args: argparse.Namespace) -> int:
    """Print the logging benchmark's JSON (``vmnav bench log``)."""
    from shared.errors import InputError

    if not args.seconds > 0:
        raise InputError("--seconds", f"must be > 0, got {args.seconds}")
    load = [round(x, 2) for x in os.getloadavg()]
    result = bench_log(seconds=args.seconds, out_dir=args.out)
    print(json.dumps({"benchmark": "log", "load_average_at_start": load, **result}, indent=2))
    return 0
