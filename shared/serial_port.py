"""SerialLink: a :class:`~shared.byte_link.ByteLink` over a serial port (pyserial).

The one adapter for serial lines: the Pioneer's port (``robot.pioneer.serial_link``), a
SiK telemetry radio carrying MAVLink (``serial:/dev/ttyUSB0:57600``, robot and ground),
a pty (``vmnav sim serve --aria pty:PATH``, tests) and any other pyserial URL
(``loop://``, ``socket://``). pyserial's exceptions are translated here and nowhere else
(STYLE.md sec. 6): failing to open raises :class:`TransportError`, failing to read
or write an open link raises :class:`LinkClosedError`; both name the URL.
"""

from __future__ import annotations

import os
import termios

import serial

from shared.byte_link import LinkClosedError
from shared.errors import TransportError

__all__ = ["SerialLink", "is_device"]

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
    def open(cls, url: str, baud: int = 9600, write_timeout_s: float = 0.5) -> SerialLink:
        """Open ``url`` (``serial.serial_for_url``), non-blocking reads.

        Args:
            url: a device or pty path, ``socket://host:port`` or ``loop://``.
            baud: line rate, baud (ignored by URLs with a scheme).
            write_timeout_s: a write that cannot finish in this long fails, s.

        Raises:
            TransportError: the URL is malformed, the device is missing or busy, or the
                connection is refused (one line naming the URL).
        """
        if is_device(url) and not os.path.exists(url):
            raise TransportError(url, "no such device (unplugged? see ls /dev/serial/by-id)")
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

    def fileno(self) -> int:
        """The port's descriptor, for ``select`` (devices and ptys only)."""
        return int(self._port.fileno())

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


def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split()) or type(error).__name__
