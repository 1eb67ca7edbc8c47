"""The visual memory: a multigraph of key images, visual paths and junctions.

Courbon et al. (ICARCV 2008, sec. II-A): "The visual memory structure is thus
defined as a multigraph which vertices are key images linked by edges which are
the visual paths (directed graphs) [...] It is yet necessary that this multigraph
is strongly connected", and a visual route is a path of the memory connecting the
localized key image to the goal key image (sec. II-B).

Here the vertices are key images; each visual path contributes a directed edge
between consecutive key images, weighted by the teach odometric distance between
them; each junction contributes two zero-length edges (the two key images are
the same place, so it is traversable both ways). Routes are shortest paths by
odometric distance (Dijkstra, ``scipy.sparse.csgraph``), planned by
:class:`RouteGraph`, which needs only the structure (ids, paths, distances,
junctions): the ground station plans on the memory's manifest with it.

Rules kept by :class:`VisualMemory` (it only ever grows):

1. Ids are never reused: a new path's key images get ids above every id so far.
2. Every key image lies on exactly one path, at position ``index``; within a path
   ``t_ns`` strictly increases and ``distance_m`` starts at 0 and never decreases;
   a key image's ``tracked_from_previous`` refers to corners of the previous key
   image of its path (the first has none).
3. All key images have the camera's image size and the same descriptor length.
4. A junction joins two distinct key images of the memory; at most one junction
   per unordered pair.
"""

from __future__ import annotations

import enum
import itertools
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import numpy.typing as npt
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components, dijkstra

from shared.camera_model import CameraModel
from shared.errors import MemoryFormatError, UnknownKeyframeError
from shared.memory.keyframe import (
    Junction,
    Keyframe,
    KeyframeRecord,
    VisualPath,
    thumbnail_from_image,
)


class EdgeKind(enum.Enum):
    """What an edge of the multigraph comes from."""

    PATH = "path"  #: consecutive key images of a visual path, in teach direction
    JUNCTION = "junction"  #: the two key images of a junction (either direction)


@dataclass(frozen=True, slots=True)
class Edge:
    """A directed edge of the multigraph.

    Attributes:
        from_id: key image left.
        to_id: key image reached.
        length_m: teach odometric distance between them, m (0 for a junction).
        kind: a path step or a junction crossing.
    """

    from_id: int
    to_id: int
    length_m: float
    kind: EdgeKind


@dataclass(frozen=True, slots=True)
class ConnectivityReport:
    """Whether every key image can be reached from every other (paper sec. II-A).

    The *main component* is the largest strongly connected component (ties: the
    one holding the smallest id); a memory is strongly connected when it is the
    only one.

    Attributes:
        strongly_connected: True if every key image reaches every other (and for
            an empty memory).
        components: the strongly connected components, ids sorted, largest first.
        not_reachable_from_main: key images no route from the main component reaches.
        cannot_reach_main: key images with no route to the main component.
    """

    strongly_connected: bool
    components: tuple[tuple[int, ...], ...]
    not_reachable_from_main: tuple[int, ...]
    cannot_reach_main: tuple[int, ...]

    @property
    def unreachable(self) -> tuple[int, ...]:
        """Key images not mutually reachable with the main component, sorted."""
        return tuple(sorted(set(self.not_reachable_from_main) | set(self.cannot_reach_main)))


def route_edges(paths: Iterable[Sequence[int]], distance_m: Mapping[int, float],
                junctions: Iterable[tuple[int, int]]) -> tuple[Edge, ...]:
    """The multigraph's directed edges (module docstring) from its bare structure.

    Args:
        paths: each path's key image ids in teach order.
        distance_m: key image id -> teach odometric distance from its path's start, m.
        junctions: (from_id, to_id) of each junction.

    Returns:
        The path steps in the order given, then both directions of each junction.
    """
    steps = [
        Edge(a, b, distance_m[b] - distance_m[a], EdgeKind.PATH)
        for ids in paths
        for a, b in itertools.pairwise(ids)
    ]
    crossings = [
        Edge(a, b, 0.0, EdgeKind.JUNCTION)
        for from_id, to_id in junctions
        for a, b in ((from_id, to_id), (to_id, from_id))
    ]
    return tuple(steps + crossings)


