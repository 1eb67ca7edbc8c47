"""MAVLink FTP: our server and client cores against each other (and pymavlink's client),
every payload carried in a real FILE_TRANSFER_PROTOCOL packet of the vmnav dialect."""

from __future__ import annotations

import os
import random
import struct
from collections.abc import Callable, Iterator
from pathlib import Path

import fastcrc
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from robot.vehicle.ftp_memory import MemoryFileSystem
from shared.clock import ManualClock
from shared.config import FtpConfig, from_mapping
from shared.errors import ConfigError, LocalProtocolError, RemoteProtocolError
from shared.mavlink.dialect import make_codec, mavlink
from shared.mavlink.ftp.gcs import (
    Checksummed,
    Downloaded,
    FtpClient,
    FtpEvent,
    FtpFailed,
    Listed,
    Uploaded,
)
from shared.mavlink.ftp.payload import (
    MAX_DATA,
    PAYLOAD_LEN,
    DirEntry,
    FtpPayload,
    NakCode,
    Opcode,
    crc32_mavlink,
)
from shared.mavlink.ftp.vehicle import FtpServer

GCS = (255, 190)
VEHICLE = (1, 1)


class Relay:
    """Carries payloads both ways as MAVLink 2 packets, dropping a seeded fraction."""

    def __init__(self, loss: float = 0.0, seed: int = 0) -> None:
        self.gcs, self.vehicle = make_codec(*GCS), make_codec(*VEHICLE)
        self.loss, self.rng = loss, random.Random(seed)
        self.sent: list[FtpPayload] = []  # every request the client sent
        self.dropped = 0

    def _carry(self, payload: bytes, src, dst, target: tuple[int, int]) -> list:
        msg = mavlink.MAVLink_file_transfer_protocol_message(0, *target, payload)
        data = src.pack(msg)
        if self.rng.random() < self.loss:
            self.dropped += 1
            return []
        received = dst.parse(data)
        assert [(m.target_system, m.target_component) for m in received] == [target]
        return received

    def to_vehicle(self, payload: bytes) -> list[tuple[bytes, tuple[int, int]]]:
        self.sent.append(FtpPayload.from_bytes(payload))
        return [(bytes(m.payload), (m.get_srcSystem(), m.get_srcComponent()))
                for m in self._carry(payload, self.gcs, self.vehicle, VEHICLE)]

    def to_gcs(self, payload: bytes) -> list[bytes]:
        return [bytes(m.payload) for m in self._carry(payload, self.vehicle, self.gcs, GCS)]


def run(client: FtpClient, server: FtpServer, relay: Relay, clock: ManualClock,
        before_request: Callable[[FtpPayload], None] = lambda _: None) -> FtpEvent:
    """Drive both ends, waiting on the client's timer, until the client reports."""
    for _ in range(10_000):
        while out := client.payloads_to_send():
            for request in out:
                for payload, peer in relay.to_vehicle(request):
                    before_request(FtpPayload.from_bytes(payload))
                    for reply in server.handle(payload, clock.now_ns(), peer):
                        for received in relay.to_gcs(reply):
                            client.receive_payload(received, clock.now_ns())
        if (event := client.next_event()) is not None:
            return event
        deadline = client.get_timer()
        assert deadline is not None, "client waits for nothing"
        clock.sleep_until_ns(deadline)
        client.handle_timer(clock.now_ns())
    raise AssertionError("no result after 10000 rounds")


def ask(server: FtpServer, request: FtpPayload, now_ns: int = 0) -> list[FtpPayload]:
    """Send one request over a lossless relay; the replies as the ground receives them."""
    relay = Relay()
    return [FtpPayload.from_bytes(received)
            for payload, peer in relay.to_vehicle(request.to_bytes())
            for reply in server.handle(payload, now_ns, peer)
            for received in relay.to_gcs(reply)]


def ask_as(server: FtpServer, peer: tuple[int, int], request: FtpPayload,
           now_ns: int = 0) -> list[FtpPayload]:
    """Hand one request to the server as sent by ``peer``; its decoded replies."""
    return [FtpPayload.from_bytes(r) for r in server.handle(request.to_bytes(), now_ns, peer)]


def path_request(opcode: int, path: str, seq: int = 7, session: int = 0x5A,
                 offset: int = 0) -> FtpPayload:
    data = path.encode()
    return FtpPayload(seq, session, opcode, len(data), offset=offset, data=data)


