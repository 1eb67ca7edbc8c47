"""Mission protocol: MissionClient (ground) against MissionServer (vehicle), through bytes."""

from __future__ import annotations

import math
import random
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shared.config import MavlinkConfig
from shared.errors import LocalProtocolError
from shared.mavlink.address import Address
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.mission.gcs import (
    ClearDone,
    DownloadDone,
    DownloadInvalid,
    MissionClient,
    Operation,
    OperationRefused,
    OperationTimedOut,
    UploadDone,
)
from shared.mavlink.mission.goal import Goal, goals_from_items
from shared.mavlink.mission.items import (
    KNOWN_FRAMES,
    MissionItem,
    MissionRefusal,
    item_from_message,
)
from shared.mavlink.mission.vehicle import (
    CurrentSet,
    MissionCleared,
    MissionRejected,
    MissionServer,
    MissionUploaded,
    UploadFailed,
)
from tests.shared.mavlink.link import GCS, VEHICLE, Endpoint, Link, events, of_type
from tools.bench.hostile_messages import HANDLED_MESSAGES, random_message

KNOWN_KEYS = set(range(100))


def refuse_unknown_keys(items: tuple[MissionItem, ...]) -> MissionRefusal | None:
    """The robot's kind of hook: goals must decode and name key images the memory holds."""
    goals = goals_from_items(items)
    if isinstance(goals, MissionRefusal):
        return goals
    for seq, goal in enumerate(goals):
        if goal.key_image_id not in KNOWN_KEYS:
            return MissionRefusal(mavlink.MAV_MISSION_INVALID_PARAM1,
                                  f"item {seq}: no key image {goal.key_image_id}")
    return None


def goal_items(*keys: int) -> tuple[MissionItem, ...]:
    return tuple(Goal(k, goal_image_id=k % 3).to_item() for k in keys)


def make_link(config: MavlinkConfig | None = None, loss: float = 0.0, seed: int = 0,
              ) -> tuple[Link, MissionClient, MissionServer]:
    client = MissionClient(GCS, VEHICLE, config)
    server = MissionServer(VEHICLE, config, validate=refuse_unknown_keys)
    return Link(Endpoint(GCS, client), Endpoint(VEHICLE, server), loss, seed), client, server


def upload(link: Link, client: MissionClient, items: tuple[MissionItem, ...]) -> None:
    link.send(link.ground, client.upload(items, link.now_ns))
    link.run(lambda: client.operation is None)


def test_upload_then_download_round_trips_n_goal_items() -> None:
    link, client, server = make_link()
    items = goal_items(5, 17, 42, 3, 99, 0, 12)
    upload(link, client, items)
    assert events(client) == [UploadDone(7)]
    assert events(server) == [MissionUploaded(items, GCS)]
    assert server.items == items and server.current_seq == 0
    assert len(of_type(link.vehicle.received, "MISSION_ITEM_INT")) == 7

    link.send(link.ground, client.download(link.now_ns))
    link.run(lambda: client.operation is None)
    assert events(client) == [DownloadDone(items)]
    assert goals_from_items(items) == tuple(Goal(k, k % 3) for k in (5, 17, 42, 3, 99, 0, 12))
    downloaded = of_type(link.ground.received, "MISSION_ITEM_INT")
    assert [m.current for m in downloaded] == [1, 0, 0, 0, 0, 0, 0]
    assert all((m.target_system, m.target_component) == (255, 190) for m in downloaded)
    assert of_type(link.vehicle.received, "MISSION_ACK")[-1].type == mavlink.MAV_MISSION_ACCEPTED


def test_rejected_mission_keeps_the_old_one() -> None:
    link, client, server = make_link()
    old = goal_items(1, 2)
    upload(link, client, old)
    events(client), events(server)
    upload(link, client, goal_items(3, 500, 4))
    refused = OperationRefused(Operation.UPLOAD, mavlink.MAV_MISSION_INVALID_PARAM1)
    assert events(client) == [refused] and refused.result_name == "MAV_MISSION_INVALID_PARAM1"
    (rejected,) = events(server)
    assert isinstance(rejected, MissionRejected)
    assert rejected.refusal.reason == "item 1: no key image 500"
    assert server.items == old
    (notice,) = of_type(link.ground.received, "STATUSTEXT")
    assert notice.text == "mission refused: item 1: no key image 500"


