"""Fuzzing the vehicle endpoint's handlers (issue 15): messages of every id the vehicle
handles, with any field values (NaN, infinities, boundaries), mission uploads and FTP
requests among them, unsigned and validly signed, never make it raise.

The harness is ``vmnav bench fuzz``'s ``mavlink_unsigned`` / ``mavlink_signed`` target (a
fresh endpoint with the link load generator's application: receive, poll, 2 s later poll);
hypothesis picks the seed of the input's generator.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tools.bench.fuzz_targets import VehicleTarget


@pytest.mark.parametrize("signed", [False, True], ids=["unsigned", "signed"])
def test_no_message_makes_the_endpoint_raise(tmp_path: Path, signed: bool) -> None:
    target = VehicleTarget(tmp_path, signed=signed)

    @settings(derandomize=True, max_examples=300, deadline=None)
    @given(st.integers(0, 2**32 - 1))
    def fuzz(seed: int) -> None:
        target.run(target.generate(np.random.default_rng(seed)))

    fuzz()