@pytest.fixture
def served(tmp_path: Path) -> MemoryFileSystem:
    """A memory directory with a manifest and a thumbnail, and an empty upload area."""
    memory = tmp_path / "mem"
    (memory / "thumbnails").mkdir(parents=True)
    (memory / "manifest.json").write_text('{"format": "vmnav-memory"}\n')
    (memory / "thumbnails" / "0.png").write_bytes(bytes(range(100)))
    (tmp_path / "outside.txt").write_text("secret")
    return MemoryFileSystem(memory, tmp_path / "upload")


def add_thumbnails(served: MemoryFileSystem, count: int) -> None:
    """More thumbnails, with names long enough that a listing needs several replies."""
    for i in range(1, count):
        (served.memory_dir / "thumbnails" / f"{i:04d}-a-long-name.png").write_bytes(bytes(i))


@pytest.fixture
def server(served: MemoryFileSystem) -> Iterator[FtpServer]:
    server = FtpServer(served)
    yield server
    server.close()  # files left open by a test


class TestPayload:
    @given(seq=st.integers(0, 0xFFFF), session=st.integers(0, 255), opcode=st.integers(0, 255),
           req_opcode=st.integers(0, 255), burst=st.booleans(),
           offset=st.integers(0, 0xFFFFFFFF), data=st.binary(max_size=MAX_DATA))
    def test_round_trip(self, seq: int, session: int, opcode: int, req_opcode: int,
                        burst: bool, offset: int, data: bytes) -> None:
        p = FtpPayload(seq, session, opcode, len(data), req_opcode, burst, offset, data)
        raw = p.to_bytes()
        assert len(raw) == PAYLOAD_LEN
        assert FtpPayload.from_bytes(raw) == p

    def test_same_bytes_as_pymavlink(self) -> None:
        from pymavlink.mavftp_op import FTP_OP

        theirs = FTP_OP(513, 0x5A, 15, 80, 4, 1, 123456, bytearray(b"abc")).pack()
        ours = FtpPayload(513, 0x5A, 15, 80, 4, True, 123456, b"abc").to_bytes()
        assert ours == bytes(theirs).ljust(PAYLOAD_LEN, b"\0")

    @settings(derandomize=True, max_examples=300, deadline=None)
    @given(raw=st.binary(max_size=PAYLOAD_LEN + 8))
    def test_any_bytes_decode_or_raise_the_remote_error(self, raw: bytes) -> None:
        try:
            p = FtpPayload.from_bytes(raw)
        except RemoteProtocolError:
            assert len(raw) < 12
            return
        assert len(raw) >= 12 and p.data == raw[12:12 + min(p.size, MAX_DATA)]
        assert len(p.to_bytes()) == PAYLOAD_LEN

    def test_short_payload_is_a_remote_error(self) -> None:
        with pytest.raises(RemoteProtocolError, match="11 bytes"):
            FtpPayload.from_bytes(bytes(11))

    def test_out_of_range_field_is_a_local_error(self) -> None:
        with pytest.raises(LocalProtocolError, match="seq 65536"):
            FtpPayload(65536, 0, 0)
        with pytest.raises(LocalProtocolError, match="240 bytes"):
            FtpPayload(0, 0, 0, data=bytes(240))


def test_config_is_checked() -> None:
    problem = r"vmnav\.toml: ftp: burst_size_bytes must be in 1\.\.239, got 240"
    with pytest.raises(ConfigError, match=problem):
        from_mapping(FtpConfig, {"burst_size_bytes": 240}, "vmnav.toml", "ftp")
    with pytest.raises(ValueError, match="retries must be >= 0"):
        FtpConfig(retries=-1)


class TestCrc32:
    def test_check_value(self) -> None:
        assert crc32_mavlink(b"123456789") == 0x2DFD2D88

    def test_matches_pymavlinks_crc_library(self) -> None:
        # fastcrc is pymavlink's CRC dependency; MAVLink's CRC32 is JAMCRC started at 0.
        data = random.Random(1).randbytes(5000)
        assert crc32_mavlink(data) == fastcrc.crc32.jamcrc(data, 0)
        assert crc32_mavlink(data[3000:], crc32_mavlink(data[:3000])) == crc32_mavlink(data)


