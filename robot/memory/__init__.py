"""The robot's use of the visual memory: localization of a view among the key images
(:mod:`.localize`), accepted on geometric verification (:mod:`.verification`), joining a
new path to the others (:mod:`.junctions`), and a path built from a recorded teach drive
(:mod:`.path_from_log`, ``vmnav memory build``)."""

from __future__ import annotations

from robot.memory.localize import (
    Candidate,
    Localization,
    Localizer,
    localize,
    verify_matches,
)
from robot.memory.verification import Verification

__all__ = [
    "Candidate",
    "Localization",
    "Localizer",
    "Verification",
    "localize",
    "verify_matches",
]
