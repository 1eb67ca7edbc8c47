"""The web app's ground station loop: one thread owns the :class:`GroundStation` and does
everything with it, in order.

Theory of operation
-------------------

The station is blocking and not thread-safe (``ground.station``), and the web server is
asyncio. So the station lives on this loop's thread alone:

1. The server hands work over with :meth:`StationLoop.submit` (a function of the station,
   run here; its result or exception comes back in a :class:`concurrent.futures.Future`).
   Work runs in arrival order, except the emergency stop, which goes to the front.
2. Between work items the loop services the link in slices of at most :data:`POLL_NS`
   (``GroundStation.run_until``), so new work waits at most that long.
3. Telemetry: a station listener turns each ODOMETRY and VISUAL_SERVO_STATUS into a sample
   (``ground.web.vehicle_json``); every :data:`PUBLISH_NS` with news (at least every
   second, for the heartbeat ages) the loop publishes one update with the fleet, the new
   samples and the new notices through the ``publish`` callback (which must be
   thread-safe). The listener also publishes when due, so a long operation (an FTP
   transfer) does not freeze the page.
4. Teleoperation: while a page drives (``teleop`` on, which sets MANUAL), a MANUAL_CONTROL
   goes out every :data:`ground.teleop.PERIOD_NS` with the command of a
   :class:`~ground.teleop.DeadMan`: zeros once the page stops refreshing it. The page
   that drives going away (its WebSocket closed) stops it at once: one all-zero
   MANUAL_CONTROL, teleop off. Like the listener, due ticks also go out from inside long
   operations; during a blocking wait for an answer none are due only if no message comes
   in, and then the robot's own dead-man stops it.
5. Key images never change once in a memory (``shared.memory.store`` rule 1), so their
   files fetched over FTP are cached by (system, path) up to :data:`CACHE_BYTES`; the
   manifest is fetched again on request (a path taught since).
6. Planned routes (``route``) start at the key image the vehicle last said it was at or
   had passed (VISUAL_SERVO_STATUS ``current_key``, kept with when it came, since the
   robot reports none between runs); a vehicle that never said is "start unknown". The
   robot localizes again when a run starts, so the route shown is the one it would take
   from there.
7. The camera (``ground.camera_stream``): a vehicle's video stream is asked of its camera
   component once and kept per system, until the page asks again (``refresh``) or the
   stream fails to open (:meth:`StationLoop.forget_video_stream`).
"""

from __future__ import annotations

import collections
import concurrent.futures
import logging
import threading
from collections.abc import Callable
from typing import Any, TypeVar

from ground.camera_stream import find_video_stream
from ground.fleet import VehicleState
from ground.memory_index import (
    MANIFEST_PATH,
    MEMORY_ROOT,
    MemoryIndex,
    memory_index_from_manifest,
)
from ground.station import GroundError, GroundStation, PhotoGoal
from ground.teleop import PERIOD_NS, DeadMan
from ground.web.link_quality import LinkQuality
from ground.web.requests import Request
from ground.web.vehicle_json import sample_json, vehicle_json
from shared.clock import NS_PER_S, Clock
from shared.errors import InputError, UnknownKeyframeError
from shared.mavlink.camera import VideoStream
from shared.mavlink.dialect import Message, mavlink
from shared.mavlink.mission.goal import Goal
from shared.mavlink.modes import Mode

_log = logging.getLogger(__name__)

T = TypeVar("T")
#: Longest wait for new work, ns (rule 2).
POLL_NS = 20_000_000
#: Shortest time between two updates, ns (rule 3).
PUBLISH_NS = 50_000_000
#: Longest time between two updates, ns (rule 3).
QUIET_PUBLISH_NS = NS_PER_S
#: Bytes of key image files kept (rule 5): about 100 full key images, thousands of thumbnails.
CACHE_BYTES = 64 * 2**20
#: Stream period asked for the plotted messages of the vehicle selected, us (10 Hz).
PLOT_INTERVAL_US = 100_000
_ENDED = "the ground station's loop has ended (its error is in the server's log)"
_PLOTTED = (mavlink.MAVLINK_MSG_ID_ODOMETRY, mavlink.MAVLINK_MSG_ID_VISUAL_SERVO_STATUS)
#: Where the robot serves the thumbnails of the path it is teaching (``robot.vehicle.ftp_memory``).
TEACHING_ROOT = "/teaching"
#: The files the page may ask for (rule 5), under ``/memory``.
MEMORY_FILES = frozenset({"thumbnails", "images"})