class TestServer:
    @pytest.mark.parametrize("opcode, path", [(Opcode.OPEN_FILE_RO, "/memory/manifest.json"),
                                              (Opcode.CREATE_FILE, "/upload/goal.png"),
                                              (Opcode.OPEN_FILE_WO, "/upload/goal.png")])
    @pytest.mark.parametrize("session", [0x5A, 0xA5])
    def test_open_echoes_the_session_and_answers_seq_plus_one(
            self, server: FtpServer, opcode: Opcode, path: str, session: int) -> None:
        [reply] = ask(server, path_request(opcode, path, seq=0xFFFF, session=session))
        assert (reply.opcode, reply.req_opcode, reply.session, reply.seq) == (
            Opcode.ACK, opcode, session, 0)

    def test_open_ro_ack_carries_the_size(self, server: FtpServer) -> None:
        [reply] = ask(server, path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json"))
        assert struct.unpack("<I", reply.data) == (27,)

    @pytest.mark.parametrize("opcode", [Opcode.RENAME, Opcode.CREATE_DIRECTORY, 16, 200])
    def test_unsupported_opcode_is_unknown_command(self, server: FtpServer, opcode: int) -> None:
        [reply] = ask(server, path_request(opcode, "/upload/x"))
        assert (reply.opcode, reply.data) == (Opcode.NAK, bytes([NakCode.UNKNOWN_COMMAND]))

    def test_ardupilot_param_file_is_not_found(self, server: FtpServer) -> None:
        [reply] = ask(server, path_request(Opcode.OPEN_FILE_RO, "@PARAM/param.pck?withdefaults=1"))
        assert (reply.opcode, reply.data) == (Opcode.NAK, bytes([NakCode.FILE_NOT_FOUND]))

    @pytest.mark.parametrize("opcode, path", [
        (Opcode.OPEN_FILE_RO, "/memory/../outside.txt"),
        (Opcode.OPEN_FILE_RO, "/upload/../../outside.txt"),
        (Opcode.LIST_DIRECTORY, "/memory/.."),
        (Opcode.CALC_FILE_CRC32, "memory/thumbnails/../../outside.txt"),
        (Opcode.CREATE_FILE, "/upload/../mem/manifest.json"),
    ])
    def test_path_traversal_is_refused(self, server: FtpServer, opcode: Opcode,
                                       path: str) -> None:
        [reply] = ask(server, path_request(opcode, path))
        assert (reply.opcode, reply.data) == (Opcode.NAK, bytes([NakCode.FILE_PROTECTED]))

    @pytest.mark.parametrize("opcode, path", [
        (Opcode.CREATE_FILE, "/memory/evil.txt"),
        (Opcode.OPEN_FILE_WO, "/memory/manifest.json"),
        (Opcode.REMOVE_FILE, "/memory/manifest.json"),
        (Opcode.CREATE_FILE, "/evil.txt"),
        (Opcode.CREATE_FILE, "/upload/sub/evil.txt"),
    ])
    def test_writing_outside_upload_is_protected(self, server: FtpServer,
                                                 served: MemoryFileSystem, opcode: Opcode,
                                                 path: str) -> None:
        [reply] = ask(server, path_request(opcode, path))
        assert (reply.opcode, reply.data) == (Opcode.NAK, bytes([NakCode.FILE_PROTECTED]))
        assert (served.memory_dir / "manifest.json").exists()
        assert not (served.memory_dir / "evil.txt").exists()

    def test_retried_request_gets_the_cached_reply(self, server: FtpServer) -> None:
        create = path_request(Opcode.CREATE_FILE, "/upload/a")
        first = server.handle(create.to_bytes(), 0, GCS)
        assert server.handle(create.to_bytes(), 0, GCS) == first  # not FileExists
        assert FtpPayload.from_bytes(first[0]).opcode == Opcode.ACK
        assert server.open_sessions == 1

    def test_read_errors(self, server: FtpServer) -> None:
        [bad] = ask(server, FtpPayload(1, 9, Opcode.READ_FILE, 10))
        assert bad.data == bytes([NakCode.INVALID_SESSION])
        ask(server, path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json", session=9))
        [eof] = ask(server, FtpPayload(2, 9, Opcode.BURST_READ_FILE, 80, offset=27))
        assert (eof.opcode, eof.data) == (Opcode.NAK, bytes([NakCode.EOF]))
        [wrong_kind] = ask(server, FtpPayload(3, 9, Opcode.WRITE_FILE, 1, data=b"x"))
        assert wrong_kind.data == bytes([NakCode.INVALID_SESSION])

    def test_sessions_run_out_then_time_out(self, served: MemoryFileSystem) -> None:
        config = FtpConfig(max_sessions=2, session_timeout_ns=1_000)
        server = FtpServer(served, config)
        for session in (1, 2):
            ask(server, path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json",
                                     session=session))
        [full] = ask(server, path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json",
                                          session=3))
        assert full.data == bytes([NakCode.NO_SESSIONS_AVAILABLE])
        [ok] = ask(server, path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json",
                                        session=3), now_ns=1_000)
        assert ok.opcode == Opcode.ACK and server.open_sessions == 1
        server.close()

    def test_reset_discards_uploads(self, server: FtpServer, served: MemoryFileSystem) -> None:
        ask(server, path_request(Opcode.CREATE_FILE, "/upload/a", session=4))
        ask(server, FtpPayload(8, 4, Opcode.WRITE_FILE, 3, data=b"abc"))
        [reset] = ask(server, FtpPayload(9, 4, Opcode.RESET_SESSIONS))
        [gone] = ask(server, FtpPayload(10, 4, Opcode.TERMINATE_SESSION))
        assert reset.opcode == Opcode.ACK and gone.data == bytes([NakCode.INVALID_SESSION])
        assert not (served.upload_dir / "a").exists()

    def test_burst_packets_count_seq_and_flag_the_last(self, served: MemoryFileSystem) -> None:
        server = FtpServer(served, FtpConfig(burst_packets=4))
        ask(server, path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json", session=2))
        replies = ask(server, FtpPayload(100, 2, Opcode.BURST_READ_FILE, 5, offset=3))
        assert [(r.seq, r.offset, r.size, r.burst_complete) for r in replies] == [
            (101, 3, 5, False), (102, 8, 5, False), (103, 13, 5, False), (104, 18, 5, True)]
        tail = ask(server, FtpPayload(105, 2, Opcode.BURST_READ_FILE, 5, offset=23))
        assert [(r.offset, r.data, r.burst_complete) for r in tail] == [(23, b"y\"}\n", True)]
        server.close()


class TestHostilePeers:
    """Issue 15: sessions bound to their peer, a bounded resend cache, no amplification."""

    STRANGER = (66, 66)

    def test_a_stranger_cannot_use_or_close_a_session(self, server: FtpServer,
                                                      served: MemoryFileSystem) -> None:
        ask_as(server, GCS, path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json", session=3))
        ask_as(server, GCS, path_request(Opcode.CREATE_FILE, "/upload/a", session=4))
        for request in (FtpPayload(1, 3, Opcode.READ_FILE, 10),
                        FtpPayload(2, 3, Opcode.BURST_READ_FILE, 10),
                        FtpPayload(3, 4, Opcode.WRITE_FILE, 3, data=b"evl"),
                        FtpPayload(4, 4, Opcode.TERMINATE_SESSION),
                        FtpPayload(5, 3, Opcode.TERMINATE_SESSION)):
            [reply] = ask_as(server, self.STRANGER, request)
            assert reply.data == bytes([NakCode.INVALID_SESSION]), request
        [reset] = ask_as(server, self.STRANGER, FtpPayload(6, 0, Opcode.RESET_SESSIONS))
        assert reset.opcode == Opcode.ACK and server.open_sessions == 2
        [read] = ask_as(server, GCS, FtpPayload(7, 3, Opcode.READ_FILE, 10))
        assert read.data == b'{"format":'
        ask_as(server, GCS, FtpPayload(8, 4, Opcode.WRITE_FILE, 2, data=b"ok"))
        [done] = ask_as(server, GCS, FtpPayload(9, 4, Opcode.TERMINATE_SESSION))
        assert done.opcode == Opcode.ACK
        assert (served.upload_dir / "a").read_bytes() == b"ok"
        server.close()

    def test_the_same_session_byte_from_another_peer_is_its_own(self,
                                                                 server: FtpServer) -> None:
        for peer, path in ((GCS, "/memory/manifest.json"),
                           (self.STRANGER, "/memory/thumbnails/0.png")):
            [opened] = ask_as(server, peer, path_request(Opcode.OPEN_FILE_RO, path, session=5))
            assert opened.opcode == Opcode.ACK
        [mine] = ask_as(server, GCS, FtpPayload(2, 5, Opcode.READ_FILE, 2))
        [theirs] = ask_as(server, self.STRANGER, FtpPayload(2, 5, Opcode.READ_FILE, 2))
        assert (mine.data, theirs.data) == (b'{"', bytes(range(2)))
        server.close()

    def test_only_the_owner_gets_a_burst_and_bursts_are_not_replayed(
            self, server: FtpServer, served: MemoryFileSystem) -> None:
        (served.upload_dir / "big").write_bytes(bytes(100_000))
        ask_as(server, GCS, path_request(Opcode.OPEN_FILE_RO, "/upload/big", session=1))
        burst = FtpPayload(10, 1, Opcode.BURST_READ_FILE, 239)
        assert len(ask_as(server, self.STRANGER, burst)) == 1
        assert len(ask_as(server, GCS, burst)) == server.config.burst_packets
        assert len(ask_as(server, GCS, burst)) == server.config.burst_packets  # read again
        server.close()

    def test_the_resend_cache_is_bounded(self, served: MemoryFileSystem) -> None:
        import tracemalloc

        server = FtpServer(served, FtpConfig(resend_cache_peers=16))
        request = path_request(Opcode.LIST_DIRECTORY, "/memory")
        tracemalloc.start()
        try:
            base = tracemalloc.get_traced_memory()[0]
            for n in range(3_000):
                server.handle(request.to_bytes(), 0, (n // 255 + 1, n % 255 + 1))
            grown = tracemalloc.get_traced_memory()[0] - base
        finally:
            tracemalloc.stop()
        assert server.cached_peers == 16 and grown < 100_000
        # the most recent peer still gets its retry from the cache, the first does not
        last = (3_000 // 255 + 1, 2_999 % 255 + 1)
        assert server.handle(request.to_bytes(), 0, last) == server.handle(
            request.to_bytes(), 0, last)

    @settings(derandomize=True, max_examples=200, deadline=None,
              suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(raw=st.one_of(st.binary(max_size=PAYLOAD_LEN), st.builds(
        lambda opcode, size, offset, rest: struct.pack("<HBBBBBxI", 1, 7, opcode, size, 0, 0,
                                                       offset) + rest,
        st.sampled_from(Opcode), st.integers(0, 255), st.integers(0, 30_000),
        st.binary(max_size=MAX_DATA))))
    def test_a_strangers_request_gets_at_most_one_reply(self, served: MemoryFileSystem,
                                                        raw: bytes) -> None:
        (served.upload_dir / "big").write_bytes(bytes(20_000))
        server = FtpServer(served)
        session = raw[2] if len(raw) > 2 else 0
        try:
            ask_as(server, GCS, path_request(Opcode.OPEN_FILE_RO, "/upload/big", session=session))
            replies = server.handle(raw, 0, self.STRANGER)
            assert len(replies) <= 1
            assert all(len(r) == PAYLOAD_LEN for r in replies)
        finally:
            server.close()


class TestClientWithServer:
    def test_list_needs_several_replies(self, server: FtpServer, served: MemoryFileSystem,
                                        manual_clock: ManualClock) -> None:
        add_thumbnails(served, 60)
        client, relay = FtpClient(), Relay()
        client.list_directory("/memory/thumbnails", manual_clock.now_ns())
        event = run(client, server, relay, manual_clock)
        names = sorted(os.listdir(served.memory_dir / "thumbnails"))
        assert isinstance(event, Listed)
        assert event.entries == tuple(
            DirEntry(n, False, (served.memory_dir / "thumbnails" / n).stat().st_size)
            for n in names)
        lists = [r for r in relay.sent if r.opcode == Opcode.LIST_DIRECTORY]
        assert len(lists) > 3 and lists[1].offset > 0

    def test_get_with_20_percent_loss(self, server: FtpServer, served: MemoryFileSystem,
                                      manual_clock: ManualClock) -> None:
        data = random.Random(2).randbytes(30_000)  # about four 32-packet bursts
        (served.memory_dir / "images").mkdir()
        (served.memory_dir / "images" / "3.png").write_bytes(data)
        client, relay = FtpClient(session=0x33), Relay(loss=0.2, seed=3)
        client.get("/memory/images/3.png", manual_clock.now_ns())
        event = run(client, server, relay, manual_clock)
        assert event == Downloaded("/memory/images/3.png", data)
        assert relay.dropped > 20  # of about 170 packets
        assert any(r.opcode == Opcode.READ_FILE for r in relay.sent)  # gaps re-requested
        assert server.open_sessions == 0 and not client.busy

    @pytest.mark.parametrize("size", [0, 1, 239, 239 * 32, 239 * 32 + 1])
    def test_get_sizes_at_packet_and_burst_edges(self, server: FtpServer,
                                                 served: MemoryFileSystem,
                                                 manual_clock: ManualClock, size: int) -> None:
        data = random.Random(size).randbytes(size)
        (served.memory_dir / "blob").write_bytes(data)
        client = FtpClient()
        client.get("/memory/blob", 0)
        assert run(client, server, Relay(), manual_clock) == Downloaded("/memory/blob", data)

    def test_put_appears_only_when_complete(self, server: FtpServer, served: MemoryFileSystem,
                                            manual_clock: ManualClock) -> None:
        data = random.Random(4).randbytes(10_000)
        target = served.upload_dir / "goal.png"
        seen: list[tuple[int, bool]] = []
        client, relay = FtpClient(), Relay(loss=0.2, seed=5)
        client.put("/upload/goal.png", data, manual_clock.now_ns())
        event = run(client, server, relay, manual_clock,
                    before_request=lambda r: seen.append((r.opcode, target.exists())))
        assert event == Uploaded("/upload/goal.png", 10_000)
        assert target.read_bytes() == data
        first_terminate = [op for op, _ in seen].index(Opcode.TERMINATE_SESSION)
        assert not any(exists for _, exists in seen[:first_terminate + 1])
        assert sum(op == Opcode.WRITE_FILE for op, _ in seen) >= 42  # 10 000 / 239

    def test_put_too_large_fails_and_keeps_nothing(self, served: MemoryFileSystem,
                                                   manual_clock: ManualClock) -> None:
        server = FtpServer(served)
        served.upload_limit_bytes = 1000
        client = FtpClient()
        client.put("/upload/big", bytes(1001), 0)
        event = run(client, server, Relay(), manual_clock)
        assert isinstance(event, FtpFailed) and event.nak is NakCode.FAIL_ERRNO
        assert not (served.upload_dir / "big").exists()

    def test_put_over_an_existing_file_is_refused(self, server: FtpServer,
                                                  served: MemoryFileSystem,
                                                  manual_clock: ManualClock) -> None:
        (served.upload_dir / "goal.png").write_bytes(b"old")
        client = FtpClient()
        client.put("/upload/goal.png", b"new", 0)
        event = run(client, server, Relay(), manual_clock)
        assert isinstance(event, FtpFailed) and event.nak is NakCode.FILE_EXISTS
        assert (served.upload_dir / "goal.png").read_bytes() == b"old"

    def test_crc(self, server: FtpServer, served: MemoryFileSystem,
                 manual_clock: ManualClock) -> None:
        data = (served.memory_dir / "thumbnails" / "0.png").read_bytes()
        client = FtpClient()
        client.crc32("/memory/thumbnails/0.png", 0)
        event = run(client, server, Relay(), manual_clock)
        assert event == Checksummed("/memory/thumbnails/0.png", fastcrc.crc32.jamcrc(data, 0))

    def test_missing_file_fails_with_the_nak(self, server: FtpServer,
                                             manual_clock: ManualClock) -> None:
        client = FtpClient()
        client.get("/memory/nope", 0)
        event = run(client, server, Relay(), manual_clock)
        assert event == FtpFailed("/memory/nope", "OPEN_FILE_RO", "OPEN_FILE_RO refused",
                                  NakCode.FILE_NOT_FOUND)

    def test_silent_server_fails_after_the_retries(self, server: FtpServer,
                                                   manual_clock: ManualClock) -> None:
        config = FtpConfig(ack_timeout_ns=100_000_000, retries=3)
        client, relay = FtpClient(config), Relay(loss=1.0)
        client.list_directory("/", 0)
        event = run(client, server, relay, manual_clock)
        assert isinstance(event, FtpFailed) and "after 4 tries" in event.reason
        assert manual_clock.now_ns() == 400_000_000 and len(relay.sent) == 4

    def test_open_waits_for_a_free_session(self, served: MemoryFileSystem,
                                           manual_clock: ManualClock) -> None:
        config = FtpConfig(ack_timeout_ns=100_000_000, max_sessions=1,
                           session_timeout_ns=300_000_000)
        server = FtpServer(served, config)
        other = path_request(Opcode.OPEN_FILE_RO, "/memory/manifest.json", session=200)
        assert FtpPayload.from_bytes(server.handle(other.to_bytes(), 0, (254, 1))[0]).opcode \
            == Opcode.ACK  # another ground station holds the only session, then goes quiet
        client, relay = FtpClient(config), Relay()
        client.get("/memory/thumbnails/0.png", 0)
        event = run(client, server, relay, manual_clock)
        assert event == Downloaded("/memory/thumbnails/0.png", bytes(range(100)))
        opens = [r for r in relay.sent if r.opcode == Opcode.OPEN_FILE_RO]
        assert len(opens) == 4 and manual_clock.now_ns() == 300_000_000

    def test_one_operation_at_a_time(self) -> None:
        client = FtpClient()
        client.list_directory("/", 0)
        with pytest.raises(LocalProtocolError, match="LIST_DIRECTORY of / in progress"):
            client.get("/memory/manifest.json", 0)


class TestPymavlinkClient:
    """pymavlink's own MAVFTP client, in-process: its connection is a loopback whose far
    end is our server (no sockets)."""

    @pytest.fixture
    def ftp(self, server: FtpServer):
        from pymavlink import mavftp, mavutil

        class Loopback(mavutil.mavfile):
            def __init__(self) -> None:
                super().__init__(None, "loopback", source_system=GCS[0],
                                 source_component=GCS[1])
                self.vehicle = make_codec(*VEHICLE)
                self.inbox = bytearray()

            def write(self, buf: bytes) -> None:
                for msg in self.vehicle.parse(bytes(buf)):
                    peer = (msg.get_srcSystem(), msg.get_srcComponent())
                    for reply in server.handle(msg.payload, 0, peer):
                        out = mavlink.MAVLink_file_transfer_protocol_message(0, *peer, reply)
                        self.inbox += self.vehicle.pack(out)

            def recv(self, n: int | None = None) -> bytes:
                data = bytes(self.inbox[:n])
                del self.inbox[:len(data)]
                return data

            def close(self) -> None:
                pass

        # Replies to CRC and NAKs end pymavlink's wait only after idle_detection_time
        # (3.7 s by default) of silence; shortened here, its other settings as default.
        settings = mavftp.MAVFTPSettings([
            ("debug", int, 0), ("pkt_loss_tx", int, 0), ("pkt_loss_rx", int, 0),
            ("max_backlog", int, 5), ("burst_read_size", int, 80), ("write_size", int, 80),
            ("write_qsize", int, 5), ("idle_detection_time", float, 0.3),
            ("read_retry_time", float, 0.2), ("retry_time", float, 0.5)])
        return mavftp.MAVFTP(Loopback(), *VEHICLE, settings)

    def test_list_get_put_crc(self, ftp, served: MemoryFileSystem, tmp_path: Path) -> None:
        from pymavlink.mavftp import FtpError

        add_thumbnails(served, 60)
        listing = ftp.cmd_list(["/memory/thumbnails"])
        assert listing.error_code == FtpError.Success
        assert len(listing.directory_listing) == 60
        goal = random.Random(6).randbytes(5000)
        (tmp_path / "goal.png").write_bytes(goal)
        ftp.cmd_put([str(tmp_path / "goal.png"), "/upload/goal.png"])
        assert ftp.process_ftp_reply("put").error_code == FtpError.Success
        assert (served.upload_dir / "goal.png").read_bytes() == goal
        ftp.cmd_get(["/upload/goal.png", str(tmp_path / "back.png")])
        assert ftp.process_ftp_reply("OpenFileRO").error_code == FtpError.Success
        assert (tmp_path / "back.png").read_bytes() == goal
        assert ftp.cmd_crc(["/upload/goal.png"]).error_code == FtpError.Success
        assert ftp.cmd_get(["@PARAM/param.pck?withdefaults=1", "-"]).error_code == \
            FtpError.Success  # sent; the NAK arrives in the reply
        assert ftp.process_ftp_reply("OpenFileRO").error_code == FtpError.FileNotFound
