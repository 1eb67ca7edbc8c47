"""The simulator's control endpoint: its ground truth and the hand that places things.

What a person standing in the room has, and a robot never gets: where the robot
really is, and the power to carry it somewhere or to put a box in its way.
``vmnav demo --hil`` drives through it: the scripted teleoperator steers by the true
pose (as a person steers by eye), the evaluation compares true trajectories, and the
robot is carried to the repeat's start. Safety scenarios put a box on a taught
route and take it away again.

Rules:

1. ``GET /truth``: ``{"t_ns": simulation time, "pose_w": [x_m, y_m, yaw_rad]}`` of
   the robot's body in the world frame, as of the last simulation step.
2. ``POST /place`` with ``{"pose_w": [x_m, y_m, yaw_rad]}`` as ``Content-Type:
   application/json``: the robot is put at rest there
   (:meth:`sim.simulation.Simulation.place_robot`) at the next simulation step; the
   reply (200 with the new truth, or 400 with a one-line reason: bad JSON, numbers
   that are not finite, a position outside the world's walls, an obstacle there)
   comes once it is done.
3. ``POST /obstacles`` with ``{"pose_w": [x_m, y_m, yaw_rad], "size_m": [length_m,
   width_m, height_m], "sonar": true}`` (``sonar`` optional, default true; false: a
   box the sonar never hears, see :class:`~sim.decor.PlacedObject`): a box standing on
   the floor, its centre at (x_m, y_m) in the world frame, its length along yaw_rad,
   is put in the world at the next simulation step
   (:meth:`~sim.simulation.Simulation.add_object`): solid, heard by the sonar, drawn
   by the camera. The reply is 200 with ``{"id": n, "t_ns": ...}`` and the box as
   placed, or 400 with a one-line reason (bad JSON, numbers that are not finite, a
   side outside [:data:`MIN_SIDE_M`, :data:`MAX_SIDE_M`], a centre outside the
   world's walls, a box on the robot, already :data:`MAX_OBSTACLES` boxes).
   ``GET /obstacles`` lists them: ``{"obstacles": [{"id": n, "pose_w": ..., "size_m":
   ..., "sonar": ...}, ...]}``. ``DELETE /obstacles/<id>`` takes one away at the next
   step: 200 with ``{"id": n, "t_ns": ...}``, or 404 when there is no such box.
4. Threads: the simulation is only touched in its own loop (:class:`ControlHook`, a
   step hook); HTTP requests wait on it. Loopback by default; anything else is 404.
5. Hostile clients (:mod:`shared.guarded_http`): idle connections hold no thread, handler
   threads are bounded, a cross-origin request (a web page in a browser on the same
   machine) is refused (403), and so is a body that is not JSON (415) or too long (413).
"""

from __future__ import annotations

import json
import math
import queue
import re
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from shared.errors import InputError, TransportError, VmnavError
from shared.guarded_http import GuardedHandler, GuardedHTTPServer, HttpLimits, RequestRefusedError
from shared.pose import Pose2
from sim.decor import PlacedObject
from sim.simulation import Simulation

TRUTH_PATH = "/truth"
PLACE_PATH = "/place"
OBSTACLES_PATH = "/obstacles"
_OBSTACLE_PATH = re.compile(r"/obstacles/([0-9]{1,9})")
#: How long a request waits for the simulation loop, s.
_STEP_TIMEOUT_S = 5.0
PLACE_FORMAT = 'want {"pose_w": [x_m, y_m, yaw_rad]}'
"""The start of every refusal of a malformed placement."""
OBSTACLE_FORMAT = ('want {"pose_w": [x_m, y_m, yaw_rad], "size_m": [length_m, width_m, '
                   'height_m], "sonar": true}')
"""The start of every refusal of a malformed box."""
MIN_SIDE_M = 0.05
"""Smallest side of a box placed through the endpoint, m."""
MAX_SIDE_M = 5.0
"""Largest side of a box placed through the endpoint, m."""
MAX_OBSTACLES = 32
"""Boxes placed through the endpoint at once, at most."""