@pytest.mark.parametrize(("item", "result"), [
    (MissionItem(command=mavlink.MAV_CMD_NAV_WAYPOINT), mavlink.MAV_MISSION_UNSUPPORTED),
    (MissionItem(command=31000, param1=2.5), mavlink.MAV_MISSION_INVALID_PARAM1),
    (MissionItem(command=31000, param1=3, param2=42), mavlink.MAV_MISSION_INVALID_PARAM2),
])
def test_undecodable_goal_gets_the_specific_result(item: MissionItem, result: int) -> None:
    link, client, server = make_link()
    upload(link, client, (Goal(1).to_item(), item))
    assert events(client) == [OperationRefused(Operation.UPLOAD, result)]
    assert server.items == ()


def test_clear_all_and_empty_upload_clear_the_mission() -> None:
    link, client, server = make_link()
    upload(link, client, goal_items(1, 2, 3))
    events(client), events(server)
    link.send(link.ground, client.clear(link.now_ns))
    link.run(lambda: client.operation is None)
    assert events(client) == [ClearDone()]
    assert events(server) == [MissionCleared(GCS)]
    assert server.items == () and server.mission_state == mavlink.MISSION_STATE_NO_MISSION

    upload(link, client, goal_items(4))
    upload(link, client, ())
    assert events(client) == [UploadDone(1), UploadDone(0)]
    assert server.items == ()


def test_the_hook_can_refuse_a_clear() -> None:
    def no_clearing(items: tuple[MissionItem, ...]) -> MissionRefusal | None:
        return None if items else MissionRefusal(mavlink.MAV_MISSION_DENIED, "mission running")

    client, server = MissionClient(GCS, VEHICLE), MissionServer(VEHICLE, validate=no_clearing)
    link = Link(Endpoint(GCS, client), Endpoint(VEHICLE, server))
    upload(link, client, goal_items(8))
    link.send(link.ground, client.clear(link.now_ns))
    link.run(lambda: client.operation is None)
    assert events(client)[-1] == OperationRefused(Operation.CLEAR, mavlink.MAV_MISSION_DENIED)
    assert server.items == goal_items(8)


def test_set_current_and_progress_messages() -> None:
    link, client, server = make_link()
    upload(link, client, goal_items(1, 2, 3))
    events(server)
    link.send(link.ground, [mavlink.MAVLink_mission_set_current_message(1, 1, 2)])
    link.deliver()
    assert events(server) == [CurrentSet(2)]
    current = of_type(link.ground.received, "MISSION_CURRENT")[-1]
    assert (current.seq, current.total, current.mission_state) == (
        2, 3, mavlink.MISSION_STATE_NOT_STARTED)

    link.send(link.ground, [mavlink.MAVLink_mission_set_current_message(1, 1, 7)])
    link.deliver()
    assert server.current_seq == 2 and events(server) == []
    assert of_type(link.ground.received, "STATUSTEXT")[-1].text == "mission: no item 7 (3 items)"

    assert server.set_current(0)
    server.set_run_state(mavlink.MISSION_STATE_ACTIVE)
    reached = server.item_reached(0)
    assert [m.get_type() for m in reached] == ["MISSION_ITEM_REACHED", "MISSION_CURRENT"]
    assert reached[1].seq == 1 and reached[1].mission_state == mavlink.MISSION_STATE_ACTIVE
    assert [m.get_type() for m in server.item_reached(2)] == ["MISSION_ITEM_REACHED"]


