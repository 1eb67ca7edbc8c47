"""Joining a newly taught path to the visual memory.

Courbon et al. (ICARCV 2008, sec. II-A): "Two visual paths Ψp1 and Ψp2 are
connected when the terminal extremity of a visual path Ψp1 is the same key
image as the initial extremity of another visual path Ψp2." A taught path does
not start on a stored key image, so its ends are *localized* in the memory
(:mod:`robot.memory.localize`) and an end that matches a key image of another
path well enough becomes a :class:`~shared.memory.Junction` with it.

Both directions are tried, so that the order of teaching does not matter:

* the new path's first and last key images against every other path;
* every other path's first and last key images against the new path (a path
  taught earlier may end in the middle of the new one).

A key image joins a given other path at most once (counting the junctions the
memory already holds). Among conflicting candidates, a junction between two
path ends wins (the paper's end-to-start connection), then the one with more
matches: if the new path's first key image matches both the last and the last
but one key image of an older path, it joins the last.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from robot.config import FeatureConfig, LocalizeConfig, TeachConfig
from robot.memory.localize import Localizer
from shared.config import CameraMountConfig
from shared.memory import Junction, VisualMemory, VisualPath


class JunctionOutcome(enum.Enum):
    """What became of a junction attempt."""

    JOINED = "joined"  #: a junction to add
    TOO_FEW_MATCHES = "too few matches"  #: below the threshold: not the same place
    NOT_VERIFIED = "not verified"  #: refused by localization's geometric verification
    ALREADY_JOINED = "already joined to that path"  #: one of the two is linked to the other's path


@dataclass(frozen=True, slots=True)
class JunctionAttempt:
    """The localization of one path end among another set of key images.

    Attributes:
        end_id: the path end localized (first or last key image of its path).
        best_id: the key image it matched best; None if there was nothing to compare with.
        matches: the number of matches with ``best_id``.
        outcome: whether it becomes a junction, and if not, why.
    """

    end_id: int
    best_id: int | None
    matches: int
    outcome: JunctionOutcome

    @property
    def accepted(self) -> bool:
        """Whether it becomes a junction."""
        return self.outcome is JunctionOutcome.JOINED

    def junction(self) -> Junction:
        """The junction ``end_id`` -> ``best_id``.

        Raises:
            ValueError: the attempt was not accepted.
        """
        if not self.accepted or self.best_id is None:
            raise ValueError(f"the attempt from key image {self.end_id} was not accepted")
        return Junction(from_id=self.end_id, to_id=self.best_id, matches=self.matches)


def join_path(memory: VisualMemory, path: VisualPath, mount: CameraMountConfig,
              feature_config: FeatureConfig, localize_config: LocalizeConfig,
              teach_config: TeachConfig) -> list[JunctionAttempt]:
    """Localize the new path's ends in the memory (and the others' along it) and add the
    junctions found (:func:`junction_attempts` with ``teach_config.junction_min_matches``).

    Returns:
        Every attempt, the accepted ones added to ``memory``.
    """
    attempts = junction_attempts(memory, path.id, mount, feature_config, localize_config,
                                 teach_config.junction_min_matches)
    for attempt in attempts:
        if attempt.accepted:
            memory.add_junction(attempt.junction())
    return attempts


def junction_attempts(
    memory: VisualMemory,
    path_id: int,
    mount: CameraMountConfig,
    feature_config: FeatureConfig,
    localize_config: LocalizeConfig,
    min_matches: int,
) -> list[JunctionAttempt]:
    """Localize path ``path_id``'s ends among the other paths, and theirs along it.

    Args:
        memory: the memory holding the new path (and perhaps others).
        path_id: the new path.
        mount: where the camera sits on the robot (for the geometric verification).
        feature_config: corner detection, as when the memory was taught.
        localize_config: the localization parameters.
        min_matches: an end joins a key image with at least this many matches (and
            only if localization's geometric verification accepts it).

    Returns:
        One attempt per end localized: the new path's two ends (one if it has a
        single key image), then the other paths' ends; empty if the memory has no
        other path. Accepted attempts are junctions to add.

    Raises:
        KeyError: no path ``path_id``.
    """
    path = memory.paths[path_id]
    others = [i for i in sorted(memory.keyframes) if memory.keyframes[i].path_id != path_id]
    if not others:
        return []
    other_ends = [
        end
        for other in sorted(memory.paths.values(), key=lambda p: p.id)
        if other.id != path_id
        for end in _ends(other.keyframe_ids)
    ]
    found: list[tuple[int, int | None, int]] = []
    verified: list[bool] = []
    for ends, candidates in (
        (_ends(path.keyframe_ids), others),
        (other_ends, list(path.keyframe_ids)),
    ):
        localizer = Localizer.from_memory(memory, mount, feature_config, localize_config,
                                          candidates)
        for end in ends:
            result = localizer.localize(memory.keyframe(end).image)
            found.append((end, result.keyframe_id, result.matches))
            verified.append(result.ok)
    all_ends = {e for p in memory.paths.values() for e in _ends(p.keyframe_ids)}
    links = {link for j in memory.junctions for link in _links(memory, j.from_id, j.to_id)}
    outcomes = [JunctionOutcome.TOO_FEW_MATCHES] * len(found)
    for k in sorted(
        range(len(found)), key=lambda k: (found[k][1] not in all_ends, -found[k][2], k)
    ):
        end, best, matches = found[k]
        if best is None or matches < min_matches:
            continue
        if not verified[k]:
            outcomes[k] = JunctionOutcome.NOT_VERIFIED
            continue
        new_links = _links(memory, end, best)
        if links.isdisjoint(new_links):
            links |= new_links
            outcomes[k] = JunctionOutcome.JOINED
        else:
            outcomes[k] = JunctionOutcome.ALREADY_JOINED
    return [
        JunctionAttempt(end, best, matches, outcome)
        for (end, best, matches), outcome in zip(found, outcomes, strict=True)
    ]


def junction_lines(
    attempts: Sequence[JunctionAttempt], memory: VisualMemory, directory: Path
) -> list[str]:
    """The end of a teach summary: the junctions made and tried, then the memory."""
    made = [a for a in attempts if a.accepted]
    lines = [f"  junctions made: {len(made)}"]
    for a in attempts:
        lines.append(
            f"    end key image {a.end_id}: best key image {a.best_id} with {a.matches} "
            f"matches: {a.outcome.value}"
        )
    lines.append(
        f"memory {directory}: {len(memory.paths)} paths, {len(memory.keyframes)} key images, "
        f"{len(memory.junctions)} junctions"
    )
    return lines


def _links(memory: VisualMemory, a: int, b: int) -> set[tuple[int, int]]:
    """What joining key images a and b uses up: (a, b's path) and (b, a's path)."""
    return {(a, memory.keyframes[b].path_id), (b, memory.keyframes[a].path_id)}


def _ends(keyframe_ids: Iterable[int]) -> list[int]:
    """The first and last ids (one id if they are the same)."""
    ids = list(keyframe_ids)
    return sorted({ids[0], ids[-1]}, key=ids.index)
