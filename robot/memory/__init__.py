"""The robot's use of the visual memory: localization of a view among the key images."""

from __future__ import annotations

from robot.memory.localize import (
    Candidate,
    Localization,
    Localizer,
    keyframe_features,
    localize,
)

__all__ = ["Candidate", "Localization", "Localizer", "keyframe_features", "localize"]