def test_fence_and_rally_are_unsupported_and_clear_all_types_clears() -> None:
    link, _, server = make_link()
    link.send(link.ground, [
        mavlink.MAVLink_mission_count_message(1, 1, 3, mavlink.MAV_MISSION_TYPE_FENCE),
        mavlink.MAVLink_mission_request_list_message(1, 1, mavlink.MAV_MISSION_TYPE_RALLY),
        mavlink.MAVLink_mission_clear_all_message(1, 1, mavlink.MAV_MISSION_TYPE_FENCE),
    ])
    link.deliver()
    acks = of_type(link.ground.received, "MISSION_ACK")
    assert [(a.type, a.mission_type) for a in acks] == [
        (mavlink.MAV_MISSION_UNSUPPORTED, mavlink.MAV_MISSION_TYPE_FENCE),
        (mavlink.MAV_MISSION_UNSUPPORTED, mavlink.MAV_MISSION_TYPE_RALLY),
        (mavlink.MAV_MISSION_UNSUPPORTED, mavlink.MAV_MISSION_TYPE_FENCE),
    ]
    link.send(link.ground, [mavlink.MAVLink_mission_clear_all_message(
        1, 1, mavlink.MAV_MISSION_TYPE_ALL)])
    link.deliver()
    ack = of_type(link.ground.received, "MISSION_ACK")[-1]
    assert (ack.type, ack.mission_type) == (mavlink.MAV_MISSION_ACCEPTED,
                                            mavlink.MAV_MISSION_TYPE_ALL)
    assert events(server) == [MissionCleared(GCS)]


def test_second_station_is_denied_during_an_upload_and_others_are_ignored() -> None:
    client, server = MissionClient(GCS, VEHICLE), MissionServer(VEHICLE)
    other = Endpoint(Address(250, 0))
    vehicle = Endpoint(VEHICLE, server)
    link, side = Link(Endpoint(GCS, client), vehicle), Link(other, vehicle)
    link.send(link.ground, client.upload(goal_items(1, 2), 0))
    link.drop_next["MISSION_ITEM_INT"] = 1  # the first item is lost: the upload stays open
    link.deliver()
    side.send(other, [mavlink.MAVLink_mission_count_message(1, 1, 5, 0),
                      mavlink.MAVLink_mission_count_message(2, 1, 5, 0)])  # not for us
    side.deliver()
    (ack,) = of_type(other.received, "MISSION_ACK")
    assert ack.type == mavlink.MAV_MISSION_DENIED and (ack.target_system, ack.target_component) == (
        250, 0)
    link.run(lambda: client.operation is None)
    assert events(client) == [UploadDone(2)] and server.items == goal_items(1, 2)


def test_items_out_of_order_are_dropped_and_re_requested() -> None:
    server = MissionServer(VEHICLE)
    link = Link(Endpoint(GCS), Endpoint(VEHICLE, server))
    a, b = goal_items(6, 7)
    link.send(link.ground, [mavlink.MAVLink_mission_count_message(1, 1, 2, 0),
                            b.to_message(1, VEHICLE), a.to_message(0, VEHICLE),
                            b.to_message(1, VEHICLE)])
    link.deliver()
    requests = of_type(link.ground.received, "MISSION_REQUEST_INT")
    assert [r.seq for r in requests] == [0, 0, 1]
    assert server.items == (a, b)


def test_legacy_mission_item_upload_and_request() -> None:
    server = MissionServer(VEHICLE)
    link = Link(Endpoint(GCS), Endpoint(VEHICLE, server))
    legacy = mavlink.MAVLink_mission_item_message(
        1, 1, 0, mavlink.MAV_FRAME_GLOBAL_RELATIVE_ALT, 31000, 0, 1, 9, 0, 0, 0, 47.3978, 8.5457,
        0.0)
    link.send(link.ground, [mavlink.MAVLink_mission_count_message(1, 1, 2, 0), legacy])
    link.deliver()
    assert [m.get_type() for m in link.ground.received] == ["MISSION_REQUEST_INT",
                                                            "MISSION_REQUEST"]
    link.send(link.ground, [mavlink.MAVLink_mission_item_message(
        1, 1, 1, mavlink.MAV_FRAME_LOCAL_NED, 31000, 0, 1, 4, 0, 0, 0, 1.5, -2.25, 0.0)])
    link.send(link.ground, [mavlink.MAVLink_mission_request_message(1, 1, 1, 0)])
    link.deliver()
    # float32 degrees carry about 4e-6 deg (40 units of 1e-7 deg): why MISSION_ITEM is deprecated
    assert server.items[0].x == pytest.approx(473978000, abs=40)
    assert server.items[0].y == pytest.approx(85457000, abs=40)
    assert (server.items[1].x, server.items[1].y) == (15000, -22500)
    reply = link.ground.received[-1]
    assert reply.get_type() == "MISSION_ITEM_INT" and reply.x == 15000


