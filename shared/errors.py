"""The project's error tree.

Every error vmnav raises on purpose derives from :class:`VmnavError`; the command
line prints such an error as one line and exits non-zero, anything else is a bug
and keeps its traceback::

    VmnavError
    ├── InputError                 bad input from a file or the user; names where
    │   ├── ConfigError            a config or world file, or a config value
    │   ├── CalibrationError       a camera calibration file or calibration images
    │   └── MemoryFormatError      a visual memory (on disk or being assembled) breaks its format
    ├── UnknownKeyframeError       a key image id the visual memory does not hold (a LookupError)
    ├── IllegalEventError          a state machine got an event its table forbids in that state
    ├── GeometryError              a geometric computation cannot proceed
    │   ├── ShapeError             an array has the wrong shape (also a ValueError)
    │   └── DegenerateGeometryError
    ├── ProtocolError              a byte-level protocol was violated
    │   ├── LocalProtocolError     we tried to send something illegal in this state
    │   └── RemoteProtocolError    the peer sent something illegal
    │       └── ChecksumError      a single frame failed its checksum
    └── TransportError             a port, socket or pipe cannot be opened or is gone

Expected outcomes (no match, link lost, mission rejected) are results or events,
never exceptions.
"""

from __future__ import annotations

from pathlib import Path


class VmnavError(Exception):
    """Root of every error vmnav raises on purpose."""


class InputError(VmnavError):
    """Bad input: a file, a value or an argument, with where it came from.

    Args:
        where: the file path (or ``file: [section] key``) or argument name at fault.
        problem: what is wrong, with the offending value where useful.
    """

    def __init__(self, where: str | Path, problem: str) -> None:
        self.where = str(where)
        self.problem = problem
        super().__init__(f"{self.where}: {problem}")

    def __reduce__(self) -> tuple[type[InputError], tuple[str, str]]:
        """Pickled as its arguments, so that it crosses to and from worker processes."""
        return type(self), (self.where, self.problem)


class ConfigError(InputError):
    """A config file, world file or config value is malformed or out of range."""


class CalibrationError(InputError):
    """A calibration file is malformed, or calibration images cannot be used."""


class MemoryFormatError(InputError):
    """A visual memory breaks its format: a file on disk, or a record being added.

    ``where`` names the file (``mem/features/12.npz``) or the record (``key image 12``).
    """


class UnknownKeyframeError(VmnavError, LookupError):
    """A key image id that the visual memory does not hold.

    Args:
        keyframe_id: the id asked for.
        known: how many key images the memory holds, for the message.
    """

    def __init__(self, keyframe_id: int, known: int) -> None:
        self.keyframe_id = keyframe_id
        self.known = known
        super().__init__(f"no key image with id {keyframe_id} in the memory ({known} key images)")


class IllegalEventError(VmnavError):
    """A state machine got an event that its transition table forbids in the current state.

    A bug in the caller (like h11's ``LocalProtocolError``), not a runtime outcome.

    Args:
        machine: the state machine's name, e.g. ``"mission"``.
        state: the current state's name.
        event: the event's type name.
    """

    def __init__(self, machine: str, state: str, event: str) -> None:
        self.machine = machine
        self.state = state
        self.event = event
        super().__init__(f"{machine}: event {event} is not allowed in state {state}")


class GeometryError(VmnavError):
    """A geometric computation cannot proceed."""


class ShapeError(GeometryError, ValueError):
    """An array argument has the wrong shape."""


class DegenerateGeometryError(GeometryError):
    """The input is geometrically degenerate (e.g. all points collinear)."""


class ProtocolError(VmnavError):
    """A byte-level protocol was violated."""


class LocalProtocolError(ProtocolError):
    """We tried to send an event that is illegal in the current state."""


class RemoteProtocolError(ProtocolError):
    """The peer sent something illegal."""


class ChecksumError(RemoteProtocolError):
    """A single frame failed its checksum.

    Args:
        expected: the checksum computed over the frame.
        actual: the checksum the frame carried.
    """

    def __init__(self, expected: int, actual: int) -> None:
        self.expected = expected
        self.actual = actual
        super().__init__(
            f"checksum mismatch: computed 0x{expected:04X}, frame carries 0x{actual:04X}"
        )


def check_shape(name: str, array_shape: tuple[int, ...], expected: tuple[int | None, ...]) -> None:
    """Raise :class:`ShapeError` unless ``array_shape`` matches ``expected``.

    Args:
        name: the argument's name, for the message.
        array_shape: the shape of the array given.
        expected: the shape wanted; ``None`` matches any length on that axis.

    Raises:
        ShapeError: naming both shapes.
    """
    ok = len(array_shape) == len(expected) and all(
        e is None or e == a for a, e in zip(array_shape, expected, strict=True)
    )
    if not ok:
        dims = ["N" if e is None else str(e) for e in expected]
        want = "(" + ", ".join(dims) + ("," if len(dims) == 1 else "") + ")"
        raise ShapeError(f"{name}: expected shape {want}, got {tuple(array_shape)}")


class TransportError(VmnavError):
    """A byte transport cannot be opened, or went away (port unplugged, socket closed).

    Args:
        where: the transport (a pyserial URL, a pty path, ``tcp:8101``, ``pipe``).
        problem: what went wrong.
    """

    def __init__(self, where: str, problem: str) -> None:
        self.where = where
        self.problem = problem
        super().__init__(f"{where}: {problem}")
