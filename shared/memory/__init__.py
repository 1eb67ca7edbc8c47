"""The visual memory: key images, visual paths and junctions, the multigraph, and its files.

Courbon et al. (ICARCV 2008, sec. II): :mod:`.keyframe` holds the records,
:mod:`.graph` the multigraph with route planning and the connectivity check,
:mod:`.store` the directory format, :mod:`.folder` opening or creating a memory to add
paths to (:func:`open_or_create`, for every command that writes one),
:mod:`.summary` what ``vmnav memory info`` shows.
"""

from __future__ import annotations

from shared.memory.folder import open_or_create
from shared.memory.graph import (
    ConnectivityReport,
    Edge,
    EdgeKind,
    RouteGraph,
    VisualMemory,
    route_edges,
)
from shared.memory.keyframe import (
    THUMBNAIL_HEIGHT_PX,
    THUMBNAIL_WIDTH_PX,
    Junction,
    Keyframe,
    KeyframeRecord,
    VisualPath,
    thumbnail_from_image,
)
from shared.memory.store import add_path_to_disk, read_memory, write_memory
from shared.memory.summary import memory_summary, summary_text

__all__ = [
    "THUMBNAIL_HEIGHT_PX",
    "THUMBNAIL_WIDTH_PX",
    "ConnectivityReport",
    "Edge",
    "EdgeKind",
    "Junction",
    "Keyframe",
    "KeyframeRecord",
    "RouteGraph",
    "VisualMemory",
    "VisualPath",
    "add_path_to_disk",
    "memory_summary",
    "open_or_create",
    "read_memory",
    "route_edges",
    "summary_text",
    "thumbnail_from_image",
    "write_memory",
]
