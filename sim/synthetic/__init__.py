"""Synthetic vision inputs with a known answer, for tests and benchmarks.

* ``image_pairs``: textured image pairs related by a known homography (features, matching);
* ``corridor_scene``: corridor scenes with known poses (geometry, state estimate).

They use only shared/ (the camera model and mount), like the rest of the simulator.
"""
