"""The cost figures of the simulated camera's flaws and people (tools/bench/camera_effects.py)."""

from __future__ import annotations

from shared.camera_model import CameraModel
from sim.config import SimConfig
from tools.bench.camera_effects import PEOPLE, bench_camera_effects


def test_times_the_sensor_and_the_people_in_view_along_a_route() -> None:
    result = bench_camera_effects(SimConfig(), CameraModel.default(), frames=6, warmup=2)
    assert result["people"] == PEOPLE
    assert result["people_in_view_frames"] == 6  # they come the other way along the route
    assert result["sensor_ms_median"] > 0 and result["people_ms_median"] > 0
    assert result["sensor_ms_p90"] >= result["sensor_ms_median"]
    assert result["sensor_blur_px_max"] > 0.4  # the robot drives: the floor blurs
    assert 0.1 < result["sensor_exposure_ms_median"] <= 30.0
