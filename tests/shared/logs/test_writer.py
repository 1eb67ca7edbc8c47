"""LogWriter: what it writes reads back with the mcap reader; rotation, drops, file errors."""

from __future__ import annotations

import base64
import json
import logging
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer as McapWriter

from shared.config import LogConfig
from shared.logs import topics
from shared.logs.messages import FrameTransform
from shared.logs.reader import log_info, read_messages, read_metadata, recover
from shared.logs.writer import LogWriter
from shared.mavlink.dialect import make_codec, mavlink

ROOT = Path(__file__).resolve().parents[3]
MS = 1_000_000
#: Unix time at the clock's zero: 2025-11-14 16:00:00 UTC, ns.
EPOCH_NS = 1_763_136_000_000_000_000


def read_all(path: Path) -> list[tuple[str, str, str, int, int, dict]]:
    """(topic, schema name, encoding, log_time, publish_time, decoded) with the mcap reader."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        assert reader.get_summary() is not None  # finished: summary and index
        return [(c.topic, s.name, s.encoding, m.log_time, m.publish_time, json.loads(m.data))
                for s, c, m in reader.iter_messages()]


def textured(rng: np.random.Generator, shape: tuple[int, int] = (60, 80)) -> np.ndarray:
    return cv2.GaussianBlur(rng.integers(0, 255, shape, dtype=np.uint8), (0, 0), 2)


def test_round_trip_with_the_mcap_reader(tmp_path: Path, rng: np.random.Generator) -> None:
    image = textured(rng)
    vehicle = make_codec(1, 1)
    heartbeat = mavlink.MAVLink_heartbeat_message(10, 8, 0, 0, 4, 3)
    frame = vehicle.pack(heartbeat)
    t_ns = 1_500_000_123
    with LogWriter(LogConfig(output_dir=str(tmp_path)), "robot",
                   unix_offset_ns=EPOCH_NS) as writer:
        writer.add_metadata("run", {"route": "corridor", "mode": "repeat"})
        assert writer.log_image(t_ns, topics.CAMERA_IMAGE, image)
        assert writer.log_points(t_ns, topics.CAMERA_ANNOTATIONS, [[10.5, 20.5], [30.0, 40.0]],
                                 label="key 3: 2 matches")
        assert writer.log_json(t_ns, topics.SERVO_STATE, "vmnav.ServoState",
                               {"stamp_ns": t_ns, "lateral_error_m": float("nan")})
        assert writer.log_transform(t_ns, [FrameTransform.planar("odom", "base_link", 1, 2, 0)])
        assert writer.log_text(t_ns, "ERROR", "link lost", "robot")
        assert writer.log_mavlink(t_ns, heartbeat, "out")
    stats = writer.stats()
    assert (stats.queued, stats.written, stats.dropped, stats.lost, stats.errors) == (7, 7, 0,
                                                                                       0, 0)
    assert [p.name for p in stats.files] == ["robot-0001.mcap"]
    rows = {row[0]: row for row in read_all(stats.files[0])}
    assert {topic: (name, enc) for topic, name, enc, *_ in rows.values()} == {
        "/camera/image/compressed": ("foxglove.CompressedImage", "jsonschema"),
        "/camera/annotations": ("foxglove.ImageAnnotations", "jsonschema"),
        "/servo/state": ("vmnav.ServoState", "jsonschema"),
        "/tf": ("foxglove.FrameTransforms", "jsonschema"),
        "/log": ("foxglove.Log", "jsonschema"),
        "/mavlink/out/HEARTBEAT": ("mavlink.HEARTBEAT", "jsonschema"),
        "/mavlink/raw": ("mavlink.Raw", "jsonschema"),
    }
    # MCAP times and Foxglove timestamps in Unix time; our stamp_ns on the loop's clock.
    assert all(row[3] == row[4] == EPOCH_NS + t_ns for row in rows.values())
    picture = rows["/camera/image/compressed"][5]
    assert (picture["timestamp"], picture["frame_id"], picture["format"]) == (
        {"sec": 1_763_136_001, "nsec": 500_000_123}, "camera", "jpeg")
    decoded = cv2.imdecode(np.frombuffer(base64.b64decode(picture["data"]), np.uint8),
                           cv2.IMREAD_GRAYSCALE)
    assert decoded.shape == image.shape
    assert np.abs(decoded.astype(int) - image).mean() < 3  # JPEG at quality 85
    points = rows["/camera/annotations"][5]["points"][0]
    assert points["timestamp"] == picture["timestamp"]
    assert points["points"] == [{"x": 10.5, "y": 20.5}, {"x": 30.0, "y": 40.0}]
    assert rows["/servo/state"][5] == {"stamp_ns": t_ns, "lateral_error_m": None}
    assert rows["/log"][5]["level"] == 4
    assert rows["/log"][5]["timestamp"] == picture["timestamp"]
    assert {tf["timestamp"]["sec"] for tf in rows["/tf"][5]["transforms"]} == {1_763_136_001}
    assert rows["/mavlink/out/HEARTBEAT"][5]["type"] == 10
    raw = rows["/mavlink/raw"][5]
    parsed = make_codec(255, 190).parse(base64.b64decode(raw["frame"]))
    assert [m.get_type() for m in parsed] == ["HEARTBEAT"]
    assert base64.b64decode(raw["frame"]) == frame
    info = log_info(stats.files[0])
    assert (info.metadata, info.unix_offset_ns, info.start_ns) == (
        ("clock", "run"), EPOCH_NS, EPOCH_NS + t_ns)
    assert read_metadata(stats.files[0])["clock"] == {"unix_offset_ns": str(EPOCH_NS)}
    assert {(m.log_time_ns, m.clock_ns) for m in read_messages(stats.files[0])} == {
        (EPOCH_NS + t_ns, t_ns)}


def test_a_log_without_the_clock_record_reads_with_offset_0(tmp_path: Path) -> None:
    """Logs written before the clock record existed: their log_time is the clock's."""
    path = tmp_path / "old.mcap"
    with open(path, "wb") as f:
        old = McapWriter(f)
        old.start(profile="", library="vmnav shared.logs (mcap-python)")
        channel = old.register_channel("/cmd_vel", "json", old.register_schema(
            "vmnav.Command", "jsonschema", b'{"title": "vmnav.Command"}'))
        old.add_message(channel, log_time=5 * MS, data=b'{"stamp_ns": 5000000}',
                        publish_time=5 * MS)
        old.finish()
    info = log_info(path)
    assert (info.complete, info.unix_offset_ns, info.start_ns) == (True, None, 5 * MS)
    [message] = read_messages(path)
    assert (message.log_time_ns, message.clock_ns) == (5 * MS, 5 * MS)


