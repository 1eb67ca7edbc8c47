"""The textures a scene uses, as mip pyramids in one flat array (what the ray kernel reads).

Each texture gets an id in the order it is first asked for. Its pyramid starts at
the picture itself (shrunk to at most :data:`MAX_SIDE_PX` on its longer side) and
halves, area-averaged (``cv2.INTER_AREA``: no aliasing), down to a few pixels. A
tiling texture is shrunk with wrap-around borders, so its levels still tile.

Each level is stored with a border of one texel on every side: the opposite edge's
texels for a tiling texture (wrap-around), copies of its own edge otherwise (clamp).
The kernel's bilinear filter then reads its four texels without any wrapping or
clamping of indices (:func:`sim._raycast._bilinear`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
import numpy.typing as npt

from sim.texture_library import Texture, TextureLibrary

MAX_SIDE_PX = 1024
"""Longest side of a pyramid's finest level, px."""
MAX_LEVELS = 12
"""Levels of a pyramid at most (1024 px down to 1 px)."""


@dataclass
class Atlas:
    """Texture pyramids in one flat array.

    Attributes:
        texels: (N,) float32, every level of every texture, row-major with its
            one-texel border (module docstring), grey 0..255.
        levels: (T, MAX_LEVELS, 3) int64: offset into ``texels`` of texel (0, 0)
            (inside the border), width, height of each level (width 0 past a
            pyramid's last level); a level's rows are ``width + 2`` texels apart.
        level_count: (T,) int64, levels of each pyramid.
        wraps: (T,) bool, whether the texture tiles (else its border is clamped).
        names: texture name of each id.
    """

    library: TextureLibrary
    texels: npt.NDArray[np.float32] = field(default_factory=lambda: np.zeros(0, np.float32))
    levels: npt.NDArray[np.int64] = field(
        default_factory=lambda: np.zeros((0, MAX_LEVELS, 3), np.int64))
    level_count: npt.NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    wraps: npt.NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, bool))
    names: list[str] = field(default_factory=list)
    _chunks: list[npt.NDArray[np.float32]] = field(default_factory=list)
    _size: int = 0
    _levels: list[npt.NDArray[np.int64]] = field(default_factory=list)

    def texture(self, name: str) -> Texture:
        """The library's texture ``name`` (raises ``ConfigError`` if unknown)."""
        return self.library.get(name)

    def id_of(self, name: str) -> int:
        """The id of texture ``name``, adding its pyramid on first use."""
        if name in self.names:
            return self.names.index(name)
        texture = self.library.get(name)
        table = np.zeros((MAX_LEVELS, 3), np.int64)
        border = cv2.BORDER_WRAP if texture.tiles else cv2.BORDER_REPLICATE
        for k, level in enumerate(_pyramid(texture)):
            h, w = level.shape
            table[k] = (self._size + (w + 2) + 1, w, h)
            padded = cv2.copyMakeBorder(level, 1, 1, 1, 1, border)
            self._chunks.append(padded.ravel())
            self._size += padded.size
        self._levels.append(table)
        self.names.append(name)
        return len(self.names) - 1

    def freeze(self) -> Atlas:
        """Gather the pyramids added so far into the flat arrays; returns self."""
        self.texels = (np.concatenate(self._chunks) if self._chunks
                       else np.zeros(1, np.float32)).astype(np.float32)
        self.levels = (np.stack(self._levels) if self._levels
                       else np.zeros((0, MAX_LEVELS, 3), np.int64))
        self.level_count = (self.levels[:, :, 1] > 0).sum(axis=1).astype(np.int64)
        self.wraps = np.array([self.library.get(n).tiles for n in self.names], dtype=bool)
        return self


def _pyramid(texture: Texture) -> list[npt.NDArray[np.float32]]:
    """The texture's levels, finest first, float32 grey."""
    image = texture.image.astype(np.float32)
    h, w = image.shape
    if max(h, w) > MAX_SIDE_PX:
        f = MAX_SIDE_PX / max(h, w)
        image = cv2.resize(image, (max(1, round(w * f)), max(1, round(h * f))),
                           interpolation=cv2.INTER_AREA)
    levels = [image]
    while len(levels) < MAX_LEVELS and max(levels[-1].shape) > 1:
        prev = levels[-1]
        ph, pw = prev.shape
        nw, nh = max(1, pw // 2), max(1, ph // 2)
        if texture.tiles:
            # Average 2 x 2 blocks with wrap-around, so the level tiles as the picture does.
            pad = np.pad(prev, ((0, ph % 2), (0, pw % 2)), mode="wrap")
            shrunk = cv2.resize(pad, (nw, nh), interpolation=cv2.INTER_AREA)
        else:
            shrunk = cv2.resize(prev, (nw, nh), interpolation=cv2.INTER_AREA)
        levels.append(shrunk.astype(np.float32))
    return levels
