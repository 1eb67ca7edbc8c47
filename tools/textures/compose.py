"""Drawing the built-in set's composed textures: frames, doors, windows, shelves, signs.

Each function takes grey pictures (uint8, (H, W)) and returns one; the surfaces
(wood, brick, glass, stone) are photographs from :mod:`tools.textures.sources`, the
layout (frames, panels, books, lettering) is drawn with OpenCV. Scales are given as
pixels per metre (``ppm``) so that a drawn element has its real size.
"""

from __future__ import annotations

import itertools

import cv2
import numpy as np

from tools.textures.sources import GreyImage

FRAME_LEVEL = 40  # a dark picture frame
MOUNT_LEVEL = 235  # the white mount between frame and picture
_FONT = cv2.FONT_HERSHEY_SIMPLEX
_FONT_BOLD = cv2.FONT_HERSHEY_DUPLEX


def framed(image: GreyImage, frame_frac: float = 0.04, mount_frac: float = 0.05) -> GreyImage:
    """``image`` in a white mount and a dark frame, fractions of its shorter side."""
    side = min(image.shape)
    mount = max(2, round(mount_frac * side))
    frame = max(2, round(frame_frac * side))
    out = cv2.copyMakeBorder(image, mount, mount, mount, mount, cv2.BORDER_CONSTANT,
                             value=MOUNT_LEVEL)
    return cv2.copyMakeBorder(out, frame, frame, frame, frame, cv2.BORDER_CONSTANT,
                              value=FRAME_LEVEL)