def test_a_negative_offset_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="unix_offset_ns must be an integer >= 0, got -1"):
        LogWriter(LogConfig(output_dir=str(tmp_path)), unix_offset_ns=-1)


def test_frames_over_the_rate_are_skipped(tmp_path: Path, rng: np.random.Generator) -> None:
    image = textured(rng)
    jitter_ns = rng.integers(-10 * MS, 10 * MS, 60)
    with LogWriter(LogConfig(output_dir=str(tmp_path), frame_rate_hz=15.0)) as writer:
        at_30_hz = [writer.log_image(i * 33_333_333, "/a", image) for i in range(60)]
        at_15_hz = [writer.log_image(i * 66_666_667 + int(j) + 10 * MS, "/b", image)
                    for i, j in enumerate(jitter_ns)]
    assert sum(at_30_hz) == 30  # every other frame
    assert all(at_15_hz)  # camera jitter does not halve the rate
    assert writer.stats().skipped == 30


def test_lossless_frames_are_png_exactly_and_every_one(tmp_path: Path,
                                                        rng: np.random.Generator) -> None:
    images = [textured(rng) for _ in range(4)]
    with LogWriter(LogConfig(output_dir=str(tmp_path), frame_rate_hz=1.0)) as writer:
        assert all(writer.log_image(i * 33_333_333, "/a", image, lossless=True)
                   for i, image in enumerate(images))
    rows = read_all(writer.stats().files[0])
    assert [row[5]["format"] for row in rows] == ["png"] * 4
    decoded = [cv2.imdecode(np.frombuffer(base64.b64decode(row[5]["data"]), np.uint8),
                            cv2.IMREAD_GRAYSCALE) for row in rows]
    assert all(np.array_equal(a, b) for a, b in zip(decoded, images, strict=True))


