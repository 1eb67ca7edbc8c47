"""Where a command serves over TCP: ``tcp:[HOST:]PORT`` and ``http:[HOST:]PORT`` arguments
(``vmnav sim serve --aria/--video/--control``, ``vmnav robot --video``), loopback unless a
host is given."""

from __future__ import annotations

from dataclasses import dataclass

from shared.errors import InputError

#: The host of a spec that names none: this machine only.
DEFAULT_HOST = "127.0.0.1"


@dataclass(frozen=True, slots=True)
class TcpSpec:
    """Serve on a TCP port (0: any free port)."""

    host: str
    port: int


def parse_http_spec(text: str, option: str, default_port: int) -> TcpSpec:
    """An HTTP server's address: ``http``, ``http:PORT`` or ``http:HOST:PORT``.

    Raises:
        InputError: anything else (the message names ``option`` and the value).
    """
    kind, _, rest = text.partition(":")
    if kind == "http":
        return tcp_spec(option, text, rest, default_port)
    raise InputError(option, f"{text!r} is not http:PORT or http:HOST:PORT")


def tcp_spec(option: str, text: str, rest: str, default_port: int) -> TcpSpec:
    """``[HOST:]PORT`` (``rest`` of ``text``), default host :data:`DEFAULT_HOST`.

    Raises:
        InputError: a port that is not 0-65535 (the message names ``option``).
    """
    host, _, port_text = rest.rpartition(":")
    port_text = port_text or str(default_port)
    if port_text.isdigit() and 0 <= int(port_text) <= 65535:
        return TcpSpec(host or DEFAULT_HOST, int(port_text))
    raise InputError(option, f"{text!r}: the TCP port must be 0-65535")
