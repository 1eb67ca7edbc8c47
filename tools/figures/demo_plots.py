"""The figures and the video of ``vmnav demo`` (matplotlib with the Agg backend, OpenCV).

* ``topdown.png``: the floor plan (walls, furniture), the taught paths, the route's
  reference and the repeated trajectory, and the objects moved since the teach
  (:mod:`sim.scene_change`);
* ``errors_vs_distance.png``: y and theta against the distance driven, true and
  estimated (as Fig. 8 of Courbon et al. 2008);
* ``image_errors.png``: errImageMax and errPoints against time (as their Fig. 6);
* ``matches.png``: matches with the next key image per frame;
* ``demo.mp4`` (:class:`VideoWriter`): the fisheye view with its corners and the
  servo state, beside the target key image and the top-down map with the trajectory so
  far.
"""

from __future__ import annotations

from collections.abc import Generator
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import matplotlib
import numpy as np
import numpy.typing as npt

from sim.config import SimConfig
from tools.figures.demo_report import following_errors, plan_references
from tools.figures.log_plot import plot_image_errors, plot_matches, save_figure
from tools.harness.demo import CycleSample, RepeatRun
from tools.harness.teach import TaughtMemory

if TYPE_CHECKING:
    from sim.renderer import RenderedFrame
    from sim.simulation import Simulation
    from sim.topdown import TopDownMap

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # after matplotlib.use: the backend must be chosen first
from matplotlib.axes import Axes
from matplotlib.patches import Polygon

#: Every n-th servo cycle becomes a video frame.
VIDEO_EVERY = 2
#: Map scale in the video, px per m.
_MAP_PX_PER_M = 20.0


def write_plots(out: Path, run: RepeatRun, taught: TaughtMemory) -> None:
    """Write the four PNG figures into ``out``."""
    _plot_topdown(out / "topdown.png", run, taught)
    _plot_errors(out / "errors_vs_distance.png", run, taught)
    _plot_image_errors(out / "image_errors.png", run)
    _plot_matches(out / "matches.png", run)


def _plot_topdown(path: Path, run: RepeatRun, taught: TaughtMemory) -> None:
    fig, ax = plt.subplots(figsize=(10, 7))
    _plot_floor_plan(ax, run)
    for path_id in taught.path_ids:
        ids = taught.memory.paths[path_id].keyframe_ids
        xy = np.array([taught.true_poses[k][:2] for k in ids])
        ax.plot(xy[:, 0], xy[:, 1], ".-", color="0.75", lw=1, ms=3)
    for i, reference in enumerate(plan_references(run, taught)):
        ax.plot(reference[:, 0], reference[:, 1], "o-", color="tab:blue", lw=1.5, ms=3,
                label="taught (route key images)" if i == 0 else None)
    _plot_moved_objects(ax, run)
    repeated = np.array([s.pose_w for s in run.samples]).reshape(-1, 3)
    ax.plot(repeated[:, 0], repeated[:, 1], color="tab:red", lw=1.2, label="repeated")
    ax.plot(*run.start_pose[:2], "g^", ms=10, label="start")
    ax.plot(*taught.true_poses[run.goal_id][:2], "k*", ms=14, label="goal key image")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best")
    ax.set_title("Taught paths and the repeated trajectory (ground truth)")
    save_figure(fig, path)


def _plot_floor_plan(ax: Axes, run: RepeatRun) -> None:
    """The repeat's world: walls (black) and furniture (grey)."""
    world = run.changed.world
    for k, wall in enumerate(world.walls):
        (x0, y0), (x1, y1) = wall.start, wall.end
        ax.plot([x0, x1], [y0, y1], color="k", lw=1.5, label=None if k else "walls")
    for k, corners in enumerate(world.furniture_corners()):
        ax.add_patch(Polygon(corners, closed=True, fc="0.85", ec="0.6",
                             label=None if k else "furniture"))


def _plot_moved_objects(ax: Axes, run: RepeatRun) -> None:
    """The objects moved since the teach: where they stood (dashed) and where they stand."""
    for k, (taught, now) in enumerate(run.changed.moved_footprints()):
        ax.add_patch(Polygon(taught, closed=True, fill=False, ls="--", ec="0.5",
                             label=None if k else "object as taught"))
        ax.add_patch(Polygon(now, closed=True, fc="tab:orange", alpha=0.6,
                             label=None if k else "moved object"))