class StationLoop:
    """The loop (module rules). Start it with :meth:`start`; :meth:`stop` ends it.

    Args:
        station: the station; from :meth:`start` on, only this loop's thread uses it.
        clock: the station's clock.
        publish: called with each update (a JSON-ready dict), from the loop's thread.
        timeout_s: how long a request waits for a vehicle not heard yet, s.
    """

    def __init__(self, station: GroundStation, clock: Clock,
                 publish: Callable[[dict[str, Any]], None], timeout_s: float = 5.0) -> None:
        self.station = station
        self.clock = clock
        self._publish = publish
        self._timeout_s = timeout_s
        self._work: collections.deque[tuple[Callable[[GroundStation], Any],
                                            concurrent.futures.Future[Any]]] = \
            collections.deque()
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._ended = False
        self._thread = threading.Thread(target=self._run, name="ground-web-station",
                                        daemon=True)
        self._start_ns = clock.now_ns()
        self._quality = LinkQuality()
        self._samples: dict[int, list[dict[str, Any]]] = {}
        self._notices_sent: dict[int, int] = {}
        self._dirty = True
        self._last_publish_ns: int | None = None
        self._deadman = DeadMan()
        self._teleop_owner: int | None = None
        self._next_tick_ns = 0
        self._files: collections.OrderedDict[tuple[int, str], bytes] = collections.OrderedDict()
        self._file_bytes = 0
        self._indexes: dict[int, MemoryIndex] = {}
        self._streams: dict[int, VideoStream] = {}
        self._last_key: dict[int, tuple[int, int]] = {}  # system -> (current_key, when ns)
        station.listeners.append(self._on_message)
        station.packet_taps.append(self._on_packet)

    # -- the server's side (any thread) --------------------------------------------------

    def start(self) -> None:
        """Start the loop's thread."""
        self._thread.start()

    def stop(self) -> None:
        """Stop driving (one all-zero MANUAL_CONTROL), end the loop and wait for it;
        idempotent. Work not started fails with :class:`concurrent.futures.CancelledError`."""
        self._stopping.set()
        if self._thread.is_alive():
            self._thread.join()
        with self._lock:
            for _, future in self._work:
                future.cancel()
            self._work.clear()

    def submit(self, action: Callable[[GroundStation], T],
               first: bool = False) -> concurrent.futures.Future[T]:
        """Run ``action(station)`` on the loop's thread (rule 1); ``first`` puts it ahead of
        the work waiting."""
        future: concurrent.futures.Future[T] = concurrent.futures.Future()
        with self._lock:
            if self._ended:
                future.set_exception(GroundError(_ENDED))
            elif self._stopping.is_set():
                future.cancel()
            elif first:
                self._work.appendleft((action, future))
            else:
                self._work.append((action, future))
        return future

    def request(self, request: Request, owner: int) -> concurrent.futures.Future[dict[str, Any]]:
        """Carry out one of the page's requests (``ground.web.requests``) for the page
        ``owner`` (its connection's number); the result is the reply's fields."""
        return self.submit(lambda station: self._execute(request, owner),
                           first=request.command == "estop")

    def disconnected(self, owner: int) -> concurrent.futures.Future[None]:
        """The page ``owner`` went away: if it was driving, stop now (rule 4)."""
        return self.submit(lambda station: self._teleop_off(owner), first=True)

    def memory_file(self, system_id: int, kind: str, key: int) -> concurrent.futures.Future[bytes]:
        """The bytes of ``/memory/<kind>/<key>.png`` of vehicle ``system_id`` (rule 5)."""
        return self.submit(lambda station: self._memory_file(system_id, kind, key))

    def teaching_file(self, system_id: int, key: int) -> concurrent.futures.Future[bytes]:
        """The thumbnail of key image ``key`` of the path vehicle ``system_id`` is teaching
        (``/teaching/<key>.png``; not cached: a path dropped frees its ids)."""
        return self.submit(lambda station: self._teaching_file(system_id, key))

    def video_stream(self, system_id: int,
                     refresh: bool = False) -> concurrent.futures.Future[VideoStream]:
        """Vehicle ``system_id``'s video stream (rule 6)."""
        return self.submit(lambda station: self._video_stream(system_id, refresh))

    def goto_photo(self, system_id: int, photo: bytes,
                   suffix: str) -> concurrent.futures.Future[PhotoGoal]:
        """Send vehicle ``system_id`` to where ``photo`` (checked, ``suffix`` ``.png`` or
        ``.jpg``) was taken; the answer names the key image it was found at."""
        return self.submit(lambda station: self._goto_photo(system_id, photo, suffix))

    def forget_video_stream(self, system_id: int) -> None:
        """The stream of ``system_id`` did not open: ask its camera again next time (rule 6)."""
        self.submit(lambda station: self._streams.pop(system_id, None))

    # -- the loop -------------------------------------------------------------------------

    def _run(self) -> None:
        try:
            self._serve()
        except Exception:  # the link itself failed (closed socket...): nothing more to do
            _log.exception("the ground station's loop ended")
        finally:
            with self._lock:
                self._ended = True
                work, self._work = list(self._work), collections.deque()
            for _, future in work:
                if future.set_running_or_notify_cancel():
                    future.set_exception(GroundError(_ENDED))

    def _serve(self) -> None:
        try:
            while not self._stopping.is_set():
                self.station.run_until(self._has_work, POLL_NS)
                self._due()
                while (item := self._take()) is not None:
                    action, future = item
                    if future.set_running_or_notify_cancel():
                        try:
                            future.set_result(action(self.station))
                        except BaseException as e:  # handed to the caller, who reports it
                            future.set_exception(e)
                    self._due()
        finally:
            if self._teleop_owner is not None:
                self._teleop_off(self._teleop_owner)

    def _has_work(self) -> bool:
        return bool(self._work) or self._stopping.is_set()

    def _take(self) -> tuple[Callable[[GroundStation], Any],
                             concurrent.futures.Future[Any]] | None:
        with self._lock:
            return self._work.popleft() if self._work else None

    def _due(self) -> None:
        """Send what is due: a teleop tick (rule 4), an update (rule 3)."""
        now_ns = self.clock.now_ns()
        if self._teleop_owner is not None and now_ns >= self._next_tick_ns:
            self.station.send_manual_control(*self._deadman.command(now_ns))
            self._next_tick_ns = max(self._next_tick_ns + PERIOD_NS, now_ns)
        last = self._last_publish_ns
        if (last is None or (self._dirty and now_ns - last >= PUBLISH_NS)
                or now_ns - last >= QUIET_PUBLISH_NS):
            self._publish_update(now_ns)

    def _on_message(self, vehicle: VehicleState, msg: Any) -> None:
        self._dirty = True
        if msg.get_type() == "VISUAL_SERVO_STATUS" and msg.current_key >= 0:
            self._last_key[vehicle.system_id] = (msg.current_key, self.clock.now_ns())
        sample = sample_json(msg, (self.clock.now_ns() - self._start_ns) / NS_PER_S)
        if sample is not None:
            self._samples.setdefault(vehicle.system_id, []).append(sample)
        self._due()

    def _on_packet(self, direction: str, packet: bytes, msg: Message, now_ns: int) -> None:
        if direction == "in":
            self._quality.packet(msg.get_srcSystem(), msg.get_srcComponent(), msg.get_seq())

    def _publish_update(self, now_ns: int) -> None:
        vehicles = sorted(self.station.fleet.vehicles.values(), key=lambda v: v.system_id)
        notices = {}
        for vehicle in vehicles:
            sent = self._notices_sent.get(vehicle.system_id, 0)
            if len(vehicle.notices) > sent:
                notices[str(vehicle.system_id)] = vehicle.notices[sent:]
                self._notices_sent[vehicle.system_id] = len(vehicle.notices)
        selected = self.station.vehicle
        update = {
            "type": "update",
            "t": round((now_ns - self._start_ns) / NS_PER_S, 3),
            "vehicles": [vehicle_json(v, now_ns, self._quality.received_share(v.system_id))
                         for v in vehicles],
            "selected": selected.system_id if selected is not None else None,
            "teleop_owner": self._teleop_owner,
            "samples": {str(k): v for k, v in self._samples.items()},
            "notices": notices,
        }
        self._samples = {}
        self._dirty = False
        self._last_publish_ns = now_ns
        self._publish(update)

    # -- requests (on the loop's thread) --------------------------------------------------

    def _aim(self, system_id: int | None) -> VehicleState:
        """Aim the station's clients at ``system_id`` (None: the vehicle aimed at already,
        else the first heard)."""
        station = self.station
        current = station.vehicle
        if current is not None and system_id in (None, current.system_id):
            return current
        if system_id is not None and system_id not in station.fleet.vehicles:
            heard = ", ".join(map(str, sorted(station.fleet.vehicles))) or "none"
            raise InputError("system", f"vehicle {system_id} not heard (heard: {heard})")
        self._teleop_off(self._teleop_owner)  # its ticks would go to the new vehicle
        station.system_id = system_id
        return station.wait_vehicle(self._timeout_s)

    def _execute(self, request: Request, owner: int) -> dict[str, Any]:
        station = self.station
        command, args = request.command, request.args
        vehicle = self._aim(request.system_id)
        who = f"vehicle {vehicle.system_id}"
        if command == "drive":
            if self._teleop_owner != owner:
                raise InputError("drive", "this page is not driving: switch teleop on first")
            self._deadman.hold(args["x"], args["r"], self.clock.now_ns())
            self._due()
            return {}
        if command == "select":
            for msg_id in _PLOTTED:
                station.command_long(mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, msg_id,
                                     PLOT_INTERVAL_US)
            return {"text": f"{who} selected"}
        if command == "estop":
            self._teleop_off(self._teleop_owner)
            station.emergency_stop()
            return {"text": f"{who}: emergency stop accepted; holding until armed"}
        if command == "arm":
            station.arm()
            return {"text": f"{who}: armed"}
        if command in ("hold", "mode"):
            mode = Mode.HOLD if command == "hold" else args["mode"]
            if mode is not Mode.MANUAL:
                self._teleop_off(self._teleop_owner)
            station.set_mode(mode)
            return {"text": f"{who}: mode {mode.name}"}
        if command == "goto":
            return self._goto(vehicle, (args["key"],))
        if command == "mission":
            return self._goto(vehicle, args["keys"])
        if command == "route":
            return self._route(vehicle, args["key"])
        if command == "params":
            return {"params": station.fetch_params()}
        if command == "param_set":
            value = station.set_param(args["name"], args["value"])
            return {"text": f"{who}: {args['name']} = {value:g}", "name": args["name"],
                    "value": value}
        if command == "teach_start":
            station.teach_start(args["name"])
            return {"text": f"{who}: teaching {args['name']!r}"}
        if command == "teach_stop":
            station.teach_stop()
            return {"text": f"{who}: teaching stopped"}
        if command == "teleop":
            return self._teleop(vehicle, owner, args["on"])
        if command == "memory":
            index = self._memory_index(vehicle.system_id, args["refresh"])
            return {"memory": index.to_json()}
        if command == "camera":
            stream = self._video_stream(vehicle.system_id, args["refresh"])
            return {"camera": {"uri": stream.uri, "width": stream.width_px,
                               "height": stream.height_px, "rate_hz": stream.rate_hz,
                               "name": stream.name,
                               "url": f"/api/vehicles/{vehicle.system_id}/camera.mjpg"}}
        raise InputError("cmd", f"unknown command {command!r}")  # parse_request stops these

    def _goto_photo(self, system_id: int, photo: bytes, suffix: str) -> PhotoGoal:
        self._aim(system_id)
        return self.station.goto_photo(photo, suffix)

    def _goto(self, vehicle: VehicleState, keys: tuple[int, ...]) -> dict[str, Any]:
        """Upload ``keys`` as the mission's goals, in order, and start it."""
        index = self._indexes.get(vehicle.system_id)
        if index is not None and any(k not in index.keyframes for k in keys):
            index = self._memory_index(vehicle.system_id, True)  # taught since?
        missing = [] if index is None else [k for k in keys if k not in index.keyframes]
        if missing:
            raise InputError("key", f"vehicle {vehicle.system_id}'s memory has no key image "
                                    f"{missing[0]} ({len(index.keyframes)} key images)")
        self.station.upload_goals([Goal(k) for k in keys])
        self.station.start_mission()
        if len(keys) == 1:
            return {"text": f"vehicle {vehicle.system_id}: going to key image {keys[0]}"}
        return {"text": f"vehicle {vehicle.system_id}: mission of {len(keys)} goals: "
                        f"key images {', '.join(map(str, keys))}"}

    def _route(self, vehicle: VehicleState, goal: int) -> dict[str, Any]:
        """The key images the vehicle would pass to reach ``goal`` (rule 6)."""
        index = self._memory_index(vehicle.system_id, False)
        if goal not in index.keyframes:
            raise InputError("key", f"vehicle {vehicle.system_id}'s memory has no key image "
                                    f"{goal} ({len(index.keyframes)} key images)")
        last = self._last_key.get(vehicle.system_id)
        if last is None:
            return {"start": None, "route": [], "text": f"key image {goal}: the start is "
                    f"unknown (vehicle {vehicle.system_id} has not said where it is)"}
        start, when_ns = last
        age_s = (self.clock.now_ns() - when_ns) / NS_PER_S
        try:
            route = index.plan_route(start, goal)
        except UnknownKeyframeError:
            return {"start": start, "route": [], "text": f"key image {goal}: the start, key "
                    f"image {start}, is not in the memory loaded (Refresh?)"}
        if not route:
            text = f"key image {goal}: no route from key image {start} (the paths run one way)"
        else:
            text = (f"key image {goal}: {len(route)} key images from key image {start} "
                    f"(where the vehicle was {age_s:.0f} s ago)")
        return {"start": start, "route": route, "text": text}

    def _teleop(self, vehicle: VehicleState, owner: int, on: bool) -> dict[str, Any]:
        who = f"vehicle {vehicle.system_id}"
        if not on:
            self._teleop_off(owner)
            return {"text": f"{who}: teleop off"}
        if self._teleop_owner not in (None, owner):
            raise InputError("teleop", f"{who} is driven from another page")
        self.station.set_mode(Mode.MANUAL)
        self._deadman.release()
        self._teleop_owner, self._next_tick_ns = owner, self.clock.now_ns()
        self._dirty = True
        self._due()
        return {"text": f"{who}: teleop on (MANUAL); release the keys or stick to stop"}

    def _teleop_off(self, owner: int | None) -> None:
        """Stop driving if ``owner`` drives: one all-zero MANUAL_CONTROL (rule 4)."""
        if owner is None or owner != self._teleop_owner:
            return
        self._deadman.release()
        self._teleop_owner = None
        self._dirty = True
        if self.station.vehicle is not None:
            self.station.send_manual_control(0.0, 0.0)

    def _memory_index(self, system_id: int, refresh: bool) -> MemoryIndex:
        index = self._indexes.get(system_id)
        if index is None or refresh:
            self._aim(system_id)
            index = memory_index_from_manifest(self.station.ftp_get(MANIFEST_PATH))
            self._indexes[system_id] = index
        return index

    def _video_stream(self, system_id: int, refresh: bool) -> VideoStream:
        stream = self._streams.get(system_id)
        if stream is None or refresh:
            self._aim(system_id)
            stream = self._streams[system_id] = find_video_stream(self.station)
        return stream

    def _teaching_file(self, system_id: int, key: int) -> bytes:
        self._aim(system_id)
        return self.station.ftp_get(f"{TEACHING_ROOT}/{key}.png")

    def _memory_file(self, system_id: int, kind: str, key: int) -> bytes:
        if kind not in MEMORY_FILES:
            raise InputError("kind", f"{kind!r:.40} is not one of {sorted(MEMORY_FILES)}")
        path = f"{MEMORY_ROOT}/{kind}/{key}.png"
        data = self._files.get((system_id, path))
        if data is not None:
            self._files.move_to_end((system_id, path))
            return data
        self._aim(system_id)
        data = self.station.ftp_get(path)
        self._files[(system_id, path)] = data
        self._file_bytes += len(data)
        while self._file_bytes > CACHE_BYTES and len(self._files) > 1:
            _, dropped = self._files.popitem(last=False)
            self._file_bytes -= len(dropped)
        return data
