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
memory already holds). Candidates are tried in priority order: a junction between
two path ends first (the paper's end-to-start connection), then the one with more
matches: if the new path's first key image matches both the last and the last
but one key image of an older path, it joins the last.

Two junctions between the same two paths must agree with the paths' odometry: the
way from one junction to the other measured along one path is the way measured
along the other (within :data:`ODOMETRY_SLACK_M`, :data:`ODOMETRY_DRIFT` of the
distance, and the yaw the verification allows between the two views). A geometric
verification cannot tell a place from another one a whole pattern period away
(carpet tiles, ceiling tiles and lamps repeat along a corridor: two places 4.8 m
apart in the lab's corridor look the same to it); two junctions that disagree by
metres can. This is the pairwise-consistency test of loop closures in SLAM
(Mangelson et al., ICRA 2018, "Pairwise consistent measurement set maximization"),
and as there, the largest set of candidates that agree with each other and with the
memory's junctions is joined; of equally large sets, the first in priority order. (The
first tried standing, whatever came after, joined the campus's south walk by a
look-alike 7.6 m away, an end with 44 matches, and refused both its true junctions,
with 74 and 146.)

Two paths may share a single junction, and then no pair can disagree; a third path
joined to both closes a triangle. Its three junctions are three places, and the
odometry of each path measures the straight distance between the two places on it:
each distance must be at most the sum of the other two (within the slack and drift
above). In the lab, with three paths taught, 2 of 6 memories held a junction between
views 3.2 m and 7.8 m apart (a corridor's look-alike; a view of the corridor the other
way), which the pairwise test passed (one was alone between its two paths, the other
within the drift allowed over a 27 m loop) and the triangles refuse; every true junction
of the six memories closes its triangles.
"""

from __future__ import annotations

import enum
import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from robot.config import FeatureConfig, LocalizeConfig, TeachConfig
from robot.memory.localize import Candidate, Localizer
from shared.config import CameraMountConfig
from shared.memory import Junction, VisualMemory, VisualPath
from shared.pose import Pose2

ODOMETRY_SLACK_M = 0.5
"""Two junctions between the same paths may disagree with the odometry by this much, m,
plus :data:`ODOMETRY_DRIFT` of the distance driven between them (a junction joins two
views taken up to a few decimetres apart)."""
ODOMETRY_DRIFT = 0.1
"""Odometry's drift allowed between two junctions, a fraction of the distance driven from
one to the other along the longer of the two paths (a loop drifts over its whole length)."""


class JunctionOutcome(enum.Enum):
    """What became of a junction attempt."""

    JOINED = "joined"  #: a junction to add
    TOO_FEW_MATCHES = "too few matches"  #: below the threshold: not the same place
    NOT_VERIFIED = "not verified"  #: refused by localization's geometric verification
    ALREADY_JOINED = "already joined to that path"  #: one of the two is linked to the other's path
    INCONSISTENT = "disagrees with the odometry of another junction"  #: see the module docstring


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
    yaws: list[float] = []
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
            yaws.append(_verified_yaw_rad(result.candidates, result.keyframe_id,
                                          localize_config.max_yaw_deg))
    all_ends = {e for p in memory.paths.values() for e in _ends(p.keyframe_ids)}
    links = {link for j in memory.junctions for link in _links(memory, j.from_id, j.to_id)}
    max_yaw = math.radians(localize_config.max_yaw_deg)
    joined = [(j.from_id, j.to_id, max_yaw) for j in memory.junctions]
    outcomes = [JunctionOutcome.TOO_FEW_MATCHES] * len(found)
    eligible: list[int] = []  # in priority order
    for k in sorted(
        range(len(found)), key=lambda k: (found[k][1] not in all_ends, -found[k][2], k)
    ):
        _, best, matches = found[k]
        if best is None or matches < min_matches:
            continue
        if verified[k]:
            eligible.append(k)
        else:
            outcomes[k] = JunctionOutcome.NOT_VERIFIED
    tried = [(found[k][0], found[k][1], yaws[k]) for k in eligible]
    chosen = _largest_consistent(memory, tried, joined, links)
    taken = links.union(*(_links(memory, a, b) for a, b, _ in (tried[i] for i in chosen)))
    for i, k in enumerate(eligible):
        if i in chosen:
            outcomes[k] = JunctionOutcome.JOINED
        elif not taken.isdisjoint(_links(memory, tried[i][0], tried[i][1])):
            outcomes[k] = JunctionOutcome.ALREADY_JOINED
        else:
            outcomes[k] = JunctionOutcome.INCONSISTENT
    return [
        JunctionAttempt(end, best, matches, outcome)
        for (end, best, matches), outcome in zip(found, outcomes, strict=True)
    ]


def same_place(memory: VisualMemory, a: int, b: int, max_yaw_deg: float) -> bool:
    """Whether key images ``a`` and ``b`` of two paths show one place, by the paths' junctions.

    A view localized on both is no proof: a geometric verification cannot tell a place
    from its look-alike a pattern period away. The pair is taken as the teach would take
    a new junction between the two paths: it must agree with every junction already
    between them and with the paths' odometry (the pairwise consistency of the module
    docstring, each junction's views allowed ``max_yaw_deg`` apart), and stand as far
    from each junction along one path as along the other (a test the turn allowed
    between the junction's views does not loosen). Paths no junction joins cannot be
    compared: never the same place.

    Raises:
        KeyError: an id is not in the memory.
    """
    keys = memory.keyframes
    paths = {keys[a].path_id, keys[b].path_id}
    between = [j for j in memory.junctions
               if {keys[j.from_id].path_id, keys[j.to_id].path_id} == paths]
    yaw = math.radians(max_yaw_deg)
    return (len(paths) == 2 and bool(between)
            and all(_consistent(memory, (j.from_id, j.to_id, yaw), (a, b))
                    and _equally_far(memory, (j.from_id, j.to_id), (a, b)) for j in between))


def _equally_far(memory: VisualMemory, first: tuple[int, int], second: tuple[int, int]) -> bool:
    """Whether pair ``second`` stands as far from pair ``first`` along one path as along the
    other (within the odometry's slack and drift): a test no turn between the paths'
    odometry frames loosens, unlike :func:`_consistent`'s."""
    offsets = _offsets(memory, first, second)
    if offsets is None:
        return True
    along_one, along_other, driven = offsets
    return (abs(math.hypot(*along_one) - math.hypot(*along_other))
            <= ODOMETRY_SLACK_M + ODOMETRY_DRIFT * driven)


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


def _largest_consistent(memory: VisualMemory, tried: Sequence[tuple[int, int, float]],
                        joined: Sequence[tuple[int, int, float]],
                        links: set[tuple[int, int]]) -> list[int]:
    """The largest set of the junctions ``tried`` (from, to, |yaw| between the views, rad;
    in priority order) that agree with each other and with those ``joined``, whose
    ``links`` they must not reuse; of equally large sets, the first in priority order
    (module docstring). Indices into ``tried``, ascending.

    A depth-first search, each junction taken before it is left out, cut where what is
    left cannot make a larger set: a handful of candidates per path.
    """
    largest: list[int] = []

    def grow(i: int, chosen: list[int], joined: list[tuple[int, int, float]],
             links: set[tuple[int, int]]) -> None:
        nonlocal largest
        if len(chosen) + len(tried) - i <= len(largest):
            return
        if i == len(tried):
            largest = chosen
            return
        a, b, _ = tried[i]
        new = _links(memory, a, b)
        if (links.isdisjoint(new) and all(_consistent(memory, j, (a, b)) for j in joined)
                and _closes_triangles(memory, [(x, y) for x, y, _ in joined], (a, b))):
            grow(i + 1, [*chosen, i], [*joined, tried[i]], links | new)
        grow(i + 1, chosen, joined, links)

    grow(0, [], list(joined), set(links))
    return largest


def _verified_yaw_rad(candidates: Sequence[Candidate], keyframe_id: int | None,
                      unknown_deg: float) -> float:
    """|yaw| between the query and key image ``keyframe_id`` as verified, rad
    (``unknown_deg`` when it was not fitted)."""
    for c in candidates:
        if c.keyframe_id == keyframe_id and c.verification is not None:
            yaw = abs(c.verification.yaw_deg)
            return math.radians(yaw if math.isfinite(yaw) else unknown_deg)
    return math.radians(unknown_deg)


def _consistent(memory: VisualMemory, first: tuple[int, int, float],
                second: tuple[int, int]) -> bool:
    """Whether junction ``second`` (from, to) agrees with junction ``first`` (from, to,
    |yaw| between its two views, rad) and the odometry of their paths (module docstring).

    Junctions that do not join the same two paths always agree.
    """
    a, b, yaw = first
    offsets = _offsets(memory, (a, b), second)
    if offsets is None:
        return True
    along_one, along_other, driven = offsets
    allowed = (ODOMETRY_SLACK_M + ODOMETRY_DRIFT * driven
               + 2.0 * math.sin(yaw / 2.0) * math.hypot(*along_one))
    return math.dist(along_one, along_other) <= allowed


def _closes_triangles(memory: VisualMemory, junctions: Sequence[tuple[int, int]],
                      new: tuple[int, int]) -> bool:
    """Whether junction ``new`` (from, to), between paths P and Q, closes every triangle it
    makes with two of ``junctions`` that join P and Q to a third path R (module docstring).

    The three junctions are three places; the odometry of each path measures the straight
    distance between the two on it. Each distance must be at most the sum of the other two,
    within :data:`ODOMETRY_SLACK_M` and :data:`ODOMETRY_DRIFT` of the three drives: a test
    no turn between the paths' odometry frames loosens.
    """
    keys = memory.keyframes
    x, y = new
    p, q = keys[x].path_id, keys[y].path_id
    on = [{keys[a].path_id: a, keys[b].path_id: b} for a, b in junctions]
    for first, second in itertools.permutations(on, 2):
        third = set(first) - {p}
        if p not in first or q not in second or len(third) != 1 or third != set(second) - {q}:
            continue
        r = third.pop()
        if r in (p, q):
            continue
        sides = [_straight(memory, first[p], x), _straight(memory, y, second[q]),
                 _straight(memory, first[r], second[r])]
        lengths = [length for length, _ in sides]
        allowed = ODOMETRY_SLACK_M + ODOMETRY_DRIFT * sum(driven for _, driven in sides)
        if 2.0 * max(lengths) - sum(lengths) > allowed:
            return False
    return True


def _straight(memory: VisualMemory, a: int, b: int) -> tuple[float, float]:
    """The straight distance between two key images of one path by its odometry, and the
    distance driven from one to the other, m."""
    ka, kb = memory.keyframes[a], memory.keyframes[b]
    return math.dist(ka.odom_pose[:2], kb.odom_pose[:2]), abs(kb.distance_m - ka.distance_m)


def _offsets(memory: VisualMemory, first: tuple[int, int], second: tuple[int, int]
             ) -> tuple[tuple[float, float], tuple[float, float], float] | None:
    """Where pair ``second``'s key images stand from pair ``first``'s, along each of the two
    paths they join (first's from-path first; x ahead, y to the left, m), and the longer
    of the two drives between them, m; None if the pairs do not join the same two paths."""
    a, b = first
    c, d = second
    path = {k: memory.keyframes[k].path_id for k in (a, b, c, d)}
    if {path[a], path[b]} != {path[c], path[d]}:
        return None
    if path[a] != path[c]:
        c, d = d, c
    keys = memory.keyframes
    driven = max(abs(keys[c].distance_m - keys[a].distance_m),
                 abs(keys[d].distance_m - keys[b].distance_m))
    return (_offset(keys[a].odom_pose, keys[c].odom_pose),
            _offset(keys[b].odom_pose, keys[d].odom_pose), driven)


def _offset(origin: Pose2, pose: Pose2) -> tuple[float, float]:
    """Where ``pose`` stands in ``origin``'s frame (x ahead, y to the left), m."""
    x0, y0, yaw0 = origin
    x, y, _ = pose
    dx, dy = x - x0, y - y0
    cos, sin = math.cos(yaw0), math.sin(yaw0)
    return cos * dx + sin * dy, -sin * dx + cos * dy


def _links(memory: VisualMemory, a: int, b: int) -> set[tuple[int, int]]:
    """What joining key images a and b uses up: (a, b's path) and (b, a's path)."""
    return {(a, memory.keyframes[b].path_id), (b, memory.keyframes[a].path_id)}


def _ends(keyframe_ids: Iterable[int]) -> list[int]:
    """The first and last ids (one id if they are the same)."""
    ids = list(keyframe_ids)
    return sorted({ids[0], ids[-1]}, key=ids.index)