class RouteGraph:
    """The multigraph as a sparse matrix over vertex indices 0..n-1, for route planning.

    The one home of planning: the robot's :class:`VisualMemory` builds it from its
    records, the ground station from the memory's manifest alone
    (``ground.memory_index``), so both plan the same routes.

    Args:
        ids: every key image id (the vertices).
        edges: the directed edges (:func:`route_edges`); both ends in ``ids``.
    """

    def __init__(self, ids: Iterable[int], edges: Iterable[Edge]) -> None:
        self.ids: npt.NDArray[np.int64] = np.array(sorted(set(ids)), dtype=np.int64)
        """(n,) key image id of each vertex index."""
        self.index: Mapping[int, int] = MappingProxyType(
            {int(i): n for n, i in enumerate(self.ids)})
        """Key image id -> vertex index."""
        # A dict keeps the shortest of parallel edges (a junction between two
        # consecutive key images of one path); a sparse matrix would sum them.
        lengths: dict[tuple[int, int], float] = {}
        for e in edges:
            key = (self.index[e.from_id], self.index[e.to_id])
            lengths[key] = min(e.length_m, lengths.get(key, e.length_m))
        rows = np.array([k[0] for k in lengths], dtype=np.int64)
        cols = np.array([k[1] for k in lengths], dtype=np.int64)
        data = np.array(list(lengths.values()), dtype=np.float64)
        n = len(self.ids)
        self.lengths_m: sp.csr_array = sp.csr_array((data, (rows, cols)), shape=(n, n))
        """(n, n) edge lengths, m; explicit zeros are edges."""

    def vertex(self, keyframe_id: int) -> int:
        """The vertex index of ``keyframe_id``.

        Raises:
            UnknownKeyframeError: not a vertex.
        """
        try:
            return self.index[keyframe_id]
        except KeyError:
            raise UnknownKeyframeError(keyframe_id, len(self.ids)) from None

    def plan_route(self, start_id: int, goal_id: int) -> list[int]:
        """The visual route: the shortest walk by teach odometric distance.

        Args:
            start_id: the key image the robot is localized at.
            goal_id: the goal key image.

        Returns:
            Key image ids from ``start_id`` to ``goal_id`` inclusive, each step an
            edge (a path step or a junction crossing, the latter zero-length);
            ``[start_id]`` if they are equal; ``[]`` if the goal is unreachable.

        Raises:
            UnknownKeyframeError: either id is not a vertex.
        """
        start, goal = self.vertex(start_id), self.vertex(goal_id)
        if start_id == goal_id:
            return [start_id]
        distances_m, predecessors = dijkstra(
            self.lengths_m, directed=True, indices=start, return_predecessors=True
        )
        if not np.isfinite(distances_m[goal]):
            return []
        walk = [goal]
        while walk[-1] != start:
            walk.append(int(predecessors[walk[-1]]))
        return [int(self.ids[i]) for i in reversed(walk)]

    def plan_route_from(self, start_ids: Sequence[int], goal_id: int) -> list[int]:
        """The shortest of the visual routes from any of several key images of one place.

        Where visual paths run together, the robot is at a key image of each (relocalized
        on one path, a co-located key image of another may lead to the goal far sooner).

        Args:
            start_ids: key images the robot is localized at, the preferred one first.
            goal_id: the goal key image.

        Returns:
            :meth:`plan_route` from the start with the shortest route (the first of
            equals); ``[]`` if none reaches the goal or there is no start.

        Raises:
            UnknownKeyframeError: an id is not a vertex.
        """
        starts = [self.vertex(i) for i in start_ids]
        to_goal_m = dijkstra(self.lengths_m.T, directed=True, indices=self.vertex(goal_id))
        lengths_m = [float(to_goal_m[v]) for v in starts]
        if not starts or not np.isfinite(min(lengths_m)):
            return []
        return self.plan_route(start_ids[lengths_m.index(min(lengths_m))], goal_id)

    def within(self, keyframe_id: int, radius_m: float) -> frozenset[int]:
        """Key images at most ``radius_m`` from ``keyframe_id`` along paths and junctions,
        either way (teach odometric distance; itself included).

        Raises:
            UnknownKeyframeError: not a vertex.
        """
        distances_m = dijkstra(self.lengths_m, directed=False, indices=self.vertex(keyframe_id),
                               limit=radius_m)
        return frozenset(int(self.ids[i]) for i in np.flatnonzero(np.isfinite(distances_m)))

    def unreached(self, matrix: sp.csr_array, source: int) -> tuple[int, ...]:
        """Key image ids that no walk over ``matrix`` (``lengths_m`` or its transpose)
        from vertex index ``source`` reaches, sorted."""
        reached = breadth_first_order(matrix, source, directed=True, return_predecessors=False)
        mask = np.ones(len(self.ids), dtype=bool)
        mask[reached] = False
        return tuple(int(i) for i in self.ids[mask])


