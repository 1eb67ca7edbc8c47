"""Textures for the simulator's surfaces: grey pictures with their size in metres.

A texture set is a folder holding a manifest, ``textures.toml``, and the pictures it
names. The built-in set is ``sim/textures/`` (photographs from free-licensed sources,
each file's source and licence in the manifest; see its README); a user's own set has
the same format and is read with :meth:`TextureLibrary.load`.

Manifest format: one table per texture, named by the texture::

    [brick_red]
    file = "brick_red.jpg"         # a PNG or JPEG beside the manifest, read as grey
    size_m = [1.2, 0.8]            # width, height of the whole picture, m (> 0)
    tiles = true                   # repeats seamlessly (walls, floors) or not (a poster)
    kind = "wall"                  # one of KINDS
    source = "where the file came from"
    licence = "CC0-1.0"            # an SPDX identifier

or, instead of ``file``, ``procedural = "<generator>"`` with a ``params`` table
(:mod:`sim.procedural_textures`; the picture is generated when the set is loaded).

Frame of a picture: row 0 is the top of the surface as one faces it, column 0 its
left; ``size_m`` spans the whole picture, so a pixel is ``size_m[0] / W`` m wide.

Errors: an unknown texture name, an unknown key, a file that is missing or does not
decode, a ``size_m`` that is not two finite numbers > 0, an unknown ``kind`` or
generator: :class:`shared.errors.ConfigError`, one line naming the manifest, the
entry and the problem. Nothing falls back to a plain grey.
"""

from __future__ import annotations

import dataclasses
import difflib
import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from shared.config import from_mapping, load_toml, require
from shared.errors import ConfigError, InputError
from shared.image_decode import read_grey
from sim.procedural_textures import GENERATORS

#: What a texture is for; a world asks for textures of a kind.
KINDS = ("wall", "floor", "ceiling", "door", "window", "furniture", "picture", "sign",
         "facade", "tree", "person", "lamp")

#: The built-in set's manifest.
BUILTIN_MANIFEST = Path(__file__).resolve().parent / "textures" / "textures.toml"

#: Largest picture a manifest may name, pixels (a 4096 x 4096 texture).
MAX_TEXTURE_PIXELS = 1 << 24


@dataclass(frozen=True, eq=False)
class Texture:
    """One texture: a grey picture and the physical size it spans.

    Attributes:
        name: the manifest's table name.
        image: (H, W) uint8 grey, C-contiguous, read-only; row 0 at the top.
        size_m: (width, height) of the whole picture on its surface, m.
        tiles: True if the picture repeats seamlessly in both directions.
        kind: one of :data:`KINDS`.
    """

    name: str
    image: npt.NDArray[np.uint8]
    size_m: tuple[float, float]
    tiles: bool
    kind: str

    @property
    def px_per_m(self) -> tuple[float, float]:
        """Pixels per metre along the picture's width and height."""
        h, w = self.image.shape
        return w / self.size_m[0], h / self.size_m[1]


@dataclass(frozen=True, slots=True)
class _Entry:
    """One table of the manifest (``params`` is read apart, by its generator's class)."""

    size_m: tuple[float, float]
    kind: str
    source: str
    licence: str
    tiles: bool = False
    file: str | None = None
    procedural: str | None = None

    def __post_init__(self) -> None:
        require(all(math.isfinite(v) and v > 0 for v in self.size_m),
                f"size_m must be two finite numbers > 0 (width, height in m), "
                f"got {list(self.size_m)}")
        require(self.kind in KINDS, f"unknown kind '{self.kind}' (known: {', '.join(KINDS)})")
        require((self.file is None) != (self.procedural is None),
                "give exactly one of 'file' and 'procedural'")
        require(self.procedural is None or self.procedural in GENERATORS,
                f"unknown procedural generator '{self.procedural}' "
                f"(known: {', '.join(sorted(GENERATORS))})")
        require(bool(self.source.strip()), "source must say where the picture came from")
        require(bool(self.licence.strip()), "licence must name the picture's licence")


class TextureLibrary:
    """A set of textures by name, all read (and checked) when the set is loaded."""

    def __init__(self, textures: Mapping[str, Texture], source: str) -> None:
        """Use :meth:`builtin` or :meth:`load`.

        Args:
            textures: the textures by name.
            source: where they came from (the manifest), for messages.
        """
        self._textures = dict(textures)
        self._source = source

    @classmethod
    @functools.cache
    def builtin(cls) -> TextureLibrary:
        """The vendored set, ``sim/textures/`` (read once per process)."""
        # The folder beside this module, not importlib.resources: the manifest names
        # pictures beside it, and as_file() may copy a single file out of its folder.
        return cls.load(BUILTIN_MANIFEST)

    @classmethod
    def load(cls, manifest: Path) -> TextureLibrary:
        """Read a texture set: its manifest and every picture it names.

        Raises:
            ConfigError: the manifest or a picture is bad (one line naming the manifest,
                the entry and the problem).
        """
        manifest = Path(manifest)
        data = load_toml(manifest)
        if not data:
            raise ConfigError(manifest, "no texture in the manifest")
        textures = {name: _read_entry(manifest, name, table) for name, table in data.items()}
        return cls(textures, str(manifest))

    def get(self, name: str) -> Texture:
        """The texture called ``name``.

        Raises:
            ConfigError: no texture of that name in the set.
        """
        try:
            return self._textures[name]
        except KeyError:
            close = difflib.get_close_matches(name, self._textures, n=3)
            hint = f"did you mean {', '.join(close)}?" if close else "see its names()"
            raise ConfigError(self._source, f"unknown texture '{name}' "
                                            f"({len(self._textures)} textures; {hint})") from None

    def names(self, kind: str | None = None) -> tuple[str, ...]:
        """The textures' names, sorted; only those of ``kind`` if given.

        Raises:
            ConfigError: ``kind`` is not one of :data:`KINDS`.
        """
        if kind is not None and kind not in KINDS:
            raise ConfigError(self._source, f"unknown texture kind '{kind}' "
                                            f"(known: {', '.join(KINDS)})")
        return tuple(sorted(n for n, t in self._textures.items()
                            if kind is None or t.kind == kind))


def _read_entry(manifest: Path, name: str, table: Any) -> Texture:
    """The texture of the manifest's table ``name`` (checks, reads or generates it)."""
    where = f"[{name}]"
    if not isinstance(table, dict):
        raise ConfigError(manifest, f"{where}: expected a table, got {type(table).__name__}")
    table = dict(table)
    params = table.pop("params", None)
    entry = from_mapping(_Entry, table, str(manifest), where)
    if entry.file is not None:
        if params is not None:
            raise ConfigError(manifest, f"{where}: 'params' is for a procedural texture only")
        image = _read_picture(manifest, where, manifest.parent / entry.file)
    else:
        assert entry.procedural is not None
        params_cls, generate = GENERATORS[entry.procedural]
        image = generate(from_mapping(params_cls, params or {}, str(manifest),
                                      f"{where}.params"))
    image = np.ascontiguousarray(image)
    image.flags.writeable = False
    fields = {f.name for f in dataclasses.fields(Texture)} - {"name", "image"}
    return Texture(name=name, image=image,
                   **{f: getattr(entry, f) for f in sorted(fields)})


def _read_picture(manifest: Path, where: str, path: Path) -> npt.NDArray[np.uint8]:
    """The grey picture at ``path``, decoded through the project's checked decode."""
    try:
        return read_grey(path, MAX_TEXTURE_PIXELS)
    except InputError as e:
        raise ConfigError(manifest, f"{where}: file {path.name}: {e.problem}") from None
