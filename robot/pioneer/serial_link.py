"""SerialLink: a :class:`~shared.byte_link.ByteLink` over any pyserial URL.

One adapter for every way to reach the robot: a device (``/dev/ttyUSB0``), a pty
(``/dev/pts/3``), TCP (``socket://host:8101``, MobileSim's and the emulator's port)
and ``loop://``. pyserial's exceptions are translated here and nowhere else
(STYLE.md sec. 6): failing to open raises :class:`TransportError`, failing to read
or write an open link raises :class:`LinkClosedError`; both name the URL.

Baud rates (reference §9): ARCOS listens at 9600 after power-up, but an earlier
client may have left it at another rate with HOSTBAUD. :func:`serial_link_factory`
therefore alternates 9600 and the configured rate between connect attempts on a
device; URLs with a scheme have no baud rate.
"""

from __future__ import annotations

import itertools
import termios
from collections.abc import Callable

import serial

from shared.byte_link import LinkClosedError
from shared.errors import TransportError

ARCOS_BAUD = 9600
"""The robot's serial rate after power-up (ArRobotConnector's default too)."""
READ_CHUNK = 65536
"""Most bytes one ``read_available`` call returns."""


def is_device(url: str) -> bool:
    """Whether ``url`` names a device or pty path (not ``socket://``, ``loop://``, ...)."""
    return "://" not in url


class SerialLink:
    """A non-blocking byte link on an open pyserial port.

    Args:
        port: an open port with ``timeout=0``.
        url: where it leads, for messages.
    """

    def __init__(self, port: serial.SerialBase, url: str) -> None:
        self._port = port
        self.url = url

    @classmethod
    def open(cls, url: str, baud: int = ARCOS_BAUD, write_timeout_s: float = 0.5) -> SerialLink:
        """Open ``url`` (``serial.serial_for_url``), non-blocking reads.

        Args:
            url: a device or pty path, ``socket://host:port`` or ``loop://``.
            baud: line rate, baud (ignored by URLs with a scheme).
            write_timeout_s: a write that cannot finish in this long fails, s.

        Raises:
            TransportError: the URL is malformed, the device is missing or busy, or the
                connection is refused (one line naming the URL).
        """
        try:
            port = serial.serial_for_url(url, baudrate=baud, timeout=0,
                                         write_timeout=write_timeout_s)
            if is_device(url):
                port.reset_input_buffer()  # stale bytes of an earlier run (reference §9)
        except (serial.SerialException, OSError, ValueError) as e:
            raise TransportError(url, f"cannot open at {baud} baud: {_one_line(e)}") from None
        return cls(port, url)

    @property
    def baud(self) -> int:
        """The port's line rate, baud."""
        return int(self._port.baudrate)

    def write(self, data: bytes) -> None:
        """Send ``data``.

        Raises:
            LinkClosedError: the port or socket is gone, or the write timed out.
        """
        try:
            self._port.write(data)
        except (serial.SerialException, OSError) as e:
            raise LinkClosedError(self.url, f"write failed: {_one_line(e)}") from None

    def read_available(self) -> bytes:
        """Whatever has arrived (b"" if nothing), without waiting.

        Raises:
            LinkClosedError: the device was unplugged, the pty master or the peer closed.
        """
        try:
            return bytes(self._port.read(READ_CHUNK))
        except (serial.SerialException, OSError) as e:
            raise LinkClosedError(self.url, f"read failed: {_one_line(e)}") from None

    def close(self) -> None:
        """Let queued bytes drain, then close; idempotent, never raises."""
        if not self._port.is_open:
            return
        try:
            self._port.flush()
        except (serial.SerialException, OSError, termios.error):
            pass  # the device or peer is gone: nothing left to drain
        finally:
            self._port.close()


def serial_link_factory(url: str, baud: int,
                        write_timeout_s: float = 0.5) -> Callable[[], SerialLink]:
    """A ``link_factory`` for :class:`~robot.pioneer.driver.PioneerDriver`.

    Each call opens ``url`` anew. On a device the rate alternates 9600, ``baud``, 9600,
    ... (just 9600 if ``baud`` is 9600); other URLs open at ``baud`` every time.

    Args:
        url: a pyserial URL (see :meth:`SerialLink.open`).
        baud: the configured rate, baud.
        write_timeout_s: write timeout, s.
    """
    rates = (itertools.cycle(dict.fromkeys((ARCOS_BAUD, baud))) if is_device(url)
             else itertools.repeat(baud))

    def open_next() -> SerialLink:
        return SerialLink.open(url, next(rates), write_timeout_s)

    return open_next


def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split()) or type(error).__name__
