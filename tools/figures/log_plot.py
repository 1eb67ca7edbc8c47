"""``vmnav log plot``: the paper-style figures of any robot log (matplotlib, Agg backend).

From the :data:`~shared.logs.topics.SERVO_STATE` messages of a finished MCAP file,
and the ``odom`` -> ``base_link`` transforms on :data:`~shared.logs.topics.TF` for the
distance driven, it writes into the output folder, each name prefixed with the log's
stem:

* ``<stem>-errors_vs_distance.png``: y and theta against the distance driven by the
  odometry, as filtered for the law and as estimated by the vision (cf. Courbon et
  al. 2008, Fig. 8); against time when the log has no odometry;
* ``<stem>-image_errors.png``: errImageMax and errPoints against time (cf. their Fig. 6);
* ``<stem>-matches.png``: matched points per frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np
import numpy.typing as npt

from shared.errors import InputError
from shared.logs import topics
from shared.logs.reader import LogMessage, log_info, read_messages

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # after matplotlib.use: the backend must be chosen first

FloatArray = npt.NDArray[np.float64]
PLOT_NAMES = ("errors_vs_distance", "image_errors", "matches")
"""The figures written, by name (files ``<stem>-<name>.png``)."""


@dataclass(frozen=True, eq=False)
class ServoSeries:
    """The servo state of a log as columns, one row per message (NaN where null).

    Attributes:
        t_s: (N,) time since the first message of the log's servo state, s.
        distance_m: (N,) odometry distance driven at each message, m, or None without
            odometry transforms in the log.
        y_m, theta_rad: (N,) filtered lateral and angular errors (the law's input).
        y_raw_m, theta_raw_rad: (N,) the vision's estimates (NaN in logs that lack them).
        err_image_max_px, err_points_px: (N,) errImageMax and errPoints, px.
        matches: (N,) matched points.
    """

    t_s: FloatArray
    distance_m: FloatArray | None
    y_m: FloatArray
    theta_rad: FloatArray
    y_raw_m: FloatArray
    theta_raw_rad: FloatArray
    err_image_max_px: FloatArray
    err_points_px: FloatArray
    matches: FloatArray


def servo_series(path: Path) -> ServoSeries:
    """Read the servo state and odometry of the log at ``path``.

    Raises:
        InputError: the file cannot be read, or has no servo state (one line naming
            the file and the topic).
    """
    info = log_info(path)
    if not any(t.topic == topics.SERVO_STATE and t.message_count for t in info.topics):
        present = ", ".join(t.topic for t in info.topics) or "none"
        raise InputError(path, f"no {topics.SERVO_STATE} messages, not a robot log "
                               f"(topics: {present})")
    states: list[LogMessage] = []
    odom_t: list[int] = []
    odom_xy: list[tuple[float, float]] = []
    for message in read_messages(path, (topics.SERVO_STATE, topics.TF)):
        if message.topic == topics.SERVO_STATE:
            states.append(message)
            continue
        for tf in message.data.get("transforms", ()):
            if (tf.get("parent_frame_id"), tf.get("child_frame_id")) == (topics.FRAME_ODOM,
                                                                         topics.FRAME_BASE):
                odom_t.append(message.clock_ns)
                odom_xy.append((tf["translation"]["x"], tf["translation"]["y"]))
    t_ns = np.array([m.clock_ns for m in states], np.int64)

    def column(name: str) -> FloatArray:
        return np.array([_number(m.data.get(name)) for m in states], np.float64)

    return ServoSeries(
        t_s=(t_ns - t_ns[0]) / 1e9,
        distance_m=_distance_at(t_ns, odom_t, odom_xy) if odom_t else None,
        y_m=column("lateral_error_m"), theta_rad=column("angular_error_rad"),
        y_raw_m=column("lateral_error_raw_m"), theta_raw_rad=column("angular_error_raw_rad"),
        err_image_max_px=column("err_image_max_px"), err_points_px=column("err_points_px"),
        matches=column("matched_points"))


def plot_log(path: Path, out: Path | None = None) -> list[Path]:
    """Write the figures of the log at ``path`` into ``out`` (default: the log's folder).

    Returns:
        The PNG files written, in :data:`PLOT_NAMES` order.

    Raises:
        InputError: the file cannot be read or has no servo state; ``out`` is not a
            folder or cannot be created.
    """
    path = Path(path)
    series = servo_series(path)
    out = path.parent if out is None else Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(out, f"cannot create the output folder: {e.strerror}") from None
    stem = path.name.removesuffix(".mcap")
    files = [out / f"{stem}-{name}.png" for name in PLOT_NAMES]
    _plot_errors(files[0], series)
    plot_image_errors(files[1], series.t_s, series.err_image_max_px, series.err_points_px)
    plot_matches(files[2], series.t_s, series.matches)
    return files


def _number(value: object) -> float:
    """A JSON number as float; NaN for null, a missing field or anything else."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    return math.nan


def _distance_at(t_ns: npt.NDArray[np.int64], odom_t: Sequence[int],
                 odom_xy: Sequence[tuple[float, float]]) -> FloatArray:
    """Odometry path length at the times ``t_ns``, m (interpolated, held at the ends)."""
    order = np.argsort(odom_t, kind="stable")
    times = np.asarray(odom_t, np.float64)[order]
    xy = np.asarray(odom_xy, np.float64)[order]
    driven = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    return np.interp(t_ns.astype(np.float64), times, driven)


def _plot_errors(path: Path, s: ServoSeries) -> None:
    x = s.t_s if s.distance_m is None else s.distance_m
    fig, (ax_y, ax_t) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    ax_y.plot(x, 100 * s.y_raw_m, ".", ms=2, color="0.6", label="vision estimate")
    ax_y.plot(x, 100 * s.y_m, lw=1.0, label="filtered (control law input)")
    ax_t.plot(x, np.degrees(s.theta_raw_rad), ".", ms=2, color="0.6", label="vision estimate")
    ax_t.plot(x, np.degrees(s.theta_rad), lw=1.0, label="filtered (control law input)")
    ax_y.set_ylabel("lateral error y (cm)")
    ax_t.set_ylabel("angular error theta (deg)")
    ax_t.set_xlabel("time (s)" if s.distance_m is None else "distance driven, odometry (m)")
    ax_y.legend(loc="best")
    ax_y.set_title("Errors to the next key image (cf. Courbon et al. 2008, Fig. 8)")
    save_figure(fig, path)


def plot_image_errors(path: Path, t_s: npt.ArrayLike, err_image_max_px: npt.ArrayLike,
                      err_points_px: npt.ArrayLike, switches_s: Sequence[float] = ()) -> None:
    """errImageMax and errPoints against time (cf. Courbon et al. 2008, Fig. 6).

    Args:
        path: the PNG.
        t_s, err_image_max_px, err_points_px: (N,) time, s, and the errors, px (inf or NaN:
            no matches, left blank).
        switches_s: times of key image switches, s, drawn as grey lines.
    """
    fig, ax = plt.subplots(figsize=(9, 4))
    for values, label in ((err_image_max_px, "errImageMax"), (err_points_px, "errPoints")):
        v = np.asarray(values, dtype=float)
        ax.plot(t_s, np.where(np.isfinite(v), v, np.nan), label=label)
    for t in switches_s:
        ax.axvline(t, color="0.85", lw=0.6, zorder=0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("image error (px)")
    ax.legend(loc="best")
    grey = "; grey: key image switches" if len(switches_s) else ""
    ax.set_title(f"Image errors to the next key image{grey} (cf. Courbon et al. 2008, Fig. 6)")
    save_figure(fig, path)


def plot_matches(path: Path, t_s: npt.ArrayLike, matches: npt.ArrayLike) -> None:
    """Matches with the next key image per frame against time, s."""
    fig, ax = plt.subplots(figsize=(9, 3.5))
    ax.plot(t_s, matches, ".", ms=2)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("matches with the next key image")
    ax.set_title("Matches per frame")
    save_figure(fig, path)


def save_figure(fig: plt.Figure, path: Path) -> None:
    """Write ``fig`` as a PNG and close it.

    Raises:
        InputError: the file cannot be written.
    """
    fig.tight_layout()
    try:
        fig.savefig(path, dpi=110)
    except OSError as e:
        raise InputError(path, f"cannot write: {e.strerror}") from None
    finally:
        plt.close(fig)
