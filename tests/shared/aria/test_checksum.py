"""The ARIA checksum (reference §1)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shared.aria.checksum import aria_checksum
from tests.shared.aria.helpers import golden, hexbytes


def _stepwise(body: bytes) -> int:
    """Reference §1's listing: mask after every addition, fold an odd last byte."""
    total = 0
    for k in range(len(body) // 2):
        total = (total + (body[2 * k] << 8 | body[2 * k + 1])) & 0xFFFF
    if len(body) % 2:
        total ^= body[-1]
    return total


@pytest.mark.parametrize("case", golden()["checksums"], ids=lambda c: c["name"])
def test_worked_examples(case: dict) -> None:
    body = hexbytes(case["body"])
    assert aria_checksum(body) == int(case["checksum"], 16)
    assert hexbytes(case["frame"])[-2:] == int(case["checksum"], 16).to_bytes(2, "big")


@given(st.binary(max_size=300))
def test_equals_stepwise_masking(body: bytes) -> None:
    assert aria_checksum(body) == _stepwise(body)


def test_empty_body_is_zero() -> None:
    assert aria_checksum(b"") == 0