def _plot_errors(path: Path, run: RepeatRun, taught: TaughtMemory) -> None:
    fig, (ax_y, ax_t) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    errors = following_errors(run, taught)
    if errors is not None:
        ax_y.plot(errors.distance_m, 100 * errors.lateral_m, label="true")
        ax_t.plot(errors.distance_m, np.degrees(errors.heading_rad), label="true")
        estimated = [s for s in run.samples if s.record.follow is not None]
        if estimated:
            steps = np.hypot(*np.diff(np.array([s.pose_w for s in estimated])[:, :2], axis=0).T)
            distance = np.concatenate([[0.0], np.cumsum(steps)])
            y = [_value(s.record.follow.y_m) if s.record.follow else np.nan for s in estimated]
            t = [_value(s.record.follow.theta_rad) if s.record.follow else np.nan
                 for s in estimated]
            ax_y.plot(distance, 100 * np.array(y), lw=0.8, label="estimated (next key image)")
            ax_t.plot(distance, np.degrees(np.array(t)), lw=0.8,
                      label="estimated (next key image)")
    ax_y.set_ylabel("lateral error y (cm)")
    ax_t.set_ylabel("angular error theta (deg)")
    ax_t.set_xlabel("distance driven (m)")
    ax_y.legend(loc="best")
    ax_y.set_title("Errors along the route (cf. Courbon et al. 2008, Fig. 8)")
    save_figure(fig, path)


def _plot_image_errors(path: Path, run: RepeatRun) -> None:
    seen = [(s.record.t_ns / 1e9, s.record.follow.vision.image_errors) for s in run.samples
            if s.record.follow is not None and s.record.follow.vision is not None]
    switches = [s.record.t_ns / 1e9 for s in run.samples
                if s.record.follow is not None and s.record.follow.switch is not None]
    plot_image_errors(path, [t for t, _ in seen], [e.err_image_max_px for _, e in seen],
                      [e.err_points_px for _, e in seen], switches)


def _plot_matches(path: Path, run: RepeatRun) -> None:
    seen = [(s.record.t_ns / 1e9, s.record.follow.vision.matches) for s in run.samples
            if s.record.follow is not None and s.record.follow.vision is not None]
    plot_matches(path, [t for t, _ in seen], [n for _, n in seen])


def _value(v: float | None) -> float:
    return np.nan if v is None else v