@dataclass(eq=False)
class _Request:
    """Work for the simulation loop: ``run`` returns the reply's data or raises."""

    run: Callable[[], dict[str, Any]]
    done: threading.Event = field(default_factory=threading.Event)
    reply: dict[str, Any] | None = None
    error: str | None = None


class ControlHook:
    """The simulation side (rule 4): publishes the truth, applies placements and boxes.

    A step hook: ``sim.add_step_hook(hook)``.
    """

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self._requests: queue.SimpleQueue[_Request] = queue.SimpleQueue()
        self.truth: dict[str, Any] = self._truth()
        """The last published truth (rule 1)."""

    def __call__(self, now_ns: int, dt_ns: int) -> None:
        while True:
            try:
                request = self._requests.get_nowait()
            except queue.Empty:
                break
            try:
                request.reply = request.run()
            except VmnavError as e:
                request.error = str(e)
            request.done.set()
        self.truth = self._truth()

    def _in_loop(self, run: Callable[[], dict[str, Any]]) -> tuple[dict[str, Any] | None,
                                                                   str | None]:
        """``run()`` in the simulation loop at its next step: (reply, None) or (None, why not)."""
        request = _Request(run)
        self._requests.put(request)
        if not request.done.wait(_STEP_TIMEOUT_S):
            return None, f"the simulation did not step within {_STEP_TIMEOUT_S:.0f} s"
        return request.reply, request.error

    def place(self, pose_w: Pose2) -> str | None:
        """Place the robot at the next step (rule 2); None when done, else why not."""
        def run() -> dict[str, Any]:
            self._sim.place_robot(pose_w)
            return {}
        return self._in_loop(run)[1]

    def add_obstacle(self, box: PlacedObject) -> tuple[dict[str, Any] | None, str | None]:
        """Put ``box`` in the world at the next step (rule 3): (its description with its
        id and the time, None), or (None, why not)."""
        def run() -> dict[str, Any]:
            if len(self._sim.added_objects) >= MAX_OBSTACLES:
                raise InputError(OBSTACLES_PATH, f"already {MAX_OBSTACLES} boxes placed; "
                                                 "delete one first")
            object_id = self._sim.add_object(box)
            return {**_described(object_id, box), "t_ns": self._sim.now_ns}
        return self._in_loop(run)

    def remove_obstacle(self, object_id: int) -> str | None:
        """Take away box ``object_id`` at the next step (rule 3); None when done, else why not."""
        def run() -> dict[str, Any]:
            self._sim.remove_object(object_id)
            return {}
        return self._in_loop(run)[1]

    def obstacles(self) -> tuple[dict[str, Any] | None, str | None]:
        """The boxes placed so far (rule 3), read in the simulation loop: (them, None), or
        (None, why not)."""
        def run() -> dict[str, Any]:
            return {"obstacles": [_described(i, box)
                                  for i, box in self._sim.added_objects.items()]}
        return self._in_loop(run)

    def _truth(self) -> dict[str, Any]:
        return {"t_ns": self._sim.now_ns, "pose_w": list(self._sim.body.pose_w)}

    def extent(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The world's walls' bounding box ((x_min, y_min), (x_max, y_max)), m."""
        return self._sim.world.extent()


def _described(object_id: int, box: PlacedObject) -> dict[str, Any]:
    """A box as ``GET /obstacles`` lists it (rule 3)."""
    (x, y), (length, width), yaw_deg = box.footprint()
    return {"id": object_id, "pose_w": [x, y, math.radians(yaw_deg)],
            "size_m": [length, width, box.height_m], "sonar": box.sonar}


def placement_pose(body: object,
                   extent: tuple[tuple[float, float], tuple[float, float]]) -> Pose2:
    """The pose of a ``POST /place`` body (rule 2).

    Args:
        body: the parsed JSON.
        extent: the world's bounding box ((x_min, y_min), (x_max, y_max)), m.

    Raises:
        ValueError: the body is not ``{"pose_w": [x_m, y_m, yaw_rad]}`` with finite
            numbers and (x_m, y_m) inside ``extent`` (message says which).
    """
    x, y, yaw = _finite_numbers(body, "pose_w", ("x_m", "y_m", "yaw_rad"), PLACE_FORMAT)
    _check_inside(x, y, extent)
    return Pose2(x, y, yaw)


def obstacle_box(body: object,
                 extent: tuple[tuple[float, float], tuple[float, float]]) -> PlacedObject:
    """The box of a ``POST /obstacles`` body (rule 3).

    Args:
        body: the parsed JSON.
        extent: the world's bounding box ((x_min, y_min), (x_max, y_max)), m.

    Raises:
        ValueError: the body is not ``{"pose_w": [x_m, y_m, yaw_rad], "size_m":
            [length_m, width_m, height_m]}`` (and an optional boolean ``sonar``) with
            finite numbers, (x_m, y_m) inside ``extent`` and every side in
            [MIN_SIDE_M, MAX_SIDE_M] (message says which).
    """
    if not isinstance(body, dict):
        raise ValueError(f"{OBSTACLE_FORMAT}: got {_short(body)}")
    x, y, yaw = _finite_numbers(body, "pose_w", ("x_m", "y_m", "yaw_rad"), OBSTACLE_FORMAT)
    sides = _finite_numbers(body, "size_m", ("length_m", "width_m", "height_m"),
                            OBSTACLE_FORMAT)
    sonar = body.get("sonar", True)
    if not isinstance(sonar, bool):
        raise ValueError(f"{OBSTACLE_FORMAT}: sonar {_short(sonar)} is not true or false")
    unknown = sorted(set(body) - {"pose_w", "size_m", "sonar"})
    if unknown:
        raise ValueError(f"{OBSTACLE_FORMAT}: unknown field {_short(unknown[0])}")
    for name, side in zip(("length_m", "width_m", "height_m"), sides, strict=True):
        if not MIN_SIDE_M <= side <= MAX_SIDE_M:
            raise ValueError(f"size_m {name} {side:g} is outside "
                             f"[{MIN_SIDE_M:g}, {MAX_SIDE_M:g}] m")
    _check_inside(x, y, extent)
    return PlacedObject("box", (x, y), (sides[0], sides[1]), sides[2],
                        yaw_deg=math.degrees(yaw), sonar=sonar)


def _finite_numbers(body: object, key: str, names: tuple[str, ...],
                    form: str) -> tuple[float, ...]:
    """``body[key]``, a list of ``len(names)`` finite numbers, as floats.

    Raises:
        ValueError: ``body`` is not an object with such a list (message starts with
            ``form`` and names the value at fault).
    """
    values = body.get(key) if isinstance(body, dict) else None
    if not isinstance(values, list):
        raise ValueError(f"{form}: got {_short(body)}")
    if len(values) != len(names):
        raise ValueError(f"{form}: {key} expected {len(names)} numbers, got {len(values)}")
    for name, value in zip(names, values, strict=True):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{form}: {name} {_short(value)} is not a number")
    try:
        floats = tuple(float(v) for v in values)
    except OverflowError:
        raise ValueError(f"{form}: a number is not finite") from None
    for name, value in zip(names, floats, strict=True):
        if not math.isfinite(value):
            raise ValueError(f"{form}: {name} {value} is not finite")
    return floats


def _check_inside(x: float, y: float,
                  extent: tuple[tuple[float, float], tuple[float, float]]) -> None:
    """Raises ValueError unless (x, y), m, lies in the bounding box ``extent``."""
    (x_min, y_min), (x_max, y_max) = extent
    if not (x_min <= x <= x_max and y_min <= y <= y_max):
        raise ValueError(f"pose_w ({x:g}, {y:g}) is outside the world's walls, "
                         f"x {x_min:g}..{x_max:g} m, y {y_min:g}..{y_max:g} m")


def _short(value: object) -> str:
    """``value``'s repr, cut to 40 characters (a reply line, not an echo of the request)."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


class ControlServer:
    """The HTTP side (rules 1-4).

    Args:
        hook: the simulation's control hook.
        host: address to listen on.
        port: TCP port; 0 picks a free one (see :attr:`port`).
        limits: what one client may take (rule 4).

    Raises:
        TransportError: the port cannot be listened on.
    """

    def __init__(self, hook: ControlHook, host: str = "127.0.0.1", port: int = 0,
                 limits: HttpLimits | None = None) -> None:
        handler = type("Handler", (_Handler,), {"hook": hook})
        try:
            self._http = GuardedHTTPServer((host, port), handler, limits or HttpLimits())
        except OSError as e:
            raise TransportError(f"http://{host}:{port}", f"cannot listen: {e.strerror}") from None
        self.port: int = self._http.server_address[1]
        self.url = f"http://{host}:{self.port}"
        self._thread = threading.Thread(target=self._http.serve_forever, name="sim-control",
                                        kwargs={"poll_interval": 0.05}, daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop serving; idempotent."""
        if self._thread.is_alive():
            self._http.shutdown()
            self._thread.join()
        self._http.server_close()

    def __enter__(self) -> ControlServer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Handler(GuardedHandler):
    hook: ControlHook

    def do_GET(self) -> None:  # noqa: N802 - http.server names the method
        if (refused := self.refusal()) is not None:
            self._reply(refused.status, {"error": refused.reason})
        elif self.path == TRUTH_PATH:
            self._reply(200, self.hook.truth)
        elif self.path == OBSTACLES_PATH:
            reply, error = self.hook.obstacles()
            if reply is None:
                self._reply(503, {"error": error})
            else:
                self._reply(200, reply)
        else:
            self._reply(404, {"error": f"no {self.path}"})

    def do_POST(self) -> None:  # noqa: N802 - http.server names the method
        try:
            if (refused := self.refusal()) is not None:
                raise refused
            if self.path not in (PLACE_PATH, OBSTACLES_PATH):
                raise RequestRefusedError(404, f"no {self.path}")
            body = self.read_json()
            if self.path == OBSTACLES_PATH:
                box = obstacle_box(body, self.hook.extent())
            else:
                pose = placement_pose(body, self.hook.extent())
        except RequestRefusedError as e:
            self._reply(e.status, {"error": e.reason})
            return
        except ValueError as e:
            self._reply(400, {"error": str(e)})
            return
        if self.path == OBSTACLES_PATH:
            reply, error = self.hook.add_obstacle(box)
        else:
            error = self.hook.place(pose)
            reply = {"t_ns": self.hook.truth["t_ns"], "pose_w": list(pose)}
        if error is None and reply is not None:
            self._reply(200, reply)
        else:
            self._reply(400, {"error": error})

    def do_DELETE(self) -> None:  # noqa: N802 - http.server names the method
        if (refused := self.refusal()) is not None:
            self._reply(refused.status, {"error": refused.reason})
            return
        match = _OBSTACLE_PATH.fullmatch(self.path)
        if match is None:
            self._reply(404, {"error": f"no {self.path}"})
            return
        object_id = int(match.group(1))
        error = self.hook.remove_obstacle(object_id)
        if error is None:
            self._reply(200, {"id": object_id, "t_ns": self.hook.truth["t_ns"]})
        else:
            self._reply(404, {"error": error})

    def _reply(self, status: int, data: dict[str, Any]) -> None:
        body = json.dumps(data).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, format: str, *args: Any) -> None:
        """Quiet: requests are not news."""
