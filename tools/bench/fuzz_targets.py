"""The targets of ``vmnav bench fuzz``: each feeds one input to a real entry point.

A target is built once per worker process in a scratch folder (:data:`FACTORIES`)
and then takes inputs one at a time: :meth:`FuzzTarget.generate` makes an input (bytes)
from the input's random generator, :meth:`FuzzTarget.run` feeds it to the project's
code. ``run`` raises what the project raises; :mod:`tools.bench.fuzz` counts anything
but :attr:`FuzzTarget.allowed` (the project's own input errors) as a crash.

==================  ======================================================================
target              entry point, and what an input is
==================  ======================================================================
aria_robot          the emulated Pioneer (``sim.pioneer.emulator``): a connected client's
                    byte stream (commands with boundary arguments, strings, SYNCs, unknown
                    IDs), then one SIP cycle of the simulation
aria_host           the Pioneer client (``robot.pioneer.client``) and through its session
                    the ``shared.aria`` decoders: a robot's byte stream after the
                    handshake (mutated SIPs, CONFIG, ENCODER, identities, resets)
mavlink_unsigned    ``VehicleEndpoint.receive`` on an unsigned link: messages of every id
                    the vehicle handles with random fields (mission uploads, FTP requests
                    among them), or their packed bytes mutated
mavlink_signed      the same on a signed link: validly signed messages with random fields
                    (they reach the handlers), or signed packets mutated (they must not)
memory              ``shared.memory.read_memory`` on a one-key-image memory with one file
                    mutated (manifest, key image, features, thumbnail)
mcap_info           ``shared.logs.reader.log_info`` on a mutated small field log
mcap_read           ``shared.logs.reader.read_messages`` (all of them) on the same
mcap_recover        ``shared.logs.reader.recover`` on the same
photo               the robot's photo goal (``robot.worker.find_photo``): a mutated PNG or
                    JPEG of the memory's camera size, localized in the memory
==================  ======================================================================
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np

from robot.config import FeatureConfig, LocalizeConfig, PioneerDriverConfig, VmnavConfig
from robot.memory.localize import Localizer
from robot.pioneer.client import PioneerClient
from robot.vehicle.endpoint import VehicleEndpoint
from robot.vehicle.options import SigningSetup, VehicleFiles
from robot.vision.front_end import make_front_end, stored_descriptors
from robot.worker import find_photo
from shared.aria import (
    Command,
    ConfigPacket,
    EncoderPacket,
    RobotIdentity,
    Sip,
    SipFlags,
    SipIo,
    SonarReading,
    SyncReply,
    encode_packet,
)
from shared.aria.commands import ArgType
from shared.camera_model import CameraModel
from shared.clock import NS_PER_S, ManualClock
from shared.config import CameraMountConfig, LogConfig
from shared.errors import InputError
from shared.logs import topics
from shared.logs.reader import log_info, read_messages, recover
from shared.logs.writer import LogWriter
from shared.mavlink.dialect import Message, make_codec, mavlink
from shared.mavlink.signing import configure_signing, timestamp_from_unix_ns
from shared.memory import KeyframeRecord, VisualMemory, read_memory, write_memory
from shared.memory.store import MANIFEST_NAME, features_path, image_path, thumbnail_path
from shared.pose import Pose2
from sim.config import EmulatorConfig, SimConfig
from sim.pioneer.emulator import EmulatedPioneer
from sim.simulation import Simulation
from sim.world import LandmarkDensity, Wall, World
from tools.bench.fuzz_inputs import (
    aria_int_arg,
    aria_stream,
    ftp_request,
    mission_upload,
    mutate_bytes,
    mutate_json,
    mutate_npz,
    mutate_png,
    random_message,
)
from tools.bench.link_load import LinkLoadApp


class FuzzTarget(Protocol):
    """One entry point under fuzzing (module docstring)."""

    #: Exceptions that are the project's documented refusal of bad input, not crashes.
    allowed: tuple[type[BaseException], ...]

    def generate(self, rng: np.random.Generator) -> bytes:
        """One input, a pure function of ``rng``'s state."""
        ...

    def run(self, data: bytes) -> None:
        """Feed ``data`` to the entry point."""
        ...


# -- ARIA ---------------------------------------------------------------------------------

_MS = 1_000_000
#: A client's connect: SYNC0, SYNC1, SYNC2, OPEN, ENABLE 1 (reference §3).
_CLIENT_CONNECT = b"".join(encode_packet(packet_id, data) for packet_id, data in (
    (0, b""), (1, b""), (2, b""), (Command.OPEN, b""),
    (Command.ENABLE, bytes((ArgType.INT, 1, 0)))))
_COMMAND_IDS = tuple(int(c) for c in Command)