class VideoWriter:
    """``demo.mp4``: the fisheye view with its corners and the servo state, beside the
    target key image (above) and the top-down map with the trajectory so far (below),
    every ``VIDEO_EVERY`` cycles. H.264 (yuv420p, the index at the front of the file), which
    browsers play, by the FFmpeg that ``imageio-ffmpeg`` ships.

    Args:
        path: the MP4 file.
        taught: the memory's truth (the taught paths are drawn on the map) and its key
            images.
        sim_config: the frame period sets the video's frame rate.
        goal_id: the mission's goal key image, named in the overlay.
    """

    def __init__(self, path: Path, taught: TaughtMemory, sim_config: SimConfig,
                 goal_id: int) -> None:
        self._path = path
        self._taught = taught
        self._goal_id = goal_id
        self._fps = 1e9 / sim_config.frame_period_ns / VIDEO_EVERY
        self._writer: Generator[None, bytes, None] | None = None
        self._size: tuple[int, int] | None = None
        self._trail: list[tuple[float, float]] = []
        self._key_image_shown: tuple[int, npt.NDArray[np.uint8]] | None = None
        self._count = 0
        self._topdown: TopDownMap | None = None  # made at the first map
        self._paths_px: list[npt.NDArray[np.int32]] = []

    def add(self, sim: Simulation, frame: RenderedFrame, sample: CycleSample) -> None:
        """Draw one cycle (called by :func:`tools.harness.demo.repeat_in_sim`)."""
        self._trail.append(sample.pose_w[:2])
        self._count += 1
        if (self._count - 1) % VIDEO_EVERY:
            return
        view = self._live_view(frame, sample)
        height, width = view.shape[:2]
        side = (width // 2) & ~1, (height // 2) & ~1  # the right column: half size, even
        target = sample.record.target_key
        panel = np.zeros((side[1], side[0], 3), np.uint8)
        if target is not None:
            panel = cv2.cvtColor(cv2.resize(self._key_image(target), side), cv2.COLOR_GRAY2BGR)
            _label(panel, [f"target: key image {target}"], 0.6)
        image = np.hstack([view[: 2 * side[1]], np.vstack([panel, self._map(sim, frame, side)])])
        self._write(image)

    def _live_view(self, frame: RenderedFrame, sample: CycleSample) -> npt.NDArray[np.uint8]:
        view = cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR)
        record = sample.record
        follow = record.follow
        lines = [f"t {record.t_ns / 1e9:6.1f} s  {record.state.name}  goal {self._goal_id}"]
        if follow is not None:
            for x, y in follow.corners_xy.astype(int):
                cv2.circle(view, (int(x), int(y)), 3, (0, 200, 0), 1, cv2.LINE_AA)
            matches = follow.vision.matches if follow.vision is not None else 0
            lines.append(f"key image {record.target_key} ({record.target_number} of "
                         f"{len(record.targets)})  matches {matches}")
            if follow.y_m is not None and follow.theta_rad is not None:
                lines.append(f"y {100 * follow.y_m:+5.1f} cm  "
                             f"theta {np.degrees(follow.theta_rad):+5.1f} deg")
        _label(view, lines, 0.7)
        return view

    def _map(self, sim: Simulation, frame: RenderedFrame,
             size: tuple[int, int]) -> npt.NDArray[np.uint8]:
        """The top-down map with the taught paths and the trail, fitted into ``size``."""
        from sim.topdown import TopDownMap

        if self._topdown is None:
            self._topdown = TopDownMap(sim, _MAP_PX_PER_M)
            memory, poses = self._taught.memory, self._taught.true_poses
            self._paths_px = [self._topdown.canvas.px([poses[k][:2] for k in
                                                       memory.paths[path_id].keyframe_ids])
                              for path_id in self._taught.path_ids]
        canvas = self._topdown.canvas
        top = self._topdown.draw(sim, frame, self._taught.memory.camera.fov_deg)
        cv2.polylines(top, self._paths_px, False, (160, 160, 160), 1, cv2.LINE_AA)
        if len(self._trail) > 1:
            cv2.polylines(top, [canvas.px(self._trail)], False, (0, 0, 230), 2, cv2.LINE_AA)
        scale = min(size[0] / top.shape[1], size[1] / top.shape[0])
        fitted = cv2.resize(top, (max(1, round(top.shape[1] * scale)),
                                  max(1, round(top.shape[0] * scale))))
        out = np.full((size[1], size[0], 3), 255, np.uint8)
        out[: fitted.shape[0], : fitted.shape[1]] = fitted
        return out

    def _key_image(self, keyframe_id: int) -> npt.NDArray[np.uint8]:
        """The target's image, read once while it stays the target (one kept, not all)."""
        if self._key_image_shown is None or self._key_image_shown[0] != keyframe_id:
            self._key_image_shown = (keyframe_id,
                                     self._taught.memory.keyframe(keyframe_id).image)
        return self._key_image_shown[1]

    def _write(self, image: npt.NDArray[np.uint8]) -> None:
        import imageio_ffmpeg

        if self._writer is None:
            self._size = (image.shape[1], image.shape[0])
            # x264's "veryfast" on one thread: the encoder runs beside the simulation on a
            # 2-core machine (`make demo`'s repeat took 84 s with the default "medium" on
            # x264's own threads, 70 s so; the file is no larger).
            self._writer = imageio_ffmpeg.write_frames(
                str(self._path), self._size, pix_fmt_in="bgr24", fps=self._fps,
                codec="libx264", macro_block_size=2, ffmpeg_log_level="error",
                output_params=["-preset", "veryfast", "-threads", "1", "-movflags", "+faststart"])
            self._writer.send(None)
        self._writer.send(np.ascontiguousarray(image).tobytes())

    def close(self) -> None:
        """Finish the file."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None


def _label(image: npt.NDArray[np.uint8], lines: list[str], scale: float) -> None:
    """Yellow text lines at the top left of ``image`` (in place)."""
    for i, text in enumerate(lines):
        cv2.putText(image, text, (10, round(25 + 32 * scale * i + 8 * scale)),
                    cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 255, 255), 2, cv2.LINE_AA)
