"""Wire-level helpers private to ``shared.aria``: units and their SI conversion, C strings.

Wire values are integers in ARCOS units (mm, mm/s, deg, decivolts, ...); above the
codec everything is SI (m, m/s, rad, V). Decoding divides by an integer (or
converts degrees to radians), so a decoded value re-encodes to the same integer.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from shared.errors import LocalProtocolError


class WireUnit(NamedTuple):
    """A wire unit: ``si = wire / divisor`` (then degrees -> radians if ``angular``).

    Attributes:
        symbol: the wire unit, for messages (``"mm/s"``).
        divisor: wire units per SI unit, or per degree when ``angular``.
        angular: whether the SI side is in radians.
    """

    symbol: str
    divisor: float
    angular: bool = False

    def si(self, wire: int) -> float:
        """The SI value of integer ``wire``."""
        value = wire / self.divisor
        return math.radians(value) if self.angular else value

    def wire(self, name: str, si: float, lo: int, hi: int) -> int:
        """The integer wire value of ``si``, rounded; raise if outside ``lo..hi``.

        Raises:
            LocalProtocolError: ``si`` is not finite or does not fit the field ``name``.
        """
        value = self._scaled(name, si)
        if not lo <= value <= hi:
            raise LocalProtocolError(
                f"{name}: {si!r} is {value} {self.symbol} on the wire, outside {lo}..{hi}"
            )
        return value

    def clamped(self, name: str, si: float, lo: int, hi: int) -> int:
        """The integer wire value of ``si``, rounded and clamped to ``lo..hi``.

        Raises:
            LocalProtocolError: ``si`` is not finite.
        """
        return max(lo, min(hi, self._scaled(name, si)))

    def _scaled(self, name: str, si: float) -> int:
        if not math.isfinite(si):
            raise LocalProtocolError(f"{name}: must be finite, got {si!r}")
        return round((math.degrees(si) if self.angular else si) * self.divisor)


MM = WireUnit("mm", 1000)
MM_S = WireUnit("mm/s", 1000)
MM_S2 = WireUnit("mm/s²", 1000)
DEG = WireUnit("deg", 1, angular=True)
DEG_S = WireUnit("deg/s", 1, angular=True)
DEG_S2 = WireUnit("deg/s²", 1, angular=True)
DECIDEG_S = WireUnit("0.1 deg/s", 10, angular=True)
TWO_DEG = WireUnit("2 deg", 0.5, angular=True)
DECIVOLT = WireUnit("0.1 V", 10)

NS_PER_MS = 1_000_000

TEXT_ENCODING = "latin-1"
"""Byte-transparent: any received string decodes, and re-encodes to the same bytes."""


def encode_cstring(name: str, text: str) -> bytes:
    """``text`` as Latin-1 bytes plus a terminating NUL.

    Raises:
        LocalProtocolError: ``text`` holds a NUL or a character outside Latin-1.
    """
    if "\0" in text:
        raise LocalProtocolError(f"{name}: {text!r} contains a NUL, which would end the string")
    try:
        return text.encode(TEXT_ENCODING) + b"\0"
    except UnicodeEncodeError:
        raise LocalProtocolError(f"{name}: {text!r} has characters outside Latin-1") from None