def _room() -> World:
    """A bare 4 m square room, the robot at its centre facing +x."""
    corners = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0)]
    walls = tuple(Wall(a, b, 2.5) for a, b in zip(corners, corners[1:] + corners[:1],
                                                   strict=True))
    return World(name="fuzz", walls=walls, start=Pose2(2.0, 2.0, 0.0),
                 landmarks=LandmarkDensity())


class AriaRobotTarget:
    """The emulated Pioneer; one simulation for all inputs, a new session per input."""

    allowed: tuple[type[BaseException], ...] = (InputError,)

    def __init__(self, work: Path) -> None:
        self.simulation = Simulation(_room(), SimConfig(seed=0))
        self.config = EmulatorConfig()
        self.emulator = EmulatedPioneer(self.simulation, self.config, np.random.default_rng(0))

    def generate(self, rng: np.random.Generator) -> bytes:
        frames = []
        for _ in range(int(rng.integers(1, 9))):
            pick = rng.random()
            command = int(rng.choice(_COMMAND_IDS))
            if pick < 0.6:
                frames.append((command, aria_int_arg(rng)))
            elif pick < 0.7:
                text = rng.bytes(int(rng.integers(0, 40)))
                frames.append((command, bytes((ArgType.STR, len(text))) + text))
            elif pick < 0.8:
                frames.append((int(rng.integers(3)) if rng.random() < 0.5 else command, b""))
            else:
                frames.append((int(rng.integers(256)), rng.bytes(int(rng.integers(0, 12)))))
        return aria_stream(frames, rng)

    def run(self, data: bytes) -> None:
        emulator, simulation = self.emulator, self.simulation
        emulator.reset_session()
        now_ns = simulation.now_ns
        emulator.receive_data(_CLIENT_CONNECT, now_ns)
        emulator.service(now_ns)
        emulator.receive_data(data, now_ns)
        emulator.service(now_ns)
        simulation.step_until(now_ns + self.config.link.sip_period_ns)
        emulator.service(simulation.now_ns)


def _robot_packets() -> list[tuple[int, bytes]]:
    """A robot's packets after the handshake, as (id, data): CONFIG, SIPs, ENCODER."""
    sip = Sip(x_counts=1000, y_counts=200, th_counts=-300, left_vel_m_s=0.2, right_vel_m_s=0.25,
              battery_v=12.8, flags=SipFlags.MOTORS_ENABLED | SipFlags.SONAR_ARRAY_1,
              sonar=(SonarReading(0, 1.5), SonarReading(3, 0.4)), io=SipIo(),
              real_battery_v=12.8, charge_state=0, rot_vel_rad_s=0.1, fault_flags=0)
    packets = [ConfigPacket().to_packet(), sip.to_packet(), Sip().to_packet(),
               EncoderPacket(100, -100).to_packet()]
    return [(p.packet_id, p.data) for p in packets]


class AriaHostTarget:
    """The Pioneer client, connected afresh for each input, then fed the input."""

    allowed: tuple[type[BaseException], ...] = (InputError,)

    def __init__(self, work: Path) -> None:
        identity = RobotIdentity("fuzz", "Pioneer", "p3at-sh").to_packet()
        self.packets = _robot_packets()
        self.handshake = (SyncReply(0).to_packet().to_bytes() + SyncReply(1).to_packet().to_bytes()
                          + identity.to_bytes())
        self.identity = (identity.packet_id, identity.data)
        self.config = PioneerDriverConfig()

    def generate(self, rng: np.random.Generator) -> bytes:
        frames = []
        for _ in range(int(rng.integers(1, 7))):
            pick = rng.random()
            if pick < 0.7:
                frames.append(self.packets[int(rng.integers(len(self.packets)))])
            elif pick < 0.8:
                frames.append(self.identity)
            elif pick < 0.9:
                frames.append((int(rng.choice([0xFF, 0xFE, 0, 1, 2])), b""))
            else:
                frames.append((int(rng.integers(256)), rng.bytes(int(rng.integers(0, 120)))))
        return aria_stream(frames, rng)

    def run(self, data: bytes) -> None:
        client = PioneerClient(self.config)
        client.start(0)
        client.receive_data(self.handshake, _MS)
        client.receive_data(encode_packet(*self.packets[0]) + encode_packet(*self.packets[1]),
                            2 * _MS)
        client.receive_data(data, 3 * _MS)
        client.command(0.3, 0.2, 4 * _MS)
        for now_ns in (4 * _MS, NS_PER_S, 5 * NS_PER_S):
            client.handle_timer(now_ns)
        _ = client.status, client.counters  # what the driver reads every cycle
        while client.next_event() is not None:
            pass
        client.data_to_send()