def test_mavlink_packets_as_bytes_log_like_messages(tmp_path: Path) -> None:
    vehicle = make_codec(1, 1)
    heartbeat = mavlink.MAVLink_heartbeat_message(10, 8, 0, 0, 4, 3)
    packet = vehicle.pack(heartbeat)
    with LogWriter(LogConfig(output_dir=str(tmp_path / "bytes"))) as from_bytes:
        assert from_bytes.log_mavlink_packet(5, packet, "in")
        assert from_bytes.log_mavlink_packet(6, packet[:-3], "in")  # truncated: counted, lost
    with LogWriter(LogConfig(output_dir=str(tmp_path / "message"))) as from_message:
        from_message.log_mavlink(5, make_codec(0, 0).parse(packet)[0], "in")
    stats = from_bytes.stats()
    assert (stats.written, stats.lost) == (2, 1) and "not one MAVLink packet" in stats.last_error
    assert read_all(stats.files[0]) == read_all(from_message.stats().files[0])
    with pytest.raises(ValueError, match="direction must be 'in' or 'out'"):
        from_bytes.log_mavlink_packet(7, packet, "sideways")


def test_rotation_by_size_gives_several_valid_files(tmp_path: Path) -> None:
    config = LogConfig(output_dir=str(tmp_path), chunk_size_bytes=4096, rotate_size_bytes=16_000,
                       compression="none", queue_messages=1000)
    with LogWriter(config, "robot") as writer:
        writer.add_metadata("run", {"route": "loop"})
        for i in range(400):
            writer.log_json(i * MS, topics.CMD_VEL, "vmnav.Command",
                            {"stamp_ns": i * MS, "linear_x_m_s": 0.3, "angular_z_rad_s": 0.0,
                             "source": f"servo {i}"})
    files = writer.stats().files
    assert len(files) >= 3
    assert [p.name for p in files] == [f"robot-{n:04d}.mcap" for n in range(1, len(files) + 1)]
    infos = [log_info(p) for p in files]
    assert all(info.complete and info.metadata == ("clock", "run") for info in infos)
    assert sum(info.message_count for info in infos) == 400
    sequences = [m.sequence for p in files for m in read_messages(p)]
    assert sequences == list(range(1, 401))  # per-topic counter continues across files