def test_lost_final_ack_is_repeated_for_the_resent_last_item() -> None:
    link, client, server = make_link()
    link.drop_next["MISSION_ACK"] = 1
    upload(link, client, goal_items(1, 2, 3))
    assert events(client) == [UploadDone(3)]
    assert events(server) == [MissionUploaded(goal_items(1, 2, 3), GCS)]  # installed once
    assert len(of_type(link.ground.received, "MISSION_ACK")) == 1 and link.dropped == 1


def test_stale_accepted_ack_does_not_end_an_upload() -> None:
    link, client, server = make_link()
    link.send(link.ground, client.upload(goal_items(1, 2), 0))
    left_over = mavlink.MAVLink_mission_ack_message(255, 190, mavlink.MAV_MISSION_ACCEPTED, 0)
    link.send(link.vehicle, [left_over])  # reaches the station before any item was requested
    link.run(lambda: client.operation is None)
    assert events(client) == [UploadDone(2)] and server.items == goal_items(1, 2)
    assert len(of_type(link.ground.received, "MISSION_ACK")) == 2


def test_upload_gives_up_when_the_station_goes_silent() -> None:
    config = MavlinkConfig(mission_retries=3)
    server = MissionServer(VEHICLE, config)
    link = Link(Endpoint(GCS), Endpoint(VEHICLE, server))
    link.send(link.ground, [mavlink.MAVLink_mission_count_message(1, 1, 4, 0)])
    link.run(lambda: server.get_timer() is None)
    assert events(server) == [UploadFailed("no item 0 of 4 after 4 requests", GCS)]
    assert len(of_type(link.ground.received, "MISSION_REQUEST_INT")) == 4
    assert link.now_ns == 4 * config.mission_item_timeout_ns
    assert of_type(link.ground.received, "MISSION_ACK")[-1].type == (
        mavlink.MAV_MISSION_OPERATION_CANCELLED)
    assert server.items == ()


def test_station_gives_up_when_the_vehicle_goes_silent() -> None:
    config = MavlinkConfig(mission_retries=2)
    client = MissionClient(GCS, VEHICLE, config)
    link = Link(Endpoint(GCS, client), Endpoint(VEHICLE))
    link.send(link.ground, client.download(0))
    link.run(lambda: client.operation is None)
    assert events(client) == [OperationTimedOut(
        Operation.DOWNLOAD, "no answer to MISSION_REQUEST_LIST after 3 tries")]
    assert [m.get_type() for m in link.vehicle.received] == ["MISSION_REQUEST_LIST"] * 3 + [
        "MISSION_ACK"]


def test_station_cancel_ends_the_upload_and_busy_client_refuses_a_second_operation() -> None:
    link, client, server = make_link()
    link.send(link.ground, client.upload(goal_items(1, 2), 0))
    with pytest.raises(LocalProtocolError, match="cannot start download while upload"):
        client.download(0)
    link.drop_next["MISSION_ITEM_INT"] = 1
    link.deliver()
    link.send(link.ground, [mavlink.MAVLink_mission_ack_message(
        1, 1, mavlink.MAV_MISSION_OPERATION_CANCELLED, 0)])
    link.deliver()
    assert events(server) == [UploadFailed(
        "cancelled by the ground station (MAV_MISSION_OPERATION_CANCELLED)", GCS)]
    assert server.get_timer() is None


def test_too_many_items_get_no_space() -> None:
    link, client, server = make_link(MavlinkConfig(mission_max_items=3))
    upload(link, client, goal_items(1, 2, 3, 4))
    assert server.get_timer() is None and server.items == ()
    assert events(client) == [OperationRefused(Operation.UPLOAD, mavlink.MAV_MISSION_NO_SPACE)]
    link.send(link.ground, [mavlink.MAVLink_mission_request_int_message(1, 1, 0, 0)])
    link.deliver()
    assert of_type(link.ground.received, "MISSION_ACK")[-1].type == (
        mavlink.MAV_MISSION_INVALID_SEQUENCE)


