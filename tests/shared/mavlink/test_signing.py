"""MAVLink 2 signing between two real pymavlink codecs, and the timestamp bump."""

from __future__ import annotations

import pytest

from shared.clock import NS_PER_S, ManualClock
from shared.mavlink.dialect import MavlinkCodec, make_codec, mavlink
from shared.mavlink.signing import (
    EPOCH_UNIX_S,
    SigningClock,
    UnsignedPolicy,
    configure_signing,
    key_from_passphrase,
    signing_stats,
    timestamp_from_unix_ns,
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
