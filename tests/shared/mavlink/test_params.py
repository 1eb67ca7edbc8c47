"""Parameter protocol: ParamClient (ground) against ParamServer (vehicle), through bytes."""

from __future__ import annotations

import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.config import MavlinkConfig
from shared.errors import ConfigError, LocalProtocolError
from shared.mavlink.dialect import make_codec, mavlink, to_float32
from shared.mavlink.params.gcs import (
    ParamClient,
    ParamOperation,
    ParamOperationFailed,
    ParamReceived,
    ParamSetDone,
    ParamsFetched,
)
from shared.mavlink.params.table import ParamSpec, ParamTable
from shared.mavlink.params.vehicle import ParamChanged, ParamRefused, ParamServer
from tests.shared.mavlink.link import GCS, VEHICLE, Endpoint, Link, events, of_type
from tools.bench.hostile_messages import random_message


def make_table(n_extra: int = 0) -> ParamTable:
    specs = [
        ParamSpec("CTL_SPEED", 0.2, 0.01, 1.0, "Forward speed, m/s"),
        ParamSpec("MIS_LOC_TRIES", 5, 1, 100, "Localization attempts", integer=True),
        ParamSpec("FS_GCS_ACTION", 0, 0, 1, "Ground link lost", choices=("hold", "continue")),
        ParamSpec("ABCDEFGHIJKLMNOP", -1.5, -10, 10, "A name of exactly 16 characters"),
    ]
    specs += [ParamSpec(f"EXTRA_{i}", i / 7, -100, 100, "filler") for i in range(n_extra)]
    return ParamTable(specs)


def make_link(table: ParamTable, config: MavlinkConfig | None = None, loss: float = 0.0,
              seed: int = 0) -> tuple[Link, ParamClient, ParamServer]:
    client = ParamClient(GCS, VEHICLE, config)
    server = ParamServer(table, VEHICLE, config)
    return Link(Endpoint(GCS, client), Endpoint(VEHICLE, server), loss, seed), client, server


def finish(link: Link, client: ParamClient, messages: list[mavlink.MAVLink_message],
           max_rounds: int = 50) -> list[object]:
    link.send(link.ground, messages)
    link.run(lambda: client.operation is None, max_rounds)
    return events(client)


def wire_values(table: ParamTable) -> dict[str, float]:
    return {name: to_float32(v) for name, v in table.values().items()}


def test_list_streams_every_value_paced_with_index_and_count() -> None:
    table = make_table()
    link, client, _ = make_link(table)
    assert finish(link, client, client.fetch_all(0)) == [ParamsFetched(wire_values(table))]
    values = of_type(link.ground.received, "PARAM_VALUE")
    assert [(v.param_index, v.param_count) for v in values] == [(i, 4) for i in range(4)]
    assert all(v.param_type == mavlink.MAV_PARAM_TYPE_REAL32 for v in values)
    assert values[3].param_id == "ABCDEFGHIJKLMNOP"
    assert link.now_ns == 3 * MavlinkConfig().param_stream_period_ns  # one every 20 ms


def test_get_by_name_and_read_by_index() -> None:
    table = make_table()
    link, client, _ = make_link(table)
    assert finish(link, client, client.get("MIS_LOC_TRIES", 0)) == [
        ParamReceived("MIS_LOC_TRIES", 5.0, 1, 4)]
    link.send(link.ground, [mavlink.MAVLink_param_request_read_message(1, 1, b"", 3)])
    link.deliver()
    assert link.ground.received[-1].param_id == "ABCDEFGHIJKLMNOP"


def test_set_changes_the_value_and_echoes_it() -> None:
    table = make_table()
    link, client, server = make_link(table)
    assert finish(link, client, client.set("CTL_SPEED", 0.35, 0)) == [
        ParamSetDone("CTL_SPEED", 0.35, to_float32(0.35), accepted=True)]
    assert events(server) == [ParamChanged("CTL_SPEED", to_float32(0.35), 0.2, GCS)]
    assert table.value("CTL_SPEED") == to_float32(0.35)
    # the same value again is echoed but changes nothing
    assert finish(link, client, client.set("CTL_SPEED", 0.35, link.now_ns))[0].accepted
    assert events(server) == []


@pytest.mark.parametrize(("name", "value", "problem"), [
    ("CTL_SPEED", 2.5, "2.5 is outside [0.01, 1]"),
    ("MIS_LOC_TRIES", 2.5, "2.5 is not a whole number"),
    ("FS_GCS_ACTION", 2, "2 is outside [0, 1]"),
])
def test_refused_set_echoes_the_value_in_force(name: str, value: float, problem: str) -> None:
    table = make_table()
    before = table.value(name)
    link, client, server = make_link(table)
    assert finish(link, client, client.set(name, value, 0)) == [
        ParamSetDone(name, value, to_float32(before), accepted=False)]
    assert events(server) == [ParamRefused(name, value, problem, GCS)]
    assert table.value(name) == before
    (error,) = of_type(link.ground.received, "PARAM_ERROR")
    assert (error.param_id, error.error) == (name, mavlink.MAV_PARAM_ERROR_VALUE_OUT_OF_RANGE)
    assert (error.target_system, error.target_component) == (255, 190)
    assert of_type(link.ground.received, "STATUSTEXT")[0].text == f"param {name}: {problem}"


def test_refusal_sends_param_error_before_the_echo() -> None:
    # MAVSDK resends a set whose echo carries another value; PARAM_ERROR first ends it.
    link, client, _ = make_link(make_table())
    finish(link, client, client.set("CTL_SPEED", 2.5, 0))
    assert [m.get_type() for m in link.ground.received] == [
        "PARAM_ERROR", "STATUSTEXT", "PARAM_VALUE"]