@pytest.mark.parametrize("seed", range(40))
def test_upload_and_download_survive_20_percent_loss(seed: int) -> None:
    link, client, server = make_link(MavlinkConfig(), loss=0.2, seed=seed)  # default retries
    items = goal_items(*range(10, 22))
    link.send(link.ground, client.upload(items, 0))
    rounds = link.run(lambda: client.operation is None, max_rounds=100)
    assert events(client) == [UploadDone(len(items))], f"after {rounds} rounds"
    assert server.items == items
    assert [type(e) for e in events(server)] == [MissionUploaded]

    link.send(link.ground, client.download(link.now_ns))
    link.run(lambda: client.operation is None, max_rounds=100)
    assert events(client) == [DownloadDone(items)]
    assert link.dropped > 0


finite32 = st.floats(allow_nan=False, allow_infinity=False, width=32)


@given(st.builds(MissionItem, command=st.integers(0, 65535),
                 frame=st.sampled_from(sorted(KNOWN_FRAMES)),
                 param1=finite32, param2=finite32, param3=finite32, param4=finite32,
                 x=st.integers(-2**31, 2**31 - 1), y=st.integers(-2**31, 2**31 - 1), z=finite32,
                 autocontinue=st.booleans()),
       st.integers(0, 65535))
def test_any_item_survives_the_wire_unchanged(item: MissionItem, seq: int) -> None:
    vehicle, ground = Endpoint(VEHICLE), Endpoint(GCS)
    (msg,) = vehicle.codec.parse(ground.codec.pack(item.to_message(seq, VEHICLE)))
    assert (msg.seq, msg.mission_type) == (seq, mavlink.MAV_MISSION_TYPE_MISSION)
    assert item_from_message(msg) == item


# -- hostile input (issue 15) ------------------------------------------------------------

NAN, INF = math.nan, math.inf
LEGACY_ITEM = mavlink.MAVLink_mission_item_message
ITEM_CLASSES = (LEGACY_ITEM, mavlink.MAVLink_mission_item_int_message)


def legacy_item(seq: int, frame: int, x: float, y: float) -> Any:
    """A deprecated MISSION_ITEM of goal key image 1 for the vehicle."""
    return LEGACY_ITEM(1, 1, seq, frame, 31000, 0, 1, 1, 0, 0, 0, x, y, 0.0)


@pytest.mark.parametrize(("frame", "x", "y", "result"), [
    (mavlink.MAV_FRAME_MISSION, NAN, 0.0, mavlink.MAV_MISSION_INVALID_PARAM5_X),
    (mavlink.MAV_FRAME_MISSION, INF, 0.0, mavlink.MAV_MISSION_INVALID_PARAM5_X),
    (mavlink.MAV_FRAME_LOCAL_NED, 0.0, -INF, mavlink.MAV_MISSION_INVALID_PARAM6_Y),
    (mavlink.MAV_FRAME_GLOBAL, 1000.0, 8.5, mavlink.MAV_MISSION_INVALID_PARAM5_X),
    (mavlink.MAV_FRAME_LOCAL_NED, 1.0, 3e5, mavlink.MAV_MISSION_INVALID_PARAM6_Y),  # 3e9 > int32
])
def test_legacy_item_not_finite_or_out_of_range_is_refused_and_the_mission_kept(
        frame: int, x: float, y: float, result: int) -> None:
    link, client, server = make_link()
    upload(link, client, goal_items(1, 2))
    events(client), events(server)
    link.send(link.ground, [mavlink.MAVLink_mission_count_message(1, 1, 2, 0),
                            legacy_item(0, frame, x, y)])
    link.deliver()
    assert of_type(link.ground.received, "MISSION_ACK")[-1].type == result
    (rejected,) = events(server)
    assert isinstance(rejected, MissionRejected) and rejected.refusal.result == result
    axis = "x" if result == mavlink.MAV_MISSION_INVALID_PARAM5_X else "y"
    assert rejected.refusal.reason.startswith(f"item 0: {axis} ")
    notice = "".join(m.text for m in of_type(link.ground.received, "STATUSTEXT")[-2:])
    assert notice.startswith("mission refused: item 0")
    assert server.get_timer() is None  # the upload ended: nothing more is requested
    link.send(link.ground, client.download(link.now_ns))
    link.run(lambda: client.operation is None)
    assert events(client) == [DownloadDone(goal_items(1, 2))]