class VisualMemory:
    """Key images as vertices, visual paths as directed edges, junctions both ways.

    Pure and in memory; :mod:`shared.memory.store` reads and writes it. See the
    module docstring for the rules it keeps.

    Args:
        camera: the calibration of the camera that took every key image.
        front_end: what described every key image's points, as the robot's front end names
            itself (``robot.vision.front_end.front_end_label``: its method and descriptor
            window); None when unknown (a memory written before it was recorded). Set by
            the first path added with one when the memory has none.
    """

    def __init__(self, camera: CameraModel, front_end: str | None = None) -> None:
        self._camera = camera
        self._front_end = front_end
        self._keyframes: dict[int, Keyframe] = {}
        self._paths: dict[int, VisualPath] = {}
        self._junctions: list[Junction] = []
        self._descriptor_length: int | None = None
        self._graph_cache: RouteGraph | None = None

    @classmethod
    def from_parts(
        cls,
        camera: CameraModel,
        keyframes: Iterable[Keyframe],
        paths: Iterable[VisualPath],
        junctions: Iterable[Junction],
        front_end: str | None = None,
    ) -> VisualMemory:
        """Assemble a memory from stored records, checking every rule.

        Raises:
            MemoryFormatError: a duplicate or dangling id, a key image on no path
                or on a path that does not list it at its index, or any rule of the
                module docstring broken; names the record.
        """
        memory = cls(camera, front_end)
        by_id: dict[int, Keyframe] = {}
        for keyframe in keyframes:
            if keyframe.id in by_id:
                raise MemoryFormatError(f"key image {keyframe.id}", "duplicate key image id")
            by_id[keyframe.id] = keyframe
        for path in sorted(paths, key=lambda p: p.id):
            missing = [i for i in path.keyframe_ids if i not in by_id]
            if missing:
                raise MemoryFormatError(
                    _path_where(path), f"lists key image {missing[0]}, which does not exist"
                )
            memory._insert_path(path, [by_id[i] for i in path.keyframe_ids])
        orphans = sorted(set(by_id) - set(memory._keyframes))
        if orphans:
            orphan = by_id[orphans[0]]
            raise MemoryFormatError(
                f"key image {orphan.id}",
                f"says it is on path {orphan.path_id}, which does not list it",
            )
        for junction in junctions:
            dangling = [i for i in (junction.from_id, junction.to_id) if i not in by_id]
            if dangling:
                raise MemoryFormatError(
                    f"junction {junction.from_id} -> {junction.to_id}",
                    f"key image {dangling[0]} does not exist",
                )
            memory.add_junction(junction)
        return memory

    @property
    def camera(self) -> CameraModel:
        """The camera of every key image."""
        return self._camera

    @property
    def front_end(self) -> str | None:
        """What described the key images' points (class docstring), or None: unknown."""
        return self._front_end

    @property
    def keyframes(self) -> Mapping[int, Keyframe]:
        """Key images by id (read-only view)."""
        return MappingProxyType(self._keyframes)

    @property
    def paths(self) -> Mapping[int, VisualPath]:
        """Visual paths by id (read-only view)."""
        return MappingProxyType(self._paths)

    @property
    def junctions(self) -> tuple[Junction, ...]:
        """Junctions in the order they were added."""
        return tuple(self._junctions)

    def keyframe(self, keyframe_id: int) -> Keyframe:
        """The key image ``keyframe_id``.

        Raises:
            UnknownKeyframeError: the memory has no such key image.
        """
        try:
            return self._keyframes[keyframe_id]
        except KeyError:
            raise UnknownKeyframeError(keyframe_id, len(self._keyframes)) from None

    def add_path(self, name: str, records: Sequence[KeyframeRecord],
                 front_end: str | None = None) -> VisualPath:
        """Add a taught visual path; its key images get fresh ids in driving order.

        Thumbnails are made here (:func:`~shared.memory.keyframe.thumbnail_from_image`)
        and distances are made relative to the first record.

        Args:
            name: what was taught, e.g. the route's name.
            records: the key images in driving order, at least one.
            front_end: what described the records' points (class docstring); a memory
                without paths takes it, a memory with another refuses the path.

        Returns:
            The new path (its id and its key image ids).

        Raises:
            MemoryFormatError: a record is invalid or breaks a rule (wrong image
                size, time going backwards, ...), or the path was described by another
                front end than the memory's key images; the memory is left unchanged.
        """
        path_id = max(self._paths, default=-1) + 1
        first_id = max(self._keyframes, default=-1) + 1
        if not records:
            raise MemoryFormatError(f"path {path_id} {name!r}", "has no key images")
        if front_end is not None and self._front_end not in (None, front_end):
            raise MemoryFormatError(
                f"path {path_id} {name!r}",
                f"taught with front end {front_end!r}, but the memory's key images were "
                f"described by {self._front_end!r}: teach with the memory's [features] or "
                f"into a new memory")
        origin_m = records[0].distance_m
        keyframes = [
            Keyframe(
                id=first_id + index,
                path_id=path_id,
                index=index,
                t_ns=record.t_ns,
                odom_pose=record.odom_pose,
                distance_m=record.distance_m - origin_m,
                image=record.image,
                pixels_xy=record.pixels_xy,
                patches=record.patches,
                thumbnail=thumbnail_from_image(record.image),
                tracked_from_previous=record.tracked_from_previous,
            )
            for index, record in enumerate(records)
        ]
        path = VisualPath(id=path_id, name=name, keyframe_ids=tuple(k.id for k in keyframes))
        self._insert_path(path, keyframes)
        if front_end is not None and not self._keyframes.keys() - set(path.keyframe_ids):
            self._front_end = front_end
        return path

    def add_junction(self, junction: Junction) -> None:
        """Join two key images that are the same place.

        Raises:
            UnknownKeyframeError: either id is not in the memory.
            MemoryFormatError: the two key images are already joined.
        """
        self.keyframe(junction.from_id)
        self.keyframe(junction.to_id)
        if any(j.pair == junction.pair for j in self._junctions):
            raise MemoryFormatError(
                f"junction {junction.from_id} -> {junction.to_id}",
                "these two key images are already joined",
            )
        self._junctions.append(junction)
        self._graph_cache = None

    def edges(self) -> tuple[Edge, ...]:
        """Every directed edge: path steps by path id, then both directions of each junction."""
        return route_edges(
            (p.keyframe_ids for p in sorted(self._paths.values(), key=lambda p: p.id)),
            {i: k.distance_m for i, k in self._keyframes.items()},
            ((j.from_id, j.to_id) for j in self._junctions),
        )

    def plan_route(self, start_id: int, goal_id: int) -> list[int]:
        """The visual route (:meth:`RouteGraph.plan_route`).

        Raises:
            UnknownKeyframeError: either id is not in the memory.
        """
        return self._graph().plan_route(start_id, goal_id)

    def plan_route_from(self, start_ids: Sequence[int], goal_id: int) -> list[int]:
        """The shortest visual route from any of ``start_ids`` (:meth:`RouteGraph.plan_route_from`).

        Raises:
            UnknownKeyframeError: an id is not in the memory.
        """
        return self._graph().plan_route_from(start_ids, goal_id)

    def within(self, keyframe_id: int, radius_m: float) -> frozenset[int]:
        """Key images near ``keyframe_id`` (:meth:`RouteGraph.within`).

        Raises:
            UnknownKeyframeError: not in the memory.
        """
        return self._graph().within(keyframe_id, radius_m)

    def unreachable_from(self, keyframe_id: int) -> tuple[int, ...]:
        """Key images that no route from ``keyframe_id`` reaches, sorted.

        Raises:
            UnknownKeyframeError: the id is not in the memory.
        """
        self.keyframe(keyframe_id)
        graph = self._graph()
        return graph.unreached(graph.lengths_m, graph.index[keyframe_id])

    def connectivity(self) -> ConnectivityReport:
        """Check the paper's requirement that the memory is strongly connected."""
        graph = self._graph()
        if len(graph.ids) == 0:
            return ConnectivityReport(True, (), (), ())
        n_components, labels = connected_components(
            graph.lengths_m, directed=True, connection="strong"
        )
        components = sorted(
            (tuple(sorted(int(i) for i in graph.ids[labels == c])) for c in range(n_components)),
            key=lambda ids: (-len(ids), ids[0]),
        )
        root = graph.index[components[0][0]]
        return ConnectivityReport(
            strongly_connected=n_components == 1,
            components=tuple(components),
            not_reachable_from_main=graph.unreached(graph.lengths_m, root),
            cannot_reach_main=graph.unreached(graph.lengths_m.T.tocsr(), root),
        )

    def _insert_path(self, path: VisualPath, keyframes: Sequence[Keyframe]) -> None:
        """Check ``path`` with its key images in order against the rules, then add them."""
        where = _path_where(path)
        if path.id in self._paths:
            raise MemoryFormatError(where, "duplicate path id")
        size = (self._camera.height, self._camera.width)
        descriptor_length = self._descriptor_length
        for index, keyframe in enumerate(keyframes):
            kf = f"key image {keyframe.id}"
            if keyframe.id in self._keyframes:
                on = self._keyframes[keyframe.id].path_id
                raise MemoryFormatError(kf, f"is already on path {on}")
            if (keyframe.path_id, keyframe.index) != (path.id, index):
                raise MemoryFormatError(
                    kf,
                    f"says it is key image {keyframe.index} of path {keyframe.path_id}, "
                    f"but {where} lists it as key image {index}",
                )
            if keyframe.image.shape != size:
                raise MemoryFormatError(
                    kf,
                    f"image is {keyframe.image.shape[1]}x{keyframe.image.shape[0]} px but the "
                    f"camera is {size[1]}x{size[0]} px",
                )
            if descriptor_length is None:
                descriptor_length = keyframe.descriptor_length
            elif keyframe.descriptor_length != descriptor_length:
                raise MemoryFormatError(
                    kf,
                    f"descriptors have {keyframe.descriptor_length} values, the memory's have "
                    f"{descriptor_length}",
                )
            _check_step(keyframes[index - 1] if index else None, keyframe)
        self._paths[path.id] = path
        self._keyframes.update((k.id, k) for k in keyframes)
        self._descriptor_length = descriptor_length
        self._graph_cache = None

    def _graph(self) -> RouteGraph:
        if self._graph_cache is None:
            self._graph_cache = RouteGraph(self._keyframes, self.edges())
        return self._graph_cache


