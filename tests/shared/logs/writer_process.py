"""A process that logs, for the tests that kill it or fill its disk.

``python -m tests.shared.logs.writer_process counter DIR``: logs a counter on
``/counter`` (foxglove.Log, message = the count) at 100 Hz plus 160x120 frames at
15 Hz, each stamped with CLOCK_MONOTONIC ns (the same clock in every process), and
prints ``started`` once the first is queued; runs until killed.

``python -m tests.shared.logs.writer_process fsize DIR LIMIT``: with files limited to
LIMIT bytes (RLIMIT_FSIZE, SIGXFSZ ignored, so writes past it fail with EFBIG as on a
full disk), logs 200 frames and 200 counters, closes, and prints the LogStats as JSON.
"""

from __future__ import annotations

import dataclasses
import json
import logging
import resource
import signal
import sys

import numpy as np

from shared.clock import WallClock
from shared.config import LogConfig
from shared.logs.writer import LogWriter

COUNTER_PERIOD_NS = 10_000_000
FRAME_EVERY = 7  # counter ticks per frame: about 15 frames/s


def run_counter(folder: str) -> None:
    clock = WallClock()
    frame = np.random.default_rng(0).integers(0, 255, (120, 160), dtype=np.uint8)
    writer = LogWriter(LogConfig(output_dir=folder), "killed")
    deadline_ns = clock.now_ns()
    count = 0
    while True:
        t_ns = clock.now_ns()
        writer.log_text(t_ns, "INFO", str(count), "writer_process", topic="/counter")
        if count % FRAME_EVERY == 0:
            writer.log_image(t_ns, "/camera/image/compressed", frame)
        if count == 0:
            print("started", flush=True)
        count += 1
        deadline_ns += COUNTER_PERIOD_NS
        clock.sleep_until_ns(deadline_ns)


def run_fsize(folder: str, limit_bytes: int) -> None:
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, resource.RLIM_INFINITY))
    rng = np.random.default_rng(0)
    config = LogConfig(output_dir=folder, chunk_size_bytes=16 * 1024, frame_rate_hz=1e6)
    with LogWriter(config, "full") as writer:
        for i in range(200):
            writer.log_image(i * 1000, "/camera/image/compressed",
                             rng.integers(0, 255, (120, 160), dtype=np.uint8))
            writer.log_text(i * 1000, "INFO", str(i), "writer_process", topic="/counter")
    stats = dataclasses.asdict(writer.stats())
    stats["files"] = [str(p) for p in stats["files"]]
    print(json.dumps(stats), flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "counter":
        run_counter(sys.argv[2])
    else:
        run_fsize(sys.argv[2], int(sys.argv[3]))