def tiled(pattern: GreyImage, width_px: int, height_px: int) -> GreyImage:
    """``pattern`` repeated to cover ``width_px`` x ``height_px`` (cropped at the ends)."""
    h, w = pattern.shape
    reps = (-(-height_px // h), -(-width_px // w))
    return np.ascontiguousarray(np.tile(pattern, reps)[:height_px, :width_px])


def relevel(image: GreyImage, mean: float, std: float) -> GreyImage:
    """``image`` with its grey levels shifted and scaled to ``mean`` and ``std``."""
    im = image.astype(np.float64)
    spread = im.std()
    out = mean + (im - im.mean()) * (std / spread if spread > 0 else 0.0)
    return np.clip(np.rint(out), 0, 255).astype(np.uint8)


def _box(image: GreyImage, x0: int, y0: int, x1: int, y1: int, level: int,
         thickness: int = -1) -> None:
    cv2.rectangle(image, (x0, y0), (x1, y1), int(level), thickness, cv2.LINE_AA)


def _bevel(image: GreyImage, x0: int, y0: int, x1: int, y1: int, width: int,
           light: float = 22.0, dark: float = -30.0) -> None:
    """Shade a recessed panel's bevel, lit from above: its top and left edges in shadow,
    its bottom and right edges lit (grey levels added)."""
    im = image.astype(np.float64)
    im[y0:y0 + width, x0:x1] += dark
    im[y0 + width:y1, x0:x0 + width] += dark * 0.6
    im[y1 - width:y1, x0 + width:x1] += light
    im[y0 + width:y1 - width, x1 - width:x1] += light * 0.6
    image[:] = np.clip(im, 0, 255).astype(np.uint8)


def door(wood: GreyImage, ppm: float, panels: int, paint: GreyImage | None = None,
         glass: GreyImage | None = None) -> GreyImage:
    """A door in its frame, 1.0 x 2.1 m: a 0.86 x 2.03 m leaf with recessed panels.

    Args:
        wood: seamless wood, its grain running up the picture (as on a door's leaf).
        ppm: pixels per metre of the result.
        panels: recessed panels up the leaf (1 to 4); 0 for a flush leaf.
        paint: if given, a painted leaf: this texture instead of the wood.
        glass: if given, the upper panel is a glazed vision panel of this texture.

    Returns:
        (round(2.1 ppm), round(1.0 ppm)) uint8; the floor is the bottom row.
    """
    w, h = round(1.0 * ppm), round(2.1 * ppm)
    out = tiled(relevel(wood, 150, 25), w, h)  # the frame (architrave), lighter wood
    surface = paint if paint is not None else relevel(wood, 105, 28)
    leaf = tiled(surface, round(0.86 * ppm), round(2.03 * ppm))
    lh, lw = leaf.shape
    margin = round(0.12 * ppm)
    if panels:
        gap = round(0.08 * ppm)
        panel_h = (lh - 2 * margin - (panels - 1) * gap) // panels
        for i in range(panels):
            y0 = margin + i * (panel_h + gap)
            y1 = y0 + panel_h
            if glass is not None and i == 0:
                leaf[y0:y1, margin:lw - margin] = cv2.resize(glass, (lw - 2 * margin, panel_h))
                _box(leaf, margin, y0, lw - margin - 1, y1 - 1, 60, max(2, round(0.015 * ppm)))
            else:
                _bevel(leaf, margin, y0, lw - margin, y1, max(2, round(0.025 * ppm)))
    x0 = (w - lw) // 2
    out[h - lh:, x0:x0 + lw] = leaf
    _box(out, x0, h - lh, x0 + lw - 1, h - 1, 45, 2)  # the gap around the leaf
    # The lever handle and its rose, 1.0 m up, 7 cm from the lock edge.
    hx, hy = x0 + lw - round(0.07 * ppm), h - round(1.0 * ppm)
    cv2.circle(out, (hx, hy), round(0.03 * ppm), 200, -1, cv2.LINE_AA)
    cv2.circle(out, (hx, hy), round(0.03 * ppm), 90, 2, cv2.LINE_AA)
    _box(out, hx - round(0.13 * ppm), hy - round(0.012 * ppm), hx, hy + round(0.012 * ppm), 215)
    _box(out, hx - round(0.13 * ppm), hy - round(0.012 * ppm), hx, hy + round(0.012 * ppm), 70, 1)
    cv2.circle(out, (hx, hy + round(0.08 * ppm)), round(0.012 * ppm), 60, -1, cv2.LINE_AA)
    return out


def glass(sky: GreyImage, width_px: int, height_px: int, level: float,
          rng: np.random.Generator) -> GreyImage:
    """Glass seen from inside (``level`` ~ 230: daylight) or outside (~ 70: reflections).

    The sky photograph (rolled and flipped at random, so two panes differ), levelled
    and stretched, plus a diagonal sheen.
    """
    sky = np.roll(sky, tuple(int(v) for v in rng.integers(0, sky.shape)), axis=(0, 1))
    if rng.random() < 0.5:
        sky = sky[:, ::-1]
    base = relevel(cv2.resize(np.ascontiguousarray(sky), (width_px, height_px),
                              interpolation=cv2.INTER_CUBIC),
                   level, 10 if level > 128 else 22).astype(np.float64)
    y, x = np.mgrid[0:height_px, 0:width_px]
    angle = rng.uniform(0.3, 0.6)
    sheen = np.sin((x * np.cos(angle) + y * np.sin(angle)) / max(width_px, height_px) * 5.0)
    base += (12 if level > 128 else 18) * sheen
    return np.clip(base, 0, 255).astype(np.uint8)


def window(sky: GreyImage, ppm: float, width_m: float, height_m: float, cols: int, rows: int,
           frame_level: int, pane_level: float, rng: np.random.Generator) -> GreyImage:
    """A window: glass panes in a frame with mullions and transoms, and a sill below.

    Returns:
        (round(height_m ppm), round(width_m ppm)) uint8.
    """
    w, h = round(width_m * ppm), round(height_m * ppm)
    out = glass(sky, w, h, pane_level, rng)
    bar = max(3, round(0.05 * ppm))
    edge = max(4, round(0.07 * ppm))
    out[:edge, :] = frame_level
    out[-edge:, :] = frame_level
    out[:, :edge] = frame_level
    out[:, -edge:] = frame_level
    for i in range(1, cols):
        x = round(i * w / cols)
        out[:, x - bar // 2:x + bar - bar // 2] = frame_level
    for j in range(1, rows):
        y = round(j * h / rows)
        out[y - bar // 2:y + bar - bar // 2, :] = frame_level
    # The frame's inner edge casts a thin shadow on the glass.
    shade = frame_level * 0.6
    _box(out, edge, edge, w - edge - 1, h - edge - 1, round(shade), 1)
    sill = max(4, round(0.04 * ppm))
    out[-sill:, :] = min(255, frame_level + 25)
    return out


def facade(wall: GreyImage, sky: GreyImage, ppm: float, width_m: float, storey_m: float,
           windows: int, window_m: tuple[float, float], frame_level: int,
           rng: np.random.Generator) -> GreyImage:
    """One storey of an outside wall with ``windows`` windows, seamless in both directions.

    Windows are evenly spaced (so repeats keep the spacing), their sills 0.9 m up, each
    under a lintel; the glass shows a dark reflection of the sky.

    Returns:
        (round(storey_m ppm), round(width_m ppm)) uint8.
    """
    w, h = round(width_m * ppm), round(storey_m * ppm)
    out = tiled(wall, w, h)
    ww, wh = round(window_m[0] * ppm), round(window_m[1] * ppm)
    sill_y = h - round(0.9 * ppm)
    for i in range(windows):
        cx = round((i + 0.5) * w / windows)
        x0, y0 = cx - ww // 2, sill_y - wh
        pane = window(sky, ppm, window_m[0], window_m[1], 2, 1, frame_level,
                      rng.uniform(55, 85), rng)
        out[y0:sill_y, x0:x0 + ww] = pane
        lintel = round(0.12 * ppm)
        ext = round(0.08 * ppm)
        out[y0 - lintel:y0, x0 - ext:x0 + ww + ext] = relevel(
            out[y0 - lintel:y0, x0 - ext:x0 + ww + ext], 150, 14)
        _box(out, x0 - ext, y0 - lintel, x0 + ww + ext, y0, 80, 1)
        sill = round(0.05 * ppm)
        _box(out, x0 - ext, sill_y, x0 + ww + ext, sill_y + sill, 175)
        out[sill_y + sill:sill_y + sill + max(2, sill // 2), x0 - ext:x0 + ww + ext] //= 2
    return out


def _book(height_px: int, width_px: int, level: int, rng: np.random.Generator) -> GreyImage:
    """One book's spine: a level, shading across, bands and a title in small type."""
    x = np.linspace(-1.0, 1.0, width_px)
    spine = level * (1.0 - 0.18 * x**2) + rng.normal(0, 3, (height_px, width_px))
    spine = np.clip(spine, 0, 255).astype(np.uint8)
    ink = 235 if level < 120 else 25
    for _ in range(rng.integers(0, 3)):
        y = int(rng.integers(2, max(3, height_px - 6)))
        spine[y:y + max(2, height_px // 40), :] = ink
    if width_px >= 12:
        title = "".join(rng.choice(list("ABCDEFGHIKLMNOPRSTUVWXYZ"), int(rng.integers(4, 9))))
        text = np.full((width_px, height_px), level, np.uint8)
        scale = width_px / 40.0
        cv2.putText(text, title, (int(height_px * 0.15), int(width_px * 0.7)), _FONT, scale,
                    ink, max(1, round(scale * 1.5)), cv2.LINE_AA)
        rot = np.rot90(text, -1)
        mask = rot != level
        spine[mask] = rot[mask]
    return spine


def bookshelf(wood: GreyImage, ppm: float, rng: np.random.Generator) -> GreyImage:
    """A bookcase, 1.0 x 2.0 m: wooden sides and five shelves of books, some leaning.

    Returns:
        (round(2.0 ppm), round(1.0 ppm)) uint8.
    """
    w, h = round(1.0 * ppm), round(2.0 * ppm)
    out = tiled(relevel(wood, 120, 22), w, h)
    side = round(0.025 * ppm)
    shelves = 5
    board = round(0.025 * ppm)
    inner_h = (h - board) // shelves
    for s in range(shelves):
        top = s * inner_h + board
        bottom = (s + 1) * inner_h
        # The back panel, in shadow.
        out[top:bottom, side:w - side] = relevel(out[top:bottom, side:w - side], 45, 8)
        x = side + int(rng.integers(0, round(0.05 * ppm)))
        while x < w - side - round(0.02 * ppm):
            bw = round(rng.uniform(0.018, 0.06) * ppm)
            bh = round(rng.uniform(0.6, 0.95) * (bottom - top))
            if x + bw > w - side:
                break
            level = int(rng.choice([30, 55, 80, 110, 140, 170, 200, 225]))
            out[bottom - bh:bottom, x:x + bw] = _book(bh, bw, level, rng)
            out[bottom - bh:bottom, x] = out[bottom - bh:bottom, x] // 2
            x += bw + int(rng.integers(0, 3))
            if rng.random() < 0.04:  # a gap
                x += round(rng.uniform(0.05, 0.15) * ppm)
        # The shelf board's front edge, lit from above.
        out[bottom:bottom + board, :] = relevel(out[bottom:bottom + board, :], 150, 15)
    out[:board, :] = relevel(out[:board, :], 140, 15)
    return out


def cabinet(wood: GreyImage, ppm: float, width_m: float, height_m: float,
            drawers: int) -> GreyImage:
    """A cabinet front of ``drawers`` drawers (0: two doors), with handles.

    Returns:
        (round(height_m ppm), round(width_m ppm)) uint8; the floor is the bottom row.
    """
    w, h = round(width_m * ppm), round(height_m * ppm)
    out = tiled(wood, w, h)
    plinth = round(0.08 * ppm)
    out[h - plinth:, :] = relevel(out[h - plinth:, :], 40, 6)
    gap = max(2, round(0.004 * ppm))
    body = h - plinth
    handle_w, handle_h = round(0.12 * ppm), max(3, round(0.015 * ppm))
    if drawers:
        for i in range(1, drawers):
            y = round(i * body / drawers)
            out[y - gap:y + gap, :] = 30
        for i in range(drawers):
            cy = round((i + 0.25) * body / drawers)
            _box(out, w // 2 - handle_w // 2, cy, w // 2 + handle_w // 2, cy + handle_h, 210)
            _box(out, w // 2 - handle_w // 2, cy, w // 2 + handle_w // 2, cy + handle_h, 60, 1)
    else:
        out[:body, w // 2 - gap:w // 2 + gap] = 30
        for cx in (w // 2 - round(0.05 * ppm), w // 2 + round(0.05 * ppm)):
            _box(out, cx - handle_h // 2, body // 3, cx + handle_h // 2, body // 3 + handle_w, 210)
            _box(out, cx - handle_h // 2, body // 3, cx + handle_h // 2, body // 3 + handle_w,
                 60, 1)
    _box(out, 0, 0, w - 1, body - 1, 35, gap)
    return out


def desk_top(wood: GreyImage, ppm: float, width_m: float, depth_m: float) -> GreyImage:
    """A desk's top seen from above: wood with a darker edge band.

    Returns:
        (round(depth_m ppm), round(width_m ppm)) uint8.
    """
    w, h = round(width_m * ppm), round(depth_m * ppm)
    out = tiled(wood, w, h)
    band = max(2, round(0.012 * ppm))
    _box(out, 0, 0, w - 1, h - 1, 70, band)
    return out


def ceiling_tiles(mineral: GreyImage, ppm: float, tiles: int, rng: np.random.Generator
                  ) -> GreyImage:
    """A suspended ceiling: ``tiles`` x ``tiles`` 0.6 m mineral tiles in a T-bar grid.

    The bars (24 mm, light metal) sit on the picture's borders, half on each side, so
    repeats join. Returns a square (round(0.6 tiles ppm)) uint8 picture.
    """
    side = round(0.6 * tiles * ppm)
    out = tiled(relevel(mineral, 215, 9), side, side)
    # Fissures: short dark strokes, as in mineral-fibre tiles.
    for _ in range(int(60 * tiles * tiles)):
        x, y = rng.integers(0, side, 2)
        length = int(rng.integers(2, max(3, round(0.015 * ppm))))
        angle = rng.uniform(0, np.pi)
        x1, y1 = int(x + length * np.cos(angle)), int(y + length * np.sin(angle))
        cv2.line(out, (int(x), int(y)), (x1, y1), int(rng.integers(150, 185)), 1, cv2.LINE_AA)
    bar = max(2, round(0.024 * ppm))
    half = bar // 2
    for i in range(tiles + 1):
        p = round(i * side / tiles)
        out[max(0, p - half):p + bar - half, :] = 232
        out[:, max(0, p - half):p + bar - half] = 232
    return out


def ceiling_lamp(ppm: float, width_m: float, length_m: float, cells: tuple[int, int]
                 ) -> GreyImage:
    """A recessed fluorescent troffer: a metal rim and a louvre of bright cells.

    Returns:
        (round(length_m ppm), round(width_m ppm)) uint8.
    """
    w, h = round(width_m * ppm), round(length_m * ppm)
    out = np.full((h, w), 205, np.uint8)
    rim = max(3, round(0.03 * ppm))
    nx, ny = cells
    cw, ch = (w - 2 * rim) / nx, (h - 2 * rim) / ny
    for i in range(nx):
        for j in range(ny):
            x0, y0 = round(rim + i * cw), round(rim + j * ch)
            x1, y1 = round(rim + (i + 1) * cw), round(rim + (j + 1) * ch)
            yy, xx = np.mgrid[y0:y1, x0:x1]
            # A parabolic cell: brightest in its middle.
            r = np.maximum(np.abs((xx - (x0 + x1) / 2) / max(1, (x1 - x0) / 2)),
                           np.abs((yy - (y0 + y1) / 2) / max(1, (y1 - y0) / 2)))
            out[y0:y1, x0:x1] = np.clip(255 - 70 * r**3, 0, 255).astype(np.uint8)
            _box(out, x0, y0, x1 - 1, y1 - 1, 175, 1)
    _box(out, 0, 0, w - 1, h - 1, 150, rim)
    return out


def round_lamp(ppm: float, diameter_m: float, margin_m: float) -> GreyImage:
    """A round ceiling light on a white ceiling: a bright disc with a darker rim.

    Returns:
        A square uint8 picture of side round((diameter_m + 2 margin_m) ppm).
    """
    side = round((diameter_m + 2 * margin_m) * ppm)
    out = np.full((side, side), 218, np.uint8)
    c = side // 2
    r = round(diameter_m / 2 * ppm)
    yy, xx = np.mgrid[0:side, 0:side]
    d = np.hypot(xx - c, yy - c) / r
    disc = np.clip(255 - 25 * d**4, 0, 255)
    out[d <= 1.0] = disc[d <= 1.0].astype(np.uint8)
    cv2.circle(out, (c, c), r, 120, max(2, round(0.012 * ppm)), cv2.LINE_AA)
    return out


def _text_block(image: GreyImage, text: str, box: tuple[int, int, int, int], level: int,
                font: int = _FONT_BOLD) -> None:
    """Write ``text`` as large as fits, centred in ``box`` (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = box
    (tw, th), _ = cv2.getTextSize(text, font, 1.0, 2)
    scale = min((x1 - x0) * 0.9 / tw, (y1 - y0) * 0.75 / th)
    thickness = max(1, round(2.2 * scale))
    (tw, th), _ = cv2.getTextSize(text, font, scale, thickness)
    org = (x0 + (x1 - x0 - tw) // 2, y0 + (y1 - y0 + th) // 2)
    cv2.putText(image, text, org, font, scale, int(level), thickness, cv2.LINE_AA)


def exit_sign(ppm: float) -> GreyImage:
    """A lit emergency exit sign, 0.4 x 0.15 m: a running figure, a door, an arrow, EXIT.

    Returns:
        (round(0.15 ppm), round(0.4 ppm)) uint8: light figures on a dark field.
    """
    w, h = round(0.4 * ppm), round(0.15 * ppm)
    out = np.full((h, w), 70, np.uint8)
    s = h / 100.0
    line = max(2, round(7 * s))

    def pt(x: float, y: float) -> tuple[int, int]:
        return round(x * s), round(y * s)

    # The running figure: head, body, arms and legs in stride.
    cv2.circle(out, pt(40, 22), round(8 * s), 250, -1, cv2.LINE_AA)
    for a, b in [((38, 32), (32, 58)), ((36, 38), (52, 46)), ((36, 38), (22, 44)),
                 ((32, 58), (46, 70)), ((46, 70), (44, 86)), ((32, 58), (22, 74)),
                 ((22, 74), (10, 78))]:
        cv2.line(out, pt(*a), pt(*b), 250, line, cv2.LINE_AA)
    _box(out, *pt(60, 12), *pt(86, 88), 250, max(2, round(4 * s)))  # the door
    cv2.arrowedLine(out, pt(95, 50), pt(125, 50), 250, line, cv2.LINE_AA, tipLength=0.4)
    _text_block(out, "EXIT", (round(135 * s), 0, w, h), 250)
    _box(out, 0, 0, w - 1, h - 1, 200, max(2, round(3 * s)))
    return out


def room_sign(ppm: float, number: str, label: str) -> GreyImage:
    """A door plate, 0.2 x 0.1 m: the room number in large type and a label under it."""
    w, h = round(0.2 * ppm), round(0.1 * ppm)
    out = np.full((h, w), 225, np.uint8)
    _text_block(out, number, (0, round(0.05 * h), w, round(0.68 * h)), 35)
    _text_block(out, label, (round(0.1 * w), round(0.66 * h), round(0.9 * w), round(0.95 * h)),
                60, _FONT)
    _box(out, 0, 0, w - 1, h - 1, 90, max(2, round(0.004 * ppm)))
    return out


def light_switch(ppm: float, gangs: int) -> GreyImage:
    """A wall switch, 0.086 m square plate with ``gangs`` rockers, on a plain wall.

    Returns:
        A square uint8 picture of side round(0.12 ppm) (the plate and 17 mm of wall).
    """
    side = round(0.12 * ppm)
    out = np.full((side, side), 185, np.uint8)
    plate = round(0.086 * ppm)
    p0 = (side - plate) // 2
    shadow = max(2, round(0.003 * ppm))
    _box(out, p0 + shadow, p0 + shadow, p0 + plate + shadow, p0 + plate + shadow, 120)
    _box(out, p0, p0, p0 + plate, p0 + plate, 238)
    _box(out, p0, p0, p0 + plate, p0 + plate, 200, 1)
    inner = round(0.05 * ppm)
    i0 = (side - inner) // 2
    rw = inner // gangs
    for g in range(gangs):
        x0 = i0 + g * rw
        _box(out, x0 + 1, i0, x0 + rw - 1, i0 + inner, 246)
        _box(out, x0 + 1, i0, x0 + rw - 1, i0 + inner // 2, 228)  # the rocker's lower half
        _box(out, x0 + 1, i0, x0 + rw - 1, i0 + inner, 150, 1)
    return out


def noticeboard(cork: GreyImage, paper: GreyImage, notices: list[GreyImage], ppm: float,
                rng: np.random.Generator) -> GreyImage:
    """A cork board, 0.9 x 0.6 m in an aluminium frame, with pinned sheets.

    Args:
        cork: seamless cork.
        paper: seamless paper, for blank sheets.
        notices: pictures pinned as printed sheets (text, photographs).
    """
    w, h = round(0.9 * ppm), round(0.6 * ppm)
    out = tiled(relevel(cork, 125, 16), w, h)
    frame = round(0.02 * ppm)
    sheets = [*notices, relevel(paper, 232, 6), relevel(paper, 225, 6)]
    slots = [(0.06, 0.08), (0.36, 0.06), (0.64, 0.1), (0.12, 0.52), (0.48, 0.5)]
    for (fx, fy), sheet in zip(slots, sheets, strict=False):
        sw = round(rng.uniform(0.18, 0.24) * ppm)
        sh = round(sw * 1.41) if sheet.shape[0] >= sheet.shape[1] else round(sw * 0.75)
        x0, y0 = round(fx * w), round(fy * h)
        sh = min(sh, h - frame - y0 - 2)
        sw = min(sw, w - frame - x0 - 2)
        piece = cv2.resize(sheet, (sw, sh), interpolation=cv2.INTER_AREA)
        out[y0 + 3:y0 + sh + 3, x0 + 3:x0 + sw + 3] //= 2  # its shadow
        out[y0:y0 + sh, x0:x0 + sw] = piece
        cv2.circle(out, (x0 + sw // 2, y0 + 6), max(3, round(0.006 * ppm)),
                   int(rng.choice([40, 90, 200])), -1, cv2.LINE_AA)
    _box(out, 0, 0, w - 1, h - 1, 175, frame)
    return out


def printed_page(ppm: float, title: str, rng: np.random.Generator) -> GreyImage:
    """An A4 sheet, 0.21 x 0.297 m: a heading and lines of text-like words."""
    w, h = round(0.21 * ppm), round(0.297 * ppm)
    out = np.full((h, w), 238, np.uint8)
    margin = round(0.02 * ppm)
    _text_block(out, title, (margin, margin, w - margin, margin + round(0.03 * ppm)), 25)
    y = margin + round(0.05 * ppm)
    line = max(3, round(0.007 * ppm))
    while y < h - margin:
        x = margin
        end = w - margin - (round(rng.uniform(0, 0.08) * ppm) if rng.random() < 0.2 else 0)
        while x < end:
            word = round(rng.uniform(0.006, 0.025) * ppm)
            cv2.rectangle(out, (x, y), (min(x + word, end), y + line // 2), 80, -1)
            x += word + round(0.003 * ppm)
        y += line + round(0.002 * ppm)
    return out


def crop_resized(image: GreyImage, box: tuple[int, int, int, int],
                 size: tuple[int, int] | None = None) -> GreyImage:
    """``image[y:y+h, x:x+w]`` for ``box`` (x, y, w, h), resized to ``size`` (w, h)."""
    x, y, w, h = box
    out = np.ascontiguousarray(image[y:y + h, x:x + w])
    if size is not None:
        out = cv2.resize(out, size, interpolation=cv2.INTER_AREA)
    return out



def bookshelf_photo(wood: GreyImage, books: list[GreyImage], ppm: float) -> GreyImage:
    """A bookcase, 1.0 x 2.0 m: wooden sides and five shelves, each filled with a
    photograph of a row of books (cycled through ``books``).

    Returns:
        (round(2.0 ppm), round(1.0 ppm)) uint8.
    """
    w, h = round(1.0 * ppm), round(2.0 * ppm)
    out = tiled(relevel(wood, 120, 22), w, h)
    side = round(0.025 * ppm)
    board = round(0.025 * ppm)
    shelves = 5
    inner_h = (h - board) // shelves
    for s in range(shelves):
        top = s * inner_h + board
        bottom = (s + 1) * inner_h
        out[top:bottom, side:w - side] = relevel(out[top:bottom, side:w - side], 40, 6)
        row = books[s % len(books)]
        bh = round(0.88 * (bottom - top))
        photo = cv2.resize(row, (w - 2 * side, bh), interpolation=cv2.INTER_AREA)
        out[bottom - bh:bottom, side:w - side] = photo
        out[bottom:bottom + board, :] = relevel(out[bottom:bottom + board, :], 150, 15)
    out[:board, :] = relevel(out[:board, :], 140, 15)
    return out


def metal_door(metal: GreyImage, ppm: float) -> GreyImage:
    """A flush steel door, 1.0 x 2.1 m in its frame, with a push bar and a kick plate."""
    w, h = round(1.0 * ppm), round(2.1 * ppm)
    out = tiled(relevel(metal, 95, 10), w, h)
    leaf = tiled(relevel(metal, 165, 12), round(0.86 * ppm), round(2.03 * ppm))
    lh, lw = leaf.shape
    x0 = (w - lw) // 2
    out[h - lh:, x0:x0 + lw] = leaf
    _box(out, x0, h - lh, x0 + lw - 1, h - 1, 50, 2)
    bar_y = h - round(1.0 * ppm)
    _box(out, x0 + round(0.08 * ppm), bar_y - round(0.025 * ppm), x0 + lw - round(0.08 * ppm),
         bar_y + round(0.025 * ppm), 215)
    _box(out, x0 + round(0.08 * ppm), bar_y - round(0.025 * ppm), x0 + lw - round(0.08 * ppm),
         bar_y + round(0.025 * ppm), 70, 2)
    kick = round(0.25 * ppm)
    out[h - kick:, x0 + 4:x0 + lw - 4] = relevel(out[h - kick:, x0 + 4:x0 + lw - 4], 200, 8)
    return out


def glass_doors(metal: GreyImage, outside: GreyImage, ppm: float) -> GreyImage:
    """An entrance, 2.0 x 2.3 m: two glazed leaves in metal frames, a transom above.

    Args:
        metal: seamless metal, for the frames.
        outside: the bright view through the glass (already of its final levels).

    Returns:
        (round(2.3 ppm), round(2.0 ppm)) uint8; the floor is the bottom row.
    """
    w, h = round(2.0 * ppm), round(2.3 * ppm)
    frame = tiled(relevel(metal, 110, 10), w, h)
    out = frame.copy()
    bar = round(0.06 * ppm)
    transom_y = round(0.22 * ppm)
    glass_w, glass_h = w - 2 * bar, h - bar
    out[bar:h, bar:w - bar] = cv2.resize(outside, (glass_w, glass_h - bar + bar),
                                         interpolation=cv2.INTER_CUBIC)[:h - bar]
    out[transom_y:transom_y + bar, :] = frame[transom_y:transom_y + bar, :]
    mid = w // 2
    out[:, mid - bar:mid + bar] = frame[:, mid - bar:mid + bar]  # the two leaves' stiles
    kick = round(0.15 * ppm)
    out[h - kick:, :] = frame[h - kick:, :]
    for x0, x1 in ((bar, mid - bar), (mid + bar, w - bar)):
        bar_y = h - round(1.0 * ppm)
        _box(out, x0 + round(0.05 * ppm), bar_y - round(0.02 * ppm), x1 - round(0.05 * ppm),
             bar_y + round(0.02 * ppm), 200)
        _box(out, x0 + round(0.05 * ppm), bar_y - round(0.02 * ppm), x1 - round(0.05 * ppm),
             bar_y + round(0.02 * ppm), 60, 1)
    return out


def whiteboard(ppm: float, rng: np.random.Generator) -> GreyImage:
    """A whiteboard, 1.8 x 1.2 m: an aluminium frame, a pen tray, marker notes and a sketch.

    Returns:
        (round(1.2 ppm), round(1.8 ppm)) uint8.
    """
    w, h = round(1.8 * ppm), round(1.2 * ppm)
    y, x = np.mgrid[0:h, 0:w]
    board = 232 + 10 * np.sin((x + 0.6 * y) / w * 3.0)  # a broad sheen
    out = np.clip(board, 0, 255).astype(np.uint8)
    font = cv2.FONT_HERSHEY_SCRIPT_SIMPLEX
    scale = ppm / 300.0
    lines = ["Meeting 10:00", "- teach route", "- repeat x20", "TODO: lens?"]
    for i, text in enumerate(lines):
        cv2.putText(out, text, (round(0.08 * ppm), round((0.18 + 0.14 * i) * ppm)), font,
                    1.3 * scale, int(rng.choice([20, 45, 70])), max(1, round(2 * scale)),
                    cv2.LINE_AA)
    # A sketch: boxes joined by arrows.
    boxes = [(1.0, 0.2), (1.45, 0.2), (1.0, 0.6), (1.45, 0.6)]
    for bx, by in boxes:
        _box(out, round(bx * ppm), round(by * ppm), round((bx + 0.25) * ppm),
             round((by + 0.18) * ppm), 40, max(2, round(2 * scale)))
    for (ax, ay), (bx, by) in itertools.pairwise(boxes):
        cv2.arrowedLine(out, (round((ax + 0.125) * ppm), round((ay + 0.18) * ppm)),
                        (round((bx + 0.125) * ppm), round(by * ppm)), 40,
                        max(2, round(2 * scale)), cv2.LINE_AA, tipLength=0.08)
    frame = round(0.02 * ppm)
    _box(out, 0, 0, w - 1, h - 1, 170, frame)
    tray = round(0.04 * ppm)
    out[h - tray:, :] = 150
    out[h - tray:h - tray + 2, :] = 200
    return out


def radiator(metal: GreyImage, ppm: float, width_m: float, height_m: float) -> GreyImage:
    """A column radiator, painted white: rounded vertical columns every 5 cm, a valve.

    Returns:
        (round(height_m ppm), round(width_m ppm)) uint8.
    """
    w, h = round(width_m * ppm), round(height_m * ppm)
    base = relevel(tiled(metal, w, h), 215, 5).astype(np.float64)
    pitch = 0.05 * ppm
    x = np.arange(w)
    phase = (x % pitch) / pitch  # 0..1 across a column
    shade = 35.0 * np.cos(np.pi * (phase - 0.4)) - 25.0  # lit from the left, gaps in shadow
    out = base + shade[None, :]
    out[:round(0.03 * ppm), :] = 230  # the top rail
    out[h - round(0.03 * ppm):, :] = 200  # the bottom rail
    out = np.clip(out, 0, 255).astype(np.uint8)
    r = round(0.02 * ppm)
    cv2.circle(out, (w - 2 * r, h - 3 * r), r, 120, -1, cv2.LINE_AA)
    return out
