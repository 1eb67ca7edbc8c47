"""MAVLink 2 signing between two real pymavlink codecs, and the timestamp bump."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.clock import NS_PER_S, ManualClock
from shared.errors import InputError
from shared.mavlink.dialect import MavlinkCodec, make_codec, mavlink
from shared.mavlink.signing import (
    EPOCH_UNIX_S,
    MAX_TIMESTAMP,
    NEW_STREAM_WINDOW,
    SigningClock,
    SigningTimestamps,
    UnsignedPolicy,
    configure_signing,
    key_from_passphrase,
    restore_timestamps,
    signing_stats,
    timestamp_from_unix_ns,
    timestamps_from_json,
    timestamps_of,
    timestamps_to_json,
)

KEY = key_from_passphrase("vmnavsecret")
#: 2026-01-01 00:00 UTC, Unix ns: the wall clock in these tests.
NOW_UNIX_NS = 1_767_225_600 * NS_PER_S
NOW_TS = timestamp_from_unix_ns(NOW_UNIX_NS)


def heartbeat() -> mavlink.MAVLink_message:
    return mavlink.MAVLink_heartbeat_message(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID,
                                             0, 0, 0, 3)


def radio_status() -> mavlink.MAVLink_message:
    return mavlink.MAVLink_radio_status_message(200, 190, 100, 10, 5, 0, 0)


@pytest.fixture
def robot() -> tuple[MavlinkCodec, UnsignedPolicy]:
    codec = make_codec(1, 1)
    return codec, configure_signing(codec, KEY, link_id=0, timestamp=NOW_TS)


def signed_ground(key: bytes = KEY, timestamp: int = NOW_TS) -> MavlinkCodec:
    codec = make_codec(255, 190)
    configure_signing(codec, key, link_id=1, timestamp=timestamp)
    return codec


class TestSignedLink:
    def test_same_key_passes_both_ways(self, robot: tuple[MavlinkCodec, UnsignedPolicy]) -> None:
        codec, policy = robot
        ground = signed_ground()
        for _ in range(3):
            assert [m.get_type() for m in codec.parse(ground.pack(heartbeat()))] == ["HEARTBEAT"]
        assert [m.get_type() for m in ground.parse(codec.pack(heartbeat()))] == ["HEARTBEAT"]
        stats = signing_stats(codec)
        assert (stats.signed, stats.good, stats.bad, stats.rejected) == (3, 3, 0, 0)
        assert policy.rejected_total == 0

    def test_unsigned_is_dropped_and_counted(self,
                                             robot: tuple[MavlinkCodec, UnsignedPolicy]) -> None:
        codec, policy = robot
        assert codec.parse(make_codec(255, 190).pack(heartbeat())) == []
        assert policy.rejected == {mavlink.MAVLINK_MSG_ID_HEARTBEAT: 1}
        assert signing_stats(codec).rejected == 1 and codec.bad_packets == 1

    def test_wrong_key_is_dropped_and_counted(self,
                                              robot: tuple[MavlinkCodec, UnsignedPolicy]) -> None:
        codec, policy = robot
        assert codec.parse(signed_ground(key_from_passphrase("guess")).pack(heartbeat())) == []
        stats = signing_stats(codec)
        assert (stats.signed, stats.good, stats.bad, stats.rejected) == (1, 0, 1, 1)
        assert policy.rejected_total == 1

    def test_replayed_packet_is_dropped(self,
                                        robot: tuple[MavlinkCodec, UnsignedPolicy]) -> None:
        codec, _ = robot
        packet = signed_ground().pack(heartbeat())
        assert len(codec.parse(packet)) == 1
        assert codec.parse(packet) == []

    def test_wrong_key_packets_move_no_timestamp(
            self, robot: tuple[MavlinkCodec, UnsignedPolicy]) -> None:
        # The lockout of issue 15: pymavlink's generated check stores the stream's
        # timestamp before it checks the signature, so these 256 packets (the real
        # station's address, one per link id, timestamp 2**48-2) shut it out until restart.
        codec, _ = robot
        for link_id in range(256):
            spoof = make_codec(255, 190)
            configure_signing(spoof, key_from_passphrase("not the key"), link_id,
                              MAX_TIMESTAMP - 1)
            assert codec.parse(spoof.pack(heartbeat())) == []
        assert codec.signing.stream_timestamps == {} and codec.signing.timestamp == NOW_TS
        station = signed_ground()
        param_set = mavlink.MAVLink_param_set_message(1, 1, b"CTL_SPEED", 0.3,
                                                      mavlink.MAV_PARAM_TYPE_REAL32)
        assert [m.get_type() for m in codec.parse(station.pack(param_set))] == ["PARAM_SET"]
        assert signing_stats(codec).bad == 256

    @settings(derandomize=True, max_examples=200, deadline=None)
    @given(link_id=st.integers(0, 255), timestamp=st.integers(0, MAX_TIMESTAMP),
           signature=st.binary(min_size=6, max_size=6), system=st.integers(0, 255))
    def test_a_forged_signature_never_moves_a_timestamp(self, link_id: int, timestamp: int,
                                                        signature: bytes, system: int) -> None:
        codec = make_codec(1, 1)
        configure_signing(codec, KEY, 0, NOW_TS)
        codec.signing.stream_timestamps[(1, 255, 190)] = NOW_TS
        forger = make_codec(system, 190)
        configure_signing(forger, KEY, link_id, timestamp)
        packet = bytearray(forger.pack(heartbeat()))
        packet[-6:] = signature  # not covered by the CRC: the check gets to the signature
        assert codec.parse(bytes(packet)) == []
        assert codec.signing.stream_timestamps == {(1, 255, 190): NOW_TS}
        assert codec.signing.timestamp == NOW_TS

    def test_new_stream_window(self, robot: tuple[MavlinkCodec, UnsignedPolicy]) -> None:
        codec, _ = robot
        assert codec.parse(signed_ground(timestamp=NOW_TS - NEW_STREAM_WINDOW - 1)
                           .pack(heartbeat())) == []
        assert len(codec.parse(signed_ground(timestamp=NOW_TS - NEW_STREAM_WINDOW)
                               .pack(heartbeat()))) == 1

    def test_policy_lets_listed_ids_through_unsigned(self) -> None:
        codec = make_codec(1, 1)
        policy = configure_signing(codec, KEY, 0, NOW_TS,
                                   UnsignedPolicy({mavlink.MAVLINK_MSG_ID_RADIO_STATUS}))
        radio = make_codec(51, 68)
        assert [m.get_type() for m in codec.parse(radio.pack(radio_status()))] == ["RADIO_STATUS"]
        assert codec.parse(radio.pack(heartbeat())) == []
        assert signing_stats(codec).unsigned_accepted == 1 and policy.rejected_total == 1

    def test_bad_arguments(self) -> None:
        with pytest.raises(ValueError, match="31 bytes"):
            configure_signing(make_codec(1, 1), KEY[:31], 0, 0)
        with pytest.raises(ValueError, match="link_id 256"):
            configure_signing(make_codec(1, 1), KEY, 256, 0)
        with pytest.raises(ValueError, match="timestamp -1"):
            configure_signing(make_codec(1, 1), KEY, 0, -1)


class TestSigningClock:
    def test_timestamp_units(self) -> None:
        assert timestamp_from_unix_ns(EPOCH_UNIX_S * NS_PER_S) == 0
        assert timestamp_from_unix_ns(EPOCH_UNIX_S * NS_PER_S + 1_000_000_000) == 100_000
        assert timestamp_from_unix_ns(0) == 0

    def test_bump_to_wall_clock_and_never_back(self, manual_clock: ManualClock) -> None:
        codec = make_codec(1, 1)
        configure_signing(codec, KEY, 0, timestamp=5)
        clock = SigningClock(codec, unix_offset_ns=NOW_UNIX_NS)
        assert clock.get_timer() is None
        assert clock.handle_timer(manual_clock.now_ns()) == NOW_TS
        assert clock.get_timer() == 10 * NS_PER_S
        manual_clock.advance(10.0)
        assert clock.handle_timer(manual_clock.now_ns()) == NOW_TS + 1_000_000
        codec.signing.timestamp += 5_000_000  # a peer's newer timestamp was adopted
        assert clock.handle_timer(manual_clock.now_ns()) == NOW_TS + 6_000_000

    def test_idle_sender_is_rejected_until_bumped(self, manual_clock: ManualClock) -> None:
        # The ground stayed idle 75 s: its timestamp is 75 s behind the robot's, and a
        # new stream more than 60 s old is refused (mavlink-vehicle.md §1.9).
        codec = make_codec(1, 1)
        configure_signing(codec, KEY, 0, timestamp=NOW_TS)
        ground = signed_ground(timestamp=NOW_TS - 75 * 100_000)
        assert codec.parse(ground.pack(heartbeat())) == []
        SigningClock(ground, unix_offset_ns=NOW_UNIX_NS).handle_timer(manual_clock.now_ns())
        assert len(codec.parse(ground.pack(heartbeat()))) == 1

    def test_period_must_be_positive(self) -> None:
        with pytest.raises(ValueError, match="period_ns"):
            SigningClock(make_codec(1, 1), 0, period_ns=0)


class TestTimestampsKept:
    def test_a_restored_codec_refuses_what_the_old_one_accepted(self) -> None:
        before = make_codec(1, 1)
        configure_signing(before, KEY, 0, NOW_TS)
        station = signed_ground(timestamp=NOW_TS + 500)
        captured = [station.pack(heartbeat()) for _ in range(3)]
        assert all(len(before.parse(packet)) == 1 for packet in captured[:2])
        kept = timestamps_of(before)
        assert kept.streams == {(1, 255, 190): NOW_TS + 501}
        after = make_codec(1, 1)  # a restart, its clock a little behind
        configure_signing(after, KEY, 0, NOW_TS - 100)
        restore_timestamps(after, kept)
        assert after.signing.timestamp == NOW_TS + 501
        assert all(after.parse(packet) == [] for packet in captured[:2])  # replays
        assert len(after.parse(captured[2])) == 1  # never accepted before: fresh

    def test_restore_never_lowers(self) -> None:
        codec = make_codec(1, 1)
        configure_signing(codec, KEY, 0, NOW_TS)
        codec.signing.stream_timestamps[(1, 255, 190)] = NOW_TS
        restore_timestamps(codec, SigningTimestamps(5, {(1, 255, 190): 7, (2, 255, 190): 9}))
        assert timestamps_of(codec) == SigningTimestamps(
            NOW_TS, {(1, 255, 190): NOW_TS, (2, 255, 190): 9})

    def test_json_round_trip(self, tmp_path: Path) -> None:
        kept = SigningTimestamps(NOW_TS, {(1, 255, 190): NOW_TS - 3, (0, 2, 1): MAX_TIMESTAMP})
        document = json.loads(timestamps_to_json(kept))
        assert timestamps_from_json(tmp_path, document) == kept

    @pytest.mark.parametrize(("document", "problem"), [
        ([], "want"),
        ({"timestamp": 1}, "want"),
        ({"timestamp": -1, "streams": []}, "timestamp -1"),
        ({"timestamp": True, "streams": []}, "timestamp True"),
        ({"timestamp": 2**48, "streams": []}, "timestamp 281474976710656"),
        ({"timestamp": 1, "streams": {}}, "streams is not a list"),
        ({"timestamp": 1, "streams": [[1, 2, 3]]}, r"streams\[0\]"),
        ({"timestamp": 1, "streams": [[0, 1, 1, 5], [256, 1, 1, 5]]}, r"streams\[1\]"),
        ({"timestamp": 1, "streams": [[0, 1, 1, 1.5]]}, r"streams\[0\]"),
    ])
    def test_bad_documents(self, tmp_path: Path, document: object, problem: str) -> None:
        with pytest.raises(InputError, match=problem):
            timestamps_from_json(tmp_path / "t.json", document)