@pytest.mark.parametrize("frame", [13, mavlink.MAV_FRAME_ENUM_END, 200])
def test_item_in_no_mav_frame_is_unsupported_frame(frame: int) -> None:
    link, client, server = make_link()
    upload(link, client, (MissionItem(command=31000, frame=frame, param1=1),))
    assert events(client) == [OperationRefused(Operation.UPLOAD,
                                               mavlink.MAV_MISSION_UNSUPPORTED_FRAME)]
    assert server.items == ()


def test_admission_hook_refuses_an_upload_before_any_item_is_requested() -> None:
    running = MissionRefusal(mavlink.MAV_MISSION_DENIED, "the mission is running")
    client = MissionClient(GCS, VEHICLE)
    server = MissionServer(VEHICLE, admit=lambda: running)
    link = Link(Endpoint(GCS, client), Endpoint(VEHICLE, server))
    upload(link, client, goal_items(1, 2))
    assert events(client) == [OperationRefused(Operation.UPLOAD, mavlink.MAV_MISSION_DENIED)]
    assert events(server) == [MissionRejected(running, (), GCS)]
    assert of_type(link.ground.received, "MISSION_REQUEST_INT") == []
    assert of_type(link.ground.received, "STATUSTEXT")[-1].text == \
        "mission refused: the mission is running"


def test_station_cancels_a_download_of_an_item_that_is_not_one() -> None:
    client = MissionClient(GCS, VEHICLE)
    link = Link(Endpoint(GCS, client), Endpoint(VEHICLE))
    link.send(link.ground, client.download(0))
    link.send(link.vehicle, [mavlink.MAVLink_mission_count_message(255, 190, 1, 0),
                             LEGACY_ITEM(255, 190, 0, 0, 31000, 0, 1, 1, 0, 0, 0, NAN, 0, 0)])
    link.deliver()
    (invalid,) = events(client)
    assert isinstance(invalid, DownloadInvalid)
    assert invalid.refusal.result == mavlink.MAV_MISSION_INVALID_PARAM5_X
    assert of_type(link.vehicle.received, "MISSION_ACK")[-1].type == \
        mavlink.MAV_MISSION_INVALID_PARAM5_X
    assert client.operation is None


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.randoms(use_true_random=False), st.sampled_from(ITEM_CLASSES))
def test_any_item_after_a_count_is_acked_and_what_is_stored_downloads(
        rng: random.Random, cls: type) -> None:
    server = MissionServer(VEHICLE)  # stores anything the protocol lets through
    ground, vehicle = make_codec(255, 190), make_codec(1, 1)

    def exchange(msg: Any) -> list[Any]:
        (received,) = vehicle.parse(ground.pack(msg))
        return [reply for out in server.handle_message(received, 0)
                for reply in ground.parse(vehicle.pack(out))]

    exchange(mavlink.MAVLink_mission_count_message(1, 1, 1, 0))
    item = random_message(rng, cls, VEHICLE)
    item.target_system, item.target_component, item.seq, item.mission_type = 1, 1, 0, 0
    ack, *notices = exchange(item)
    assert ack.get_type() == "MISSION_ACK"
    assert {m.get_type() for m in notices} <= {"STATUSTEXT"}
    assert (ack.type == mavlink.MAV_MISSION_ACCEPTED) == (len(server.items) == 1)
    if server.items:
        (download,) = exchange(mavlink.MAVLink_mission_request_int_message(1, 1, 0, 0))
        assert repr(item_from_message(download)) == repr(server.items[0])  # NaN params too


@settings(derandomize=True, max_examples=60, deadline=None)
@given(st.randoms(use_true_random=False), st.integers(1, 30))
def test_random_mission_messages_never_raise_and_every_reply_packs(
        rng: random.Random, count: int) -> None:
    server = MissionServer(VEHICLE, validate=refuse_unknown_keys)
    ground, vehicle = make_codec(255, 190), make_codec(1, 1)
    mission_classes = [c for c in HANDLED_MESSAGES if c.__name__.startswith("MAVLink_mission")]
    for i in range(count):
        msg = random_message(rng, rng.choice(mission_classes), VEHICLE)
        (received,) = vehicle.parse(ground.pack(msg))
        now_ns = i * 300_000_000
        for out in server.handle_message(received, now_ns) + server.handle_timer(now_ns):
            vehicle.pack(out)
