"""Real byte links for the emulated Pioneer: a pseudo-terminal here; TCP clients and the
TCP listener are :mod:`shared.stream_link`'s (re-exported, the robot uses them too).

The links are :class:`shared.byte_link.ByteLink` adapters, non-blocking, each owning
its file descriptor or socket (see :mod:`shared.stream_link` for what a full buffer and
OS errors do).
"""

from __future__ import annotations

import os
import tty
from pathlib import Path

from shared.errors import TransportError
from shared.stream_link import READ_LIMIT, StreamLink, TcpListener, fd_io

__all__ = ["READ_LIMIT", "PtyLink", "StreamLink", "TcpListener"]


class PtyLink(StreamLink):
    """The master end of a new pseudo-terminal; a client opens :attr:`path` as its serial port.

    The slave end stays open here too, so the terminal survives between clients and
    the master never reads end-of-file; it is put in raw mode (no echo, no line
    editing, no CR/LF translation), so bytes pass as they are.

    Args:
        symlink: also point this symbolic link at the slave (e.g. ``/tmp/vmnav-pioneer``);
            an existing symlink there is replaced, and the link is removed on close.

    Raises:
        TransportError: no pty can be opened, or the symlink cannot be made.
    """

    def __init__(self, symlink: Path | None = None) -> None:
        try:
            master, slave = os.openpty()
        except OSError as e:
            raise TransportError("pty", f"cannot open a pseudo-terminal: {e.strerror}") from None
        tty.setraw(slave)
        os.set_blocking(master, False)
        self._master, self._slave = master, slave
        self.path = os.ttyname(slave)
        """The slave's device path, for the client."""
        self.symlink = symlink
        super().__init__(self.path, *fd_io(master), release=self._release_pty, fd=master)
        if symlink is not None:
            try:
                if symlink.is_symlink():
                    symlink.unlink()
                symlink.symlink_to(self.path)
            except OSError as e:
                self.symlink = None
                self.close()
                raise TransportError(symlink, f"cannot link to {self.path}: {e.strerror}") from None

    def _release_pty(self) -> None:
        os.close(self._master)
        os.close(self._slave)
        if self.symlink is not None:
            self.symlink.unlink(missing_ok=True)
