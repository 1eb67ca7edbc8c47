"""Top-down map of a simulated world: walls, furniture, landmarks, people, the robot, its view.

Pure drawing on a colour (BGR uint8) canvas with OpenCV; the caller writes the file.
World frame: x right, y up on the map (the image's rows are flipped).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import numpy.typing as npt

from sim._geometry import box_corners
from sim._world_checks import place_picture
from sim.landmarks import Surface
from sim.renderer import RenderedFrame
from sim.simulation import OCCLUDER_FILTER, Simulation
from sim.world import World

_MARGIN_M = 1.0
_FOV_RAYS = 181
_FOV_RANGE_M = 30.0

# BGR colours.
_BACKGROUND = (250, 250, 250)
_CEILING = (235, 228, 222)
_WALL = (40, 40, 40)
_FURNITURE = (150, 170, 190)
_FOV = (170, 235, 255)
_LANDMARK = {
    Surface.WALL: (180, 120, 60),
    Surface.FURNITURE: (60, 140, 60),
    Surface.CEILING: (170, 170, 170),
}
_VISIBLE = (30, 30, 220)
_TREE = (60, 150, 60)
_PERSON = (60, 60, 160)
_ROBOT = (200, 80, 20)


class MapCanvas:
    """Maps world metres to pixels of a canvas covering the world's walls.

    ``image`` is the canvas, blank: (H, W, 3) uint8 BGR.

    Args:
        sim: the simulation whose world sets the extent.
        px_per_m: scale, pixels per metre.
    """

    def __init__(self, sim: Simulation, px_per_m: float = 30.0) -> None:
        pts = np.array([p for w in sim.world.walls for p in (w.start, w.end)], dtype=np.float64)
        self.min_xy = pts.min(axis=0) - _MARGIN_M
        max_xy = pts.max(axis=0) + _MARGIN_M
        self.px_per_m = px_per_m
        w, h = np.ceil((max_xy - self.min_xy) * px_per_m).astype(int)
        self.image = np.full((int(h), int(w), 3), _BACKGROUND, dtype=np.uint8)

    def px(self, xy_w: npt.ArrayLike) -> npt.NDArray[np.int32]:
        """World points (N, 2) m -> canvas pixels (N, 2) int32 (y flipped)."""
        xy = np.atleast_2d(np.asarray(xy_w, dtype=np.float64))
        u = (xy[:, 0] - self.min_xy[0]) * self.px_per_m
        v = self.image.shape[0] - 1 - (xy[:, 1] - self.min_xy[1]) * self.px_per_m
        return np.round(np.column_stack([u, v])).astype(np.int32)


class TopDownMap:
    """A simulation's top-down map: the world, the robot and the camera's view of the field.

    What does not move is drawn once: the ceilings (the layer under the view's fan) and
    the furniture, objects, trees and walls (the layer over it, with the mask of its
    pixels), drawn again only when objects are added or taken away
    (:attr:`sim.simulation.Simulation.objects_revision`); the pictures' strokes are placed
    once. A video draws a map every other frame.

    Args:
        sim: the simulation (its world sets the extent).
        px_per_m: map scale.
    """

    def __init__(self, sim: Simulation, px_per_m: float = 30.0) -> None:
        self.canvas = MapCanvas(sim, px_per_m)
        self._strokes_px = ([] if len(sim.landmarks) else
                            [self.canvas.px(stroke) for stroke in picture_strokes(sim.world)])
        self._draw_still(sim)

    def draw(self, sim: Simulation, frame: RenderedFrame, fov_deg: float) -> npt.NDArray[np.uint8]:
        """The map now.

        Args:
            sim: the simulation this map was made for (landmarks, people, robot).
            frame: the frame just rendered (its visible landmarks are highlighted).
            fov_deg: the lens's field of view, degrees (the fan drawn on the floor).

        Returns:
            (H, W, 3) uint8 BGR image, the caller's.
        """
        if sim.objects_revision != self._revision:
            self._draw_still(sim)
        canvas = self.canvas
        img = self._under.copy()
        cv2.fillPoly(img, [canvas.px(_fov_polygon(sim, frame, fov_deg))], _FOV,
                     lineType=cv2.LINE_AA)
        cv2.copyTo(self._over, self._over_mask, img)
        if len(sim.landmarks):
            _draw_patches(canvas, img, sim, frame)
        else:
            _draw_pictures(img, self._strokes_px, frame)
        positions, radius, _ = sim.people_state()
        for p in canvas.px(positions) if len(positions) else []:
            cv2.circle(img, (int(p[0]), int(p[1])), max(int(radius * canvas.px_per_m), 2),
                       _PERSON, -1, cv2.LINE_AA)
        _draw_robot(canvas, img, sim)
        return img

    def _draw_still(self, sim: Simulation) -> None:
        """The layers under and over the view's fan."""
        canvas = self.canvas
        under = canvas.image.copy()
        for ceiling in sim.world.ceilings:
            (x0, y0), (x1, y1) = ceiling.min_corner, ceiling.max_corner
            corners = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
            cv2.fillPoly(under, [canvas.px(corners)], _CEILING)
        over = under.copy()
        added = np.array([box_corners(*o.footprint()) for o in sim.added_objects.values()],
                         dtype=float).reshape(-1, 4, 2)
        for corners in np.concatenate([sim.world.furniture_corners(),
                                       sim.world.object_corners(), added]):
            cv2.fillPoly(over, [canvas.px(corners)], _FURNITURE, lineType=cv2.LINE_AA)
        px_per_m = canvas.px_per_m
        for tree in sim.world.trees:
            (u, v), = canvas.px([tree.at])
            cv2.circle(over, (int(u), int(v)), max(int(tree.crown_radius_m * px_per_m), 2),
                       _TREE, 1, cv2.LINE_AA)
            cv2.circle(over, (int(u), int(v)), max(int(tree.trunk_radius_m * px_per_m), 2),
                       _FURNITURE, -1, cv2.LINE_AA)
        for wall in sim.world.walls:
            a, b = canvas.px([wall.start, wall.end])
            cv2.line(over, tuple(int(v) for v in a), tuple(int(v) for v in b), _WALL, 3,
                     cv2.LINE_AA)
        self._under, self._over = under, over
        self._over_mask = (over != under).any(axis=2).astype(np.uint8)
        self._revision = sim.objects_revision


def draw_topdown(sim: Simulation, frame: RenderedFrame, fov_deg: float,
                 px_per_m: float = 30.0) -> npt.NDArray[np.uint8]:
    """One map of ``sim`` now (:meth:`TopDownMap.draw`; a video keeps a :class:`TopDownMap`).

    Returns:
        (H, W, 3) uint8 BGR image.
    """
    return TopDownMap(sim, px_per_m).draw(sim, frame, fov_deg)


def _draw_patches(canvas: MapCanvas, img: npt.NDArray[np.uint8], sim: Simulation,
                  frame: RenderedFrame) -> None:
    """Legacy landmark patches, coloured by surface; those in view circled."""
    lm = sim.landmarks
    pts = canvas.px(lm.positions_w[:, :2])
    for surface, colour in _LANDMARK.items():
        for u, v in pts[lm.surface == surface]:
            img[max(v - 1, 0) : v + 1, max(u - 1, 0) : u + 1] = colour
    for u, v in pts[np.isin(lm.ids, frame.visible_ids)]:
        cv2.circle(img, (int(u), int(v)), 2, _VISIBLE, -1, cv2.LINE_AA)


#: Each picture of a world as a stroke on the plan, a hand's breadth off its wall: (2, 2)
#: its ends, world frame, m.
PictureStrokes = list[npt.NDArray[np.float64]]


def picture_strokes(world: World) -> PictureStrokes:
    """The pictures on the walls as :data:`PictureStrokes`, in the world's order."""
    strokes = []
    for picture in world.pictures:
        place = place_picture(world.walls, picture)
        wall = world.walls[place.wall]
        d = np.subtract(wall.end, wall.start) / wall.length_m
        n = place.side * np.array([-d[1], d[0]]) * 0.12
        width = (picture.size or world.textures().get(picture.texture).size_m)[0]
        centre = np.asarray(wall.start) + place.along_m * d + n
        strokes.append(np.array([centre - 0.5 * width * d, centre + 0.5 * width * d]))
    return strokes


def _draw_pictures(img: npt.NDArray[np.uint8], strokes_px: list[npt.NDArray[np.int32]],
                   frame: RenderedFrame) -> None:
    """Pictures on the walls as short strokes (their ends (2, 2) in map pixels); those with
    a corner in view in red."""
    seen = set((np.asarray(frame.visible_ids) // 4).tolist())
    for i, (a, b) in enumerate(strokes_px):
        colour = _VISIBLE if i in seen else _LANDMARK[Surface.WALL]
        cv2.line(img, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), colour, 2, cv2.LINE_AA)


def _fov_polygon(sim: Simulation, frame: RenderedFrame, fov_deg: float) -> npt.NDArray[np.float64]:
    """The floor-plan region the camera sees: its horizontal FOV fan, cut by walls and furniture."""
    cam = frame.T_world_cam
    cx, cy = float(cam[0, 3]), float(cam[1, 3])
    axis = cam[:3, 2]
    heading = math.atan2(axis[1], axis[0])
    half = math.radians(min(fov_deg, 359.0) / 2.0)
    pts = [(cx, cy)]
    for ang in np.linspace(heading - half, heading + half, _FOV_RAYS):
        end = (cx + _FOV_RANGE_M * math.cos(ang), cy + _FOV_RANGE_M * math.sin(ang))
        hit = sim.space.segment_query_first((cx, cy), end, 0.0, OCCLUDER_FILTER)
        pts.append(tuple(hit.point) if hit is not None else end)
    return np.array(pts)


def _draw_robot(canvas: MapCanvas, img: npt.NDArray[np.uint8], sim: Simulation) -> None:
    """The robot's footprint and a heading arrow."""
    x, y, yaw = sim.body.pose_w
    half_l, half_w = sim.config.body.length_m / 2.0, sim.config.body.width_m / 2.0
    c, s = math.cos(yaw), math.sin(yaw)
    corners = [
        (x + c * dx - s * dy, y + s * dx + c * dy)
        for dx, dy in ((half_l, half_w), (half_l, -half_w), (-half_l, -half_w), (-half_l, half_w))
    ]
    cv2.fillPoly(img, [canvas.px(corners)], _ROBOT, lineType=cv2.LINE_AA)
    tip = (x + c * 0.8, y + s * 0.8)
    a, b = canvas.px([(x, y), tip])
    cv2.arrowedLine(
        img,
        tuple(int(v) for v in a),
        tuple(int(v) for v in b),
        (0, 0, 0),
        2,
        cv2.LINE_AA,
        tipLength=0.3,
    )
