"""``vmnav calibrate --from-equidistant YAML``: import an equidistant calibration.

Reads a Kannala-Brandt (``cv2.fisheye``) calibration (:mod:`shared.kannala_brandt_yaml`),
fits the unified model to it over the image (:func:`shared.kannala_brandt.fit_unified`),
prints the fit and its residual and writes the calibration JSON (:mod:`shared.calibration`).
Registered by :mod:`tools.calibrate`, whose option it is.
"""

from __future__ import annotations

from pathlib import Path


def import_equidistant(yaml_path: Path, output: Path, writer: str) -> int:
    """Fit, print the report, write ``output``; returns the exit code.

    Args:
        yaml_path: the equidistant calibration (:mod:`shared.kannala_brandt_yaml`).
        output: the vmnav calibration JSON to write (the caller checked it may be replaced).
        writer: what the file's ``source`` starts with.
    """
    from shared.calibration import write_camera
    from shared.kannala_brandt import fit_unified
    from shared.kannala_brandt_yaml import read_equidistant_yaml

    kb = read_equidistant_yaml(yaml_path).camera
    fit = fit_unified(kb, str(yaml_path))
    camera = fit.camera
    print(f"{yaml_path}: equidistant camera {kb.width}x{kb.height}, fx {kb.fx:g} fy {kb.fy:g} "
          f"cx {kb.cx:g} cy {kb.cy:g}, k " + " ".join(f"{k:.6g}" for k in kb.k))
    terms = "xi and k1, k2" if fit.with_distortion else "xi, no distortion"
    print(f"unified model fitted ({terms}) on {fit.samples} pixels: residual RMS "
          f"{fit.rms_px:.3f} px, max {fit.max_px:.3f} px")
    print(f"  K: fx {camera.K[0, 0]:.3f}  fy {camera.K[1, 1]:.3f}  cx {camera.K[0, 2]:.3f}  "
          f"cy {camera.K[1, 2]:.3f}  (px)")
    print(f"  xi: {camera.xi:.6f}  D: " + " ".join(f"{d:.6g}" for d in camera.D)
          + f"  fov: {camera.fov_deg:g} deg (the image's corners)")
    source = (f"{writer} --from-equidistant {yaml_path}: residual RMS {fit.rms_px:.3f} px, "
              f"max {fit.max_px:.3f} px")
    write_camera(output, camera, rms_px=fit.rms_px, source=source)
    print(f"wrote {output}")
    return 0
