"""The built-in worlds' routes join into one strongly connected visual memory.

Teaching a route localizes its first and last key images in the memory, and the
other paths' ends along it (``robot.memory.junctions``); an end becomes a
junction with a key image that shows the same view. A fisheye view does not
survive a 90 degree turn, so a junction needs the two routes at the same place
AND heading the same way. Teaching the lab's three routes takes about a minute,
so this checks the world data that makes the junctions possible instead:

* every route's first and last waypoints lie on another route (within
  ``_NEAR_M``) whose leg there heads the same way (within ``_SAME_HEADING_DEG``);
* each route's first and last legs are straight for ``_MIN_END_LEG_M``, so the
  driver has settled on the heading where the junction is localized;
* the directed graph of routes (each route a chain through the places where
  other routes join it, each join both ways) is strongly connected, as the
  paper requires of the memory (Courbon et al., ICARCV 2008, sec. II-A).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from sim._geometry import point_segment_distances
from sim.world import Route, load_world

_NEAR_M = 0.3
"""A route end within this distance of another route's polyline lies on it, m."""
_SAME_HEADING_DEG = 20.0
"""Headings closer than this are the same way, degrees."""
_MIN_END_LEG_M = 1.2
"""Length of straight driving before a route's last waypoint and after its first, m."""


@dataclass(frozen=True, slots=True)
class Join:
    """A route end that lies on another route, heading the same way.

    Attributes:
        route: the route whose end it is.
        at_m: where that end is along ``route``: 0 (first waypoint) or its length, m.
        other: the route it lies on.
        other_at_m: where along ``other``, m.
    """

    route: str
    at_m: float
    other: str
    other_at_m: float


def _legs(route: Route) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(starts (L, 2), ends (L, 2), headings (L,) rad, arc length at each start (L,) m)."""
    points = np.asarray(route.waypoints, dtype=float)
    a, b = points[:-1], points[1:]
    d = b - a
    lengths = np.hypot(d[:, 0], d[:, 1])
    return a, b, np.arctan2(d[:, 1], d[:, 0]), np.concatenate([[0.0], np.cumsum(lengths)[:-1]])


def _length(route: Route) -> float:
    points = np.asarray(route.waypoints, dtype=float)
    return float(np.hypot(*np.diff(points, axis=0).T).sum())


def _angle_deg(a_rad: float | np.ndarray, b_rad: float | np.ndarray) -> np.ndarray:
    """Absolute difference of two headings, wrapped to [0, 180] degrees."""
    return np.abs(np.degrees((np.asarray(a_rad) - b_rad + math.pi) % (2 * math.pi) - math.pi))


def route_ends(route: Route) -> list[tuple[float, tuple[float, float], float]]:
    """The route's first and last waypoints: (arc length m, (x, y) m, heading rad)."""
    _, _, headings, _ = _legs(route)
    return [
        (0.0, route.waypoints[0], float(headings[0])),
        (_length(route), route.waypoints[-1], float(headings[-1])),
    ]


def joins(routes: tuple[Route, ...]) -> list[Join]:
    """Every route end that lies on another route heading the same way (the nearest such leg)."""
    found = []
    for route in routes:
        for at_m, xy, heading in route_ends(route):
            point = np.asarray(xy, dtype=float)
            for other in routes:
                if other is route:
                    continue
                a, b, headings, starts = _legs(other)
                distances = point_segment_distances(point[None, :], a, b)[0]
                fits = (distances <= _NEAR_M) & (_angle_deg(headings, heading) <= _SAME_HEADING_DEG)
                if fits.any():
                    k = int(np.argmin(np.where(fits, distances, np.inf)))
                    leg = b[k] - a[k]
                    along_m = np.clip(
                        np.dot(point - a[k], leg) / np.hypot(*leg), 0.0, np.hypot(*leg)
                    )
                    found.append(Join(route.name, at_m, other.name, float(starts[k] + along_m)))
    return found