def test_bounds_sent_as_float32_are_accepted() -> None:
    table = ParamTable([ParamSpec("GAIN", 0.5, 0.1, 0.7, "a gain")])
    link, client, _ = make_link(table)
    assert finish(link, client, client.set("GAIN", 0.7, 0))[0].accepted
    assert finish(link, client, client.set("GAIN", 0.1, link.now_ns))[0].accepted


def test_unknown_names_fail_fast() -> None:
    link, client, server = make_link(make_table())
    for start in (client.get, lambda n, t: client.set(n, 1.0, t)):
        (failed,) = finish(link, client, start("NOPE", link.now_ns), max_rounds=0)
        assert isinstance(failed, ParamOperationFailed)
        assert (failed.name, failed.reason) == ("NOPE", "no such parameter")
    assert of_type(link.ground.received, "STATUSTEXT")[-1].text == "param NOPE: no such parameter"
    assert events(server) == []


def test_requests_for_another_vehicle_are_ignored_and_busy_client_refuses() -> None:
    link, client, _ = make_link(make_table())
    link.send(link.ground, [mavlink.MAVLink_param_request_list_message(2, 1),
                            mavlink.MAVLink_param_set_message(1, 7, b"CTL_SPEED", 0.5, 9)])
    link.deliver()
    assert link.ground.received == []
    client.fetch_all(0)
    with pytest.raises(LocalProtocolError, match="cannot start set while fetch all"):
        client.set("CTL_SPEED", 0.3, 0)


def test_client_gives_up_on_a_silent_vehicle() -> None:
    config = MavlinkConfig(param_retries=2)
    client = ParamClient(GCS, VEHICLE, config)
    link = Link(Endpoint(GCS, client), Endpoint(VEHICLE))
    assert finish(link, client, client.get("CTL_SPEED", 0)) == [ParamOperationFailed(
        ParamOperation.GET, "CTL_SPEED", "no PARAM_VALUE after 3 requests")]
    assert len(link.vehicle.received) == 3 and link.now_ns == 3 * config.param_timeout_ns


def test_fetch_re_reads_only_missing_indexes() -> None:
    table = make_table(n_extra=8)
    link, client, _ = make_link(table)
    link.drop_next["PARAM_VALUE"] = 3  # the first three streamed values are lost
    assert finish(link, client, client.fetch_all(0)) == [ParamsFetched(wire_values(table))]
    reads = of_type(link.vehicle.received, "PARAM_REQUEST_READ")
    assert sorted(r.param_index for r in reads) == [0, 1, 2]


@pytest.mark.parametrize("seed", range(40))
def test_fetch_all_survives_20_percent_loss(seed: int) -> None:
    table = make_table(n_extra=30)
    link, client, _ = make_link(table, MavlinkConfig(), loss=0.2, seed=seed)  # default retries
    assert finish(link, client, client.fetch_all(0), max_rounds=100) == [
        ParamsFetched(wire_values(table))]
    assert link.dropped > 0


@pytest.mark.parametrize("seed", range(10))
def test_set_survives_20_percent_loss(seed: int) -> None:
    table = make_table()
    link, client, _ = make_link(table, MavlinkConfig(), loss=0.2, seed=seed)
    (done,) = finish(link, client, client.set("MIS_LOC_TRIES", 9, 0))
    assert done == ParamSetDone("MIS_LOC_TRIES", 9.0, 9.0, accepted=True)


def test_table_refuses_bad_declarations() -> None:
    with pytest.raises(ValueError, match="1-16 printable ASCII"):
        ParamSpec("SEVENTEEN_CHARS_X", 0, 0, 1, "")
    with pytest.raises(ValueError, match="choices need min 0 and max 2"):
        ParamSpec("MODE", 0, 0, 1, "", choices=("a", "b", "c"))
    with pytest.raises(ValueError, match="parameter A is declared twice"):
        ParamTable([ParamSpec("A", 0, 0, 1, ""), ParamSpec("A", 0, 0, 1, "")])
    with pytest.raises(ConfigError, match=r"parameters: B: default 5 is outside \[0, 1\]"):
        ParamTable([ParamSpec("B", 5, 0, 1, "")])
    with pytest.raises(ConfigError, match="param C: no such parameter"):
        make_table().set("C", 0)


PARAM_REQUESTS = (mavlink.MAVLink_param_set_message, mavlink.MAVLink_param_request_read_message,
                  mavlink.MAVLink_param_request_list_message)


@settings(derandomize=True, max_examples=80, deadline=None)
@given(st.randoms(use_true_random=False), st.integers(1, 20))
def test_random_requests_never_raise_and_every_value_stays_in_its_range(
        rng: random.Random, count: int) -> None:
    table = make_table()
    server = ParamServer(table, VEHICLE)
    ground, vehicle = make_codec(255, 190), make_codec(1, 1)
    for i in range(count):
        msg = random_message(rng, rng.choice(PARAM_REQUESTS), VEHICLE)
        if isinstance(msg, mavlink.MAVLink_param_set_message) and rng.random() < 0.5:
            msg.param_id = rng.choice(list(table.values())).encode("ascii")
        (received,) = vehicle.parse(ground.pack(msg))
        now_ns = i * 100_000_000
        for out in server.handle_message(received, now_ns) + server.handle_timer(now_ns):
            ground.parse(vehicle.pack(out))
        events(server)
    for spec in table:
        assert spec.problem(table.value(spec.name)) is None, spec.name