# -- MAVLink ------------------------------------------------------------------------------

#: The messages the vehicle handles (``robot.vehicle.endpoint`` and the cores it composes).
HANDLED_MESSAGES: tuple[type[Message], ...] = tuple(getattr(mavlink, f"MAVLink_{name}_message")
                                                    for name in (
    "heartbeat", "file_transfer_protocol", "manual_control", "set_mode", "timesync",
    "command_long", "command_int", "mission_count", "mission_item", "mission_item_int",
    "mission_request", "mission_request_int", "mission_request_list", "mission_ack",
    "mission_clear_all", "mission_set_current", "param_request_list", "param_request_read",
    "param_set", "radio_status"))
_ALL_MESSAGES: tuple[type[Message], ...] = tuple(
    cls for _, cls in sorted(mavlink.mavlink_map.items()))
#: Fuzzing key (32 bytes) and the Unix time the signed target's clocks read, ns.
_KEY = bytes(range(32))
_UNIX_NS = 1_750_000_000 * NS_PER_S
_TIMESTAMP = timestamp_from_unix_ns(_UNIX_NS)


class VehicleTarget:
    """A fresh :class:`VehicleEndpoint` (with the link load generator's application) per
    input; ``signed`` signs the link and the ground's messages with one key."""

    allowed: tuple[type[BaseException], ...] = (InputError,)

    def __init__(self, work: Path, signed: bool) -> None:
        self.files = VehicleFiles(work / "memory", work / "upload", work / "params.json")
        self.signing = SigningSetup(_KEY, _UNIX_NS) if signed else None
        self.ground = make_codec(255, 190)
        if signed:
            configure_signing(self.ground, _KEY, 0, _TIMESTAMP)
        self.commands = [int(c) for c in mavlink.enums["MAV_CMD"]]

    def generate(self, rng: np.random.Generator) -> bytes:
        if rng.random() < 0.1:
            return rng.bytes(int(rng.integers(1, 300)))
        ground = self.ground
        ground.seq, ground.signing.timestamp = 0, _TIMESTAMP  # each input from the same start
        packets = [ground.pack(msg) for msg in self._messages(rng)]
        if rng.random() < 0.3:
            at = int(rng.integers(len(packets)))
            packets[at] = mutate_bytes(packets[at], rng)
        return b"".join(packets)

    def _messages(self, rng: np.random.Generator) -> list[Message]:
        pick = rng.random()
        if pick < 0.2:
            return mission_upload(rng, legacy=bool(rng.integers(2)))
        if pick < 0.3:
            return [ftp_request(rng) for _ in range(int(rng.integers(1, 4)))]
        out = []
        for _ in range(int(rng.integers(1, 5))):
            cls = (HANDLED_MESSAGES[int(rng.integers(len(HANDLED_MESSAGES)))]
                   if rng.random() < 0.9 else _ALL_MESSAGES[int(rng.integers(len(_ALL_MESSAGES)))])
            command = {"command": int(rng.choice(self.commands))} \
                if cls in (mavlink.MAVLink_command_long_message,
                           mavlink.MAVLink_command_int_message) and rng.random() < 0.7 else None
            out.append(random_message(cls, rng, command))
        return out

    def run(self, data: bytes) -> None:
        clock = ManualClock()
        endpoint = VehicleEndpoint(LinkLoadApp(range(7), clock), VmnavConfig(), self.files,
                                   signing=self.signing)
        endpoint.receive(data, clock.now_ns(), datagram=True)
        endpoint.poll(clock.now_ns())
        clock.advance(2.0)
        endpoint.poll(clock.now_ns())
        endpoint.close()


# -- files --------------------------------------------------------------------------------


def _tiny_memory(folder: Path) -> VisualMemory:
    """A memory of one path of two key images (64x48 camera, blurred noise, Harris corners)
    written to ``folder``."""
    width, height = 64, 48
    camera = CameraModel(width=width, height=height, K=[[32.0, 0.0, 31.5], [0.0, 32.0, 23.5],
                                                        [0.0, 0.0, 1.0]], xi=1.2, fov_deg=185.0)
    rng = np.random.default_rng(0)
    records = []
    for i in range(2):
        noise = rng.uniform(0, 255, (height, width)).astype(np.float32)
        image = np.clip(cv2.GaussianBlur(noise, (0, 0), 1.5) * 3 - 255, 0, 255).astype(np.uint8)
        features = make_front_end(FeatureConfig(), camera).describe(image)
        records.append(KeyframeRecord(t_ns=i * NS_PER_S, odom_pose=Pose2(0.5 * i, 0.0, 0.0),
                                      distance_m=0.5 * i, image=image,
                                      pixels_xy=np.array(features.pixels_xy),
                                      patches=stored_descriptors(features)))
    memory = VisualMemory(camera)
    memory.add_path("fuzz", records)
    write_memory(folder, memory)
    return memory