def strongly_connected(routes: tuple[Route, ...], found: list[Join]) -> bool:
    """Whether every place of the route graph reaches every other.

    The places are the routes' ends and the points where other routes join them;
    a route runs forward from place to place; a join goes both ways.
    """
    stops = {r.name: {0.0, _length(r)} for r in routes}
    for j in found:
        stops[j.other].add(j.other_at_m)
    index = {(name, s): i for i, (name, s) in enumerate((n, s) for n in stops for s in stops[n])}
    edges = [
        (index[name, s0], index[name, s1])
        for name, places in stops.items()
        for s0, s1 in zip(sorted(places), sorted(places)[1:], strict=False)
    ]
    for j in found:
        a, b = index[j.route, j.at_m], index[j.other, j.other_at_m]
        edges += [(a, b), (b, a)]
    rows, cols = np.array(edges, dtype=np.intp).reshape(-1, 2).T
    graph = sp.csr_array((np.ones(len(edges)), (rows, cols)), shape=(len(index), len(index)))
    count, _ = connected_components(graph, directed=True, connection="strong")
    return count == 1


@pytest.mark.parametrize("world_name", ["lab", "campus"])
class TestBuiltinRoutes:
    def test_every_route_end_lies_on_another_route_heading_the_same_way(
        self, world_name: str
    ) -> None:
        routes = load_world(world_name).routes
        joined = {(j.route, j.at_m) for j in joins(routes)}
        missing = [
            f"{r.name} at {xy}"
            for r in routes
            for at_m, xy, _ in route_ends(r)
            if (r.name, at_m) not in joined
        ]
        assert not missing, f"{world_name}: route ends that join no other route: {missing}"

    def test_routes_start_and_end_with_a_straight_leg(self, world_name: str) -> None:
        for route in load_world(world_name).routes:
            points = np.asarray(route.waypoints, dtype=float)
            for leg in (points[1] - points[0], points[-1] - points[-2]):
                assert np.hypot(*leg) >= _MIN_END_LEG_M, route.name

    def test_the_route_graph_is_strongly_connected(self, world_name: str) -> None:
        routes = load_world(world_name).routes
        assert strongly_connected(routes, joins(routes))


class TestTheCheck:
    """The checks above can fail: right-angle meetings and one-way joins are caught."""

    def test_a_route_leaving_another_at_a_right_angle_does_not_join(self) -> None:
        main = Route("main", ((0.0, 0.0), (10.0, 0.0)))
        branch = Route("branch", ((5.0, 0.0), (5.0, 4.0)))
        assert joins((main, branch)) == []

    def test_a_route_leaving_another_heading_the_same_way_joins_it(self) -> None:
        main = Route("main", ((0.0, 0.0), (10.0, 0.0)))
        branch = Route("branch", ((5.0, 0.1), (7.0, 0.1), (8.0, 3.0)))
        (join,) = joins((main, branch))
        assert join.route == "branch" and join.at_m == 0.0
        assert join.other == "main" and join.other_at_m == pytest.approx(5.0)

    def test_a_route_continuing_another_is_not_a_cycle(self) -> None:
        a = Route("a", ((0.0, 0.0), (5.0, 0.0)))
        b = Route("b", ((3.0, 0.0), (8.0, 0.0)))
        found = joins((a, b))
        assert {(j.route, j.at_m) for j in found} == {("a", 5.0), ("b", 0.0)}
        assert not strongly_connected((a, b), found)

    def test_a_loop_back_to_the_start_is_a_cycle(self) -> None:
        a = Route("a", ((0.0, 0.0), (10.0, 0.0)))
        b = Route("b", ((8.0, 0.0), (11.0, 0.0), (11.0, 3.0), (-1.0, 3.0), (-1.0, 0.0), (2.0, 0.0)))
        found = joins((a, b))
        assert len(found) == 4
        assert strongly_connected((a, b), found)
