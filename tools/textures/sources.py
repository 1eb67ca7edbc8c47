"""The free-licensed pictures the built-in textures are made from, and how to fetch them.

Three packages, each fetched with its ordinary client and pinned to one version:

* scikit-image's wheel from PyPI (``pip download``): its ``skimage/data/`` holds
  photographs whose licences its ``skimage/data/_fetchers.py`` states, function by
  function (CC0 or public domain for the ones used here);
* Debian's ``gimp-data`` (``apt-get download``): GIMP's patterns,
  ``usr/share/gimp/2.0/patterns/*/*.pat``, photographic tiles covered by the
  package's ``usr/share/doc/gimp-data/copyright`` stanza ``Files: *`` (GPL-3+);
* Debian's ``sweethome3d-furniture`` (``apt-get download``): furniture libraries
  (``usr/share/sweethome3d/furniture/*.sh3f``, zip files) whose models carry
  photographic textures, licensed per library in the package's copyright file:
  BlendSwap-CC-0 (CC0), Scopia (CC-BY-3.0, Scopia Visual Interfaces Systems, s.l.),
  KatorLegaz (CC-BY-3.0-US, Andrew Kator & Jennifer Legaz).

:func:`fetch` downloads and unpacks both into a folder; :class:`Sources` reads
pictures from it as grey arrays.
"""

from __future__ import annotations

import struct
import subprocess
import sys
import zipfile
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

SKIMAGE_VERSION = "0.26.0"
GIMP_DATA_VERSION = "2.10.34-1+deb12u10"
SKIMAGE_WHERE = f"scikit-image {SKIMAGE_VERSION} wheel (PyPI), skimage/data/"
GIMP_WHERE = f"Debian gimp-data {GIMP_DATA_VERSION}, usr/share/gimp/2.0/patterns/"
SWEETHOME3D_VERSION = "1.8-1"
SWEETHOME3D_WHERE = (f"Debian sweethome3d-furniture {SWEETHOME3D_VERSION}, "
                     "usr/share/sweethome3d/furniture/")

GreyImage = npt.NDArray[np.uint8]


def fetch(folder: Path) -> Path:
    """Download scikit-image's wheel, gimp-data and sweethome3d-furniture, unpacked.

    Needs ``pip`` (this interpreter's), ``apt-get`` (after ``apt-get update``) and
    ``dpkg-deb``. Returns ``folder``.
    """
    folder.mkdir(parents=True, exist_ok=True)
    subprocess.run([sys.executable, "-m", "pip", "download", "--quiet", "--no-deps",
                    "--only-binary=:all:", f"scikit-image=={SKIMAGE_VERSION}", "-d",
                    str(folder)], check=True)
    (wheel,) = folder.glob(f"scikit_image-{SKIMAGE_VERSION}-*.whl")
    with zipfile.ZipFile(wheel) as z:
        z.extractall(folder / "skimage-wheel",
                     [n for n in z.namelist() if n.startswith("skimage/data/")])
    subprocess.run(["apt-get", "download", f"gimp-data={GIMP_DATA_VERSION}"], cwd=folder,
                   check=True)
    (deb,) = folder.glob("gimp-data_*.deb")
    subprocess.run(["dpkg-deb", "-x", str(deb), str(folder / "gimp-data")], check=True)
    subprocess.run(["apt-get", "download", f"sweethome3d-furniture={SWEETHOME3D_VERSION}"],
                   cwd=folder, check=True)
    (deb,) = folder.glob("sweethome3d-furniture_*.deb")
    subprocess.run(["dpkg-deb", "-x", str(deb), str(folder / "sweethome3d-furniture")],
                   check=True)
    return folder


@dataclass(frozen=True)
class Sources:
    """Pictures of the unpacked packages in ``folder`` (as :func:`fetch` left them)."""

    folder: Path

    def skimage(self, file: str) -> GreyImage:
        """scikit-image's ``skimage/data/<file>``, grey (colour converted by OpenCV)."""
        path = self.folder / "skimage-wheel" / "skimage" / "data" / file
        image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise FileNotFoundError(path)
        return image

    def gimp_pattern(self, file: str) -> GreyImage:
        """GIMP's pattern ``patterns/<file>`` (``Wood/wood1.pat``), grey.

        GIMP's pattern format: a big-endian header of uint32 header size, version,
        width, height, bytes per pixel, magic ``GPAT``, then the name; then the pixels,
        rows from the top, 1 (grey), 2 (grey, alpha), 3 (RGB) or 4 (RGBA) bytes each.
        """
        data = (self.folder / "gimp-data" / "usr/share/gimp/2.0/patterns" / file).read_bytes()
        header_size, _, w, h, depth = struct.unpack(">5I", data[:20])
        if data[20:24] != b"GPAT":
            raise ValueError(f"{file}: not a GIMP pattern")
        pixels = np.frombuffer(data[header_size:header_size + w * h * depth], np.uint8)
        pixels = pixels.reshape(h, w, depth)
        if depth <= 2:
            return np.ascontiguousarray(pixels[..., 0])
        return cv2.cvtColor(np.ascontiguousarray(pixels[..., :3]), cv2.COLOR_RGB2GRAY)

    def sweethome3d(self, library: str, member: str) -> GreyImage:
        """The picture ``member`` of Sweet Home 3D's furniture library ``library``.sh3f, grey.

        Args:
            library: ``"BlendSwap-CC-0"``, ``"Scopia"``, ``"KatorLegaz"``.
            member: the path inside the zip (``"blendswap-cc-0/table/Wood_013_COLOR.jpg"``).
        """
        path = (self.folder / "sweethome3d-furniture" / "usr/share/sweethome3d/furniture"
                / f"{library}.sh3f")
        with zipfile.ZipFile(path) as z:
            data = z.read(member)
        image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
        if image is None:
            raise ValueError(f"{path}: {member} does not decode")
        return image
