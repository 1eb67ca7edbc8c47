"""The simulator's control endpoint: its ground truth and the hand that places the robot.

What a person standing in the room has, and a robot never gets: where the robot
really is, and the power to carry it somewhere. ``vmnav demo --hil`` drives through
it: the scripted teleoperator steers by the true pose (as a person steers by eye),
the evaluation compares true trajectories, and the robot is carried to the repeat's
start.

Rules:

1. ``GET /truth``: ``{"t_ns": simulation time, "pose_w": [x_m, y_m, yaw_rad]}`` of
   the robot's body in the world frame, as of the last simulation step.
2. ``POST /place`` with ``{"pose_w": [x_m, y_m, yaw_rad]}`` as ``Content-Type:
   application/json``: the robot is put at rest there
   (:meth:`sim.simulation.Simulation.place_robot`) at the next simulation step; the
   reply (200 with the new truth, or 400 with a one-line reason: bad JSON, numbers
   that are not finite, a position outside the world's walls, an obstacle there)
   comes once it is done.
3. Threads: the simulation is only touched in its own loop (:class:`ControlHook`, a
   step hook); HTTP requests wait on it. Loopback by default; anything else is 404.
4. Hostile clients (:mod:`sim.guarded_http`): idle connections hold no thread, handler
   threads are bounded, a cross-origin request (a web page in a browser on the same
   machine) is refused (403), and so is a body that is not JSON (415) or too long (413).
"""

from __future__ import annotations

import json
import math
import queue
import threading
from dataclasses import dataclass, field
from typing import Any

from shared.errors import TransportError, VmnavError
from shared.pose import Pose2
from sim.guarded_http import GuardedHandler, GuardedHTTPServer, HttpLimits, RequestRefusedError
from sim.simulation import Simulation

TRUTH_PATH = "/truth"
PLACE_PATH = "/place"
#: How long a placement waits for the simulation loop, s.
_PLACE_TIMEOUT_S = 5.0
PLACE_FORMAT = 'want {"pose_w": [x_m, y_m, yaw_rad]}'
"""The start of every refusal of a malformed placement."""


@dataclass(eq=False)
class _Placement:
    pose_w: Pose2
    done: threading.Event = field(default_factory=threading.Event)
    error: str | None = None


class ControlHook:
    """The simulation side (rule 3): publishes the truth, applies placements.

    A step hook: ``sim.add_step_hook(hook)``.
    """

    def __init__(self, sim: Simulation) -> None:
        self._sim = sim
        self._placements: queue.SimpleQueue[_Placement] = queue.SimpleQueue()
        self.truth: dict[str, Any] = self._truth()
        """The last published truth (rule 1)."""

    def __call__(self, now_ns: int, dt_ns: int) -> None:
        while True:
            try:
                placement = self._placements.get_nowait()
            except queue.Empty:
                break
            try:
                self._sim.place_robot(placement.pose_w)
            except VmnavError as e:
                placement.error = str(e)
            placement.done.set()
        self.truth = self._truth()

    def place(self, pose_w: Pose2) -> str | None:
        """Place the robot at the next step (rule 2); None when done, else why not."""
        placement = _Placement(pose_w)
        self._placements.put(placement)
        if not placement.done.wait(_PLACE_TIMEOUT_S):
            return f"the simulation did not step within {_PLACE_TIMEOUT_S:.0f} s"
        return placement.error

    def _truth(self) -> dict[str, Any]:
        return {"t_ns": self._sim.now_ns, "pose_w": list(self._sim.body.pose_w)}

    def extent(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """The world's walls' bounding box ((x_min, y_min), (x_max, y_max)), m."""
        return self._sim.world.extent()


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
    pose = body.get("pose_w") if isinstance(body, dict) else None
    if not isinstance(pose, list):
        raise ValueError(f"{PLACE_FORMAT}: got {_short(body)}")
    if len(pose) != 3:
        raise ValueError(f"{PLACE_FORMAT}: expected 3 numbers, got {len(pose)}")
    names = ("x_m", "y_m", "yaw_rad")
    for name, value in zip(names, pose, strict=True):
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{PLACE_FORMAT}: {name} {_short(value)} is not a number")
    try:
        x, y, yaw = (float(v) for v in pose)
    except OverflowError:
        raise ValueError(f"{PLACE_FORMAT}: a number is not finite") from None
    for name, value in zip(names, (x, y, yaw), strict=True):
        if not math.isfinite(value):
            raise ValueError(f"{PLACE_FORMAT}: {name} {value} is not finite")
    (x_min, y_min), (x_max, y_max) = extent
    if not (x_min <= x <= x_max and y_min <= y <= y_max):
        raise ValueError(f"pose_w ({x:g}, {y:g}) is outside the world's walls, "
                         f"x {x_min:g}..{x_max:g} m, y {y_min:g}..{y_max:g} m")
    return Pose2(x, y, yaw)


def _short(value: object) -> str:
    """``value``'s repr, cut to 40 characters (a reply line, not an echo of the request)."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


class ControlServer:
    """The HTTP side (rules 1-3).

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
        else:
            self._reply(404, {"error": f"no {self.path}"})

    def do_POST(self) -> None:  # noqa: N802 - http.server names the method
        try:
            if (refused := self.refusal()) is not None:
                raise refused
            if self.path != PLACE_PATH:
                raise RequestRefusedError(404, f"no {self.path}")
            pose = placement_pose(self.read_json(), self.hook.extent())
        except RequestRefusedError as e:
            self._reply(e.status, {"error": e.reason})
            return
        except ValueError as e:
            self._reply(400, {"error": str(e)})
            return
        error = self.hook.place(pose)
        if error is None:
            self._reply(200, {"t_ns": self.hook.truth["t_ns"], "pose_w": list(pose)})
        else:
            self._reply(400, {"error": error})

    def _reply(self, status: int, data: dict[str, Any]) -> None:
        body = json.dumps(data).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, format: str, *args: Any) -> None:
        """Quiet: requests are not news."""