class MemoryTarget:
    """``read_memory`` on a tiny memory with one of its files replaced by the input.

    An input is one byte naming the file (index into :attr:`files`), then its content.
    """

    allowed: tuple[type[BaseException], ...] = (InputError,)

    def __init__(self, work: Path) -> None:
        self.folder = work / "memory"
        _tiny_memory(self.folder)
        self.files = [self.folder / MANIFEST_NAME, image_path(self.folder, 0),
                      features_path(self.folder, 0), thumbnail_path(self.folder, 1)]
        self.originals = [path.read_bytes() for path in self.files]

    def generate(self, rng: np.random.Generator) -> bytes:
        which = int(rng.integers(len(self.files)))
        original = self.originals[which]
        mutate = {0: mutate_json, 2: mutate_npz}.get(which, mutate_png)
        return bytes((which,)) + mutate(original, rng)

    def run(self, data: bytes) -> None:
        which = data[0] % len(self.files) if data else 0
        path = self.files[which]
        path.write_bytes(data[1:])
        try:
            read_memory(self.folder)
        finally:
            path.write_bytes(self.originals[which])


def _tiny_log(folder: Path) -> bytes:
    """A finished field log from the robot's writer: a dozen JSON messages on two topics
    and a metadata record in zstd chunks of about 1 KB (a small seed, so that each input
    costs little); returns the file's bytes."""
    config = LogConfig(output_dir=str(folder), chunk_size_bytes=1024, compression="zstd",
                       fsync=False)
    writer = LogWriter(config, "fuzz")
    writer.add_metadata("run", {"route": "fuzz"})
    for i in range(12):
        t_ns = i * 20_000_000
        writer.log_json(t_ns, topics.CMD_VEL, "vmnav.Command",
                        {"stamp_ns": t_ns, "linear_x_m_s": 0.2, "angular_z_rad_s": 0.0,
                         "source": "fuzz"})
        writer.log_json(t_ns, topics.SERVO_STATE, "vmnav.ServoState",
                        {"stamp_ns": t_ns, "lateral_error_m": 0.01 * i})
    (path,) = writer.close().files
    return path.read_bytes()


class McapTarget:
    """One reader function on a mutated small field log (``mode``: info, read, recover)."""

    allowed: tuple[type[BaseException], ...] = (InputError,)

    def __init__(self, work: Path, mode: str) -> None:
        self.seed = _tiny_log(work / "seed")
        self.path, self.out = work / "in.mcap", work / "out.mcap"
        self.mode = mode

    def generate(self, rng: np.random.Generator) -> bytes:
        return mutate_bytes(self.seed, rng, max_ops=int(rng.integers(1, 9)))

    def run(self, data: bytes) -> None:
        self.path.write_bytes(data)
        if self.mode == "info":
            log_info(self.path)
        elif self.mode == "read":
            for _ in read_messages(self.path):
                pass
        else:
            recover(self.path, self.out)


class PhotoTarget:
    """``find_photo`` against the tiny memory's localizer; an input is the photo file."""

    allowed: tuple[type[BaseException], ...] = (InputError,)

    def __init__(self, work: Path) -> None:
        memory = _tiny_memory(work / "memory")
        self.camera = memory.camera
        self.localizer = Localizer.from_memory(memory, CameraMountConfig(), FeatureConfig(),
                                               LocalizeConfig())
        image = memory.keyframe(0).image
        self.seeds = [cv2.imencode(ext, image)[1].tobytes() for ext in (".png", ".jpg")]
        self.path = work / "upload" / "1.png"
        self.path.parent.mkdir()

    def generate(self, rng: np.random.Generator) -> bytes:
        png, jpeg = self.seeds
        return mutate_png(png, rng) if rng.random() < 0.7 else mutate_bytes(jpeg, rng)

    def run(self, data: bytes) -> None:
        self.path.write_bytes(data)
        find_photo(self.path, self.localizer, self.camera)


#: Target name -> how to build it in a scratch folder.
FACTORIES: dict[str, Callable[[Path], FuzzTarget]] = {
    "aria_robot": AriaRobotTarget,
    "aria_host": AriaHostTarget,
    "mavlink_unsigned": lambda work: VehicleTarget(work, signed=False),
    "mavlink_signed": lambda work: VehicleTarget(work, signed=True),
    "memory": MemoryTarget,
    "mcap_info": lambda work: McapTarget(work, "info"),
    "mcap_read": lambda work: McapTarget(work, "read"),
    "mcap_recover": lambda work: McapTarget(work, "recover"),
    "photo": PhotoTarget,
}