def _check_step(previous: Keyframe | None, keyframe: Keyframe) -> None:
    """Time, distance and tracks along a path: distances start at 0 and never decrease."""
    where = f"key image {keyframe.id}"
    tracks = keyframe.tracked_from_previous
    if previous is None:
        if keyframe.distance_m != 0.0:
            raise MemoryFormatError(
                where, f"first of its path, must be at distance_m 0, got {keyframe.distance_m}"
            )
        if len(tracks):
            raise MemoryFormatError(
                where, "first of its path, must have no tracked_from_previous"
            )
        return
    if len(tracks) and tracks[:, 0].max() >= previous.n_features:
        raise MemoryFormatError(
            where,
            f"tracked_from_previous: corner {int(tracks[:, 0].max())} of the previous key "
            f"image, which has {previous.n_features}",
        )
    if keyframe.t_ns <= previous.t_ns:
        raise MemoryFormatError(
            where, f"t_ns {keyframe.t_ns} is not after the previous key image's {previous.t_ns}"
        )
    if keyframe.distance_m < previous.distance_m:
        raise MemoryFormatError(
            where,
            f"distance_m {keyframe.distance_m} m is less than the previous key image's "
            f"{previous.distance_m} m",
        )


def _path_where(path: VisualPath) -> str:
    return f"path {path.id} {path.name!r}"