def test_the_quota_stops_bulky_topics_once_and_keeps_the_rest(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    config = LogConfig(output_dir=str(tmp_path), chunk_size_bytes=4096, rotate_size_bytes=16_000,
                       compression="none", queue_messages=1000, max_bytes=30_000)
    packet = make_codec(1, 1).pack(mavlink.MAVLink_heartbeat_message(10, 8, 0, 0, 4, 3))
    with caplog.at_level(logging.WARNING), LogWriter(config, "robot") as writer:
        for i in range(300):
            writer.log_mavlink_packet(i * MS, packet, "in")
            writer.log_json(i * MS, topics.CMD_VEL, "vmnav.Command",
                            {"stamp_ns": i * MS, "linear_x_m_s": 0.3, "angular_z_rad_s": 0.0,
                             "source": "servo"})
    stats = writer.stats()
    messages = [m for p in stats.files for m in read_messages(p)]
    kept = sum(m.topic == topics.MAVLINK_RAW for m in messages)
    assert sum(m.topic == topics.CMD_VEL for m in messages) == 300
    assert 0 < kept < 300 and kept + stats.over_quota == 300 and stats.dropped == 0
    [warning] = [m.data for m in messages if m.topic == topics.LOG]
    assert warning["level"] == 3 and "quota of 30000 bytes reached" in warning["message"]
    assert sum("log quota" in r.getMessage() for r in caplog.records) == 1


def test_rotation_by_log_time_and_numbering_after_existing_files(tmp_path: Path) -> None:
    config = LogConfig(output_dir=str(tmp_path), rotate_period_ns=1_000_000_000)
    for _ in range(2):
        with LogWriter(config, "ground") as writer:
            for i in range(50):  # 10 Hz for 5 s
                writer.log_text(i * 100 * MS, "INFO", str(i), "ground")
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [f"ground-{n:04d}.mcap" for n in range(1, 11)]
    assert [log_info(tmp_path / n).message_count for n in names] == [10] * 10


def test_full_queue_drops_and_counts_without_blocking(tmp_path: Path,
                                                      rng: np.random.Generator) -> None:
    """JPEG-encoding 800x600 noise takes milliseconds per frame: a blocking queue would
    make 100 calls last far longer than the copies they cost."""
    images = [rng.integers(0, 255, (600, 800), dtype=np.uint8) for _ in range(4)]
    config = LogConfig(output_dir=str(tmp_path), queue_messages=1, frame_rate_hz=1e9,
                       jpeg_quality=100)
    with LogWriter(config) as writer:
        started = time.perf_counter()
        accepted = [writer.log_image(i, "/camera", images[i % 4]) for i in range(100)]
        elapsed_s = time.perf_counter() - started
    stats = writer.stats()
    assert elapsed_s < 0.25
    assert stats.dropped == accepted.count(False) > 50
    assert stats.queued == accepted.count(True) == stats.written
    assert log_info(stats.files[0]).message_count == stats.written


def test_unwritable_folder_is_reported_once_and_never_raised(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("")
    with caplog.at_level(logging.ERROR):
        writer = LogWriter(LogConfig(output_dir=str(blocker / "logs")))
        results = [writer.log_text(i, "INFO", str(i), "robot") for i in range(5)]
        stats = writer.close()
    assert all(results)  # queued; the loss is the writer thread's to count
    assert (stats.written, stats.lost, stats.errors, stats.files) == (0, 5, 1, ())
    assert stats.last_error is not None and str(blocker / "logs") in stats.last_error
    errors = [r for r in caplog.records if r.levelno == logging.ERROR]
    assert len(errors) == 1 and "not_a_folder" in errors[0].getMessage()


def test_disk_full_mid_run_keeps_the_caller_running(tmp_path: Path) -> None:
    """Files limited to 300 kB (RLIMIT_FSIZE) fail like a full disk: the process goes on,
    reports once, and what reached the file is recoverable."""
    done = subprocess.run(
        [sys.executable, "-m", "tests.shared.logs.writer_process", "fsize", str(tmp_path),
         "300000"], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    stats = json.loads(done.stdout)
    assert stats["errors"] == 1 and stats["lost"] > 0 and stats["written"] > 0
    assert "File too large" in stats["last_error"]
    assert done.stderr.count("ERROR") == 1
    report = recover(stats["files"][0], tmp_path / "recovered.mcap")
    assert 0 < report.messages <= stats["written"]


def test_close_is_idempotent_and_stops_the_thread(tmp_path: Path) -> None:
    before = threading.active_count()
    writer = LogWriter(LogConfig(output_dir=str(tmp_path)))
    writer.log_text(1, "INFO", "x", "robot")
    first = writer.close()
    assert writer.close() == first
    assert threading.active_count() == before
    assert not writer.log_text(2, "INFO", "late", "robot")
    assert writer.stats().dropped == 1


def test_bad_arguments_raise_at_the_call(tmp_path: Path) -> None:
    with LogWriter(LogConfig(output_dir=str(tmp_path))) as writer:
        with pytest.raises(ValueError, match=r"unknown log schema 'vmnav\.Nope'"):
            writer.log_json(0, "/x", "vmnav.Nope", {})
        with pytest.raises(ValueError, match="t_ns must be >= 0"):
            writer.log_text(-1, "INFO", "x", "robot")
        with pytest.raises(ValueError, match="pixels_xy: expected shape"):
            writer.log_points(0, "/p", np.zeros((3, 3)))
        with pytest.raises(ValueError, match="unknown log level"):
            writer.log_text(0, "LOUD", "x", "robot")
        with pytest.raises(ValueError, match="image: expected uint8 grey, got float64"):
            writer.log_image(0, "/c", np.zeros((4, 4)))


def test_a_message_that_cannot_be_encoded_is_counted_and_the_rest_written(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.ERROR), LogWriter(LogConfig(output_dir=str(tmp_path))) as writer:
        writer.log_json(0, topics.CMD_VEL, "vmnav.Command", {"source": {"not", "json"}})
        writer.log_json(1, topics.CMD_VEL, "vmnav.Command", {"source": "servo"})
    stats = writer.stats()
    assert (stats.written, stats.lost, stats.errors) == (1, 1, 1)
    assert stats.last_error is not None and "not JSON serializable" in stats.last_error
    assert [m.data for m in read_messages(stats.files[0])] == [{"source": "servo"}]
    assert len([r for r in caplog.records if r.levelno == logging.ERROR]) == 1
