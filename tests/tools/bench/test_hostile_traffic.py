"""``tools/bench/hostile_traffic.py``: its flood is all rejected by a signed vehicle, its FTP
part counts what it says, and (slow) a short flood against ``vmnav robot`` meets the
targets' mechanism: heartbeats both ways, no failsafe, nothing of the flood logged."""

from __future__ import annotations

import pytest

from shared.mavlink.dialect import make_codec
from shared.mavlink.signing import configure_signing
from tools.bench.hostile_traffic import (
    FLOODER_SYSTEM,
    flood_datagrams,
    measure_flood,
    measure_ftp,
)


def test_the_flood_is_garbage_unsigned_and_wrongly_signed() -> None:
    datagrams = flood_datagrams(seed=3, count=30)
    assert len(datagrams) == len(set(datagrams)) == 30
    open_vehicle, signed_vehicle = make_codec(1, 1), make_codec(1, 1)
    configure_signing(signed_vehicle, bytes(range(32)), 0, 0)
    opened = [m for d in datagrams for m in open_vehicle.parse(d, datagram=True)]
    assert len(opened) >= 20 and {m.get_srcSystem() for m in opened} == {FLOODER_SYSTEM}
    for data in datagrams:
        signed_vehicle.parse(data, datagram=True)
    assert signed_vehicle.verified_packets == 0


def test_ftp_part_counts_replies_and_keeps_the_cache_small() -> None:
    figures = measure_ftp(seed=0, peers=600)
    assert figures["ftp_replies_per_stranger_request"] == 1
    assert figures["ftp_replies_per_owner_burst"] == 32
    assert figures["ftp_cache_mb"] < 10


@pytest.mark.slow
def test_a_short_flood_leaves_the_station_in_control() -> None:
    figures = measure_flood(seed=0, seconds=6.0, flooders=1)
    assert figures["flood_datagrams_per_s"] > 0
    assert not figures["false_gcs_failsafe"]
    assert figures["heartbeat_hz_at_station"] > 0 and figures["heartbeat_hz_at_robot"] > 0
    assert figures["log_growth_rejected_mb"] < 0.01  # counts only, never the packets
