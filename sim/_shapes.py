"""Collision categories of the simulation's pymunk shapes, and the height each shape stands for.

pymunk is 2D: a shape is a footprint on the floor plan. What it is (wall,
furniture, person, robot) lives in its filter category and collision type; how
tall it is lives on the shape itself, so a ray query's hit tells the renderer at
once whether a line of sight passes over it. Whether the sonar hears it lives in its
filter mask: the sonar's ray queries are of category :attr:`Category.SONAR`, which an
acoustically silent shape leaves out of its mask (pymunk's filter test is two-sided),
so its pings pass through what the robot still bumps into and the camera still sees.
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
    SONAR = 16
    """No shape's category: the sonar's ray queries (see the module docstring)."""


def tag(shape: pymunk.Shape, category: Category, height_m: float, *,
        sonar_echo: bool = True) -> None:
    """Mark ``shape`` as one of ``category``, standing ``height_m`` tall, echoing the
    sonar's pings or not (``sonar_echo`` False: acoustically silent, still solid)."""
    mask = pymunk.ShapeFilter.ALL_MASKS()
    if not sonar_echo:
        mask &= ~int(Category.SONAR)
    shape.filter = pymunk.ShapeFilter(categories=int(category), mask=mask)
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
