"""The robot's use of the visual memory: localization of a view among the key images
(:mod:`.localize`), joining a new path to the others (:mod:`.junctions`), and a path built
from a recorded teach drive (:mod:`.path_from_log`, ``vmnav memory build``)."""

from __future__ import annotations

from robot.memory.localize import (
    Candidate,
    Localization,
    Localizer,
    localize,
)

__all__ = ["Candidate", "Localization", "Localizer", "localize"]
