"""Collision categories of the simulation's pymunk shapes, and the height each shape stands for.

pymunk is 2D: a shape is a footprint on the floor plan. What it is (wall,
furniture, person, robot) lives in its filter category and collision type; how
tall it is lives on the shape itself, so a ray query's hit tells the renderer at
once whether a line of sight passes over it.
"""

from __future__ import annotations

import enum

import pymunk

_HEIGHT_ATTR = "vmnav_height_m"


class Category(enum.IntFlag):
    """Filter category bits, also used as collision types."""

    WALL = 1
    FURNITURE = 2
    PERSON = 4
    ROBOT = 8


def tag(shape: pymunk.Shape, category: Category, height_m: float) -> None:
    """Mark ``shape`` as one of ``category``, standing ``height_m`` tall."""
    shape.filter = pymunk.ShapeFilter(categories=int(category))
    shape.collision_type = int(category)
    setattr(shape, _HEIGHT_ATTR, float(height_m))


def height_of(shape: pymunk.Shape) -> float:
    """The height given to ``shape`` by :func:`tag`, m.

    Raises:
        ValueError: the shape was not made by the simulation.
    """
    height = getattr(shape, _HEIGHT_ATTR, None)
    if height is None:
        raise ValueError(f"{shape!r} is not a simulation shape (no height)")
    return float(height)


def category_of(shape: pymunk.Shape) -> int:
    """The category bits of ``shape``."""
    return int(shape.filter.categories)
