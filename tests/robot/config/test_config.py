"""The robot's config (robot/config/__init__.py): the robot's tables of a vmnav config
file, the tables that moved out, and configs stored by field logs in either layout."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import pytest

from robot.config import (
    CameraSourceConfig,
    ControlConfig,
    PathStateConfig,
    RelativePoseConfig,
    VmnavConfig,
    config_from_log,
    load_config,
)
from robot.vision.features import PixelSizes
from shared.camera_model import CameraModel
from shared.config import CameraMountConfig
from shared.errors import ConfigError

FIXTURES = Path(__file__).parents[2] / "fixtures"


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "vmnav.toml"
    path.write_text(text)
    return path


def old_layout() -> dict[str, Any]:
    """The demo's config (the defaults, law "paper+ff", turn rates up to 25 deg/s) as a
    field log stored it before the simulator's tables left the robot's config (written by
    that code: ``dataclasses.asdict``)."""
    return json.loads((FIXTURES / "logged_config_old_layout.json").read_text())


class TestLoadConfig:
    def test_none_gives_defaults(self) -> None:
        assert load_config(None) == VmnavConfig()

    def test_values_and_nested_tables(self, tmp_path: Path) -> None:
        config = load_config(write(tmp_path, '[control]\nlaw = "paper+ff"\nspeed_m_s = 0.25\n'
                                             "[camera]\nsource = \"1\"\n"
                                             "[camera.mount]\npitch_deg = -5\n"))
        assert config.control == ControlConfig(law="paper+ff", speed_m_s=0.25)
        assert config.camera == CameraSourceConfig(source="1",
                                                   mount=CameraMountConfig(pitch_deg=-5.0))

    def test_the_simulators_table_is_left_to_the_simulator(self, tmp_path: Path) -> None:
        path = write(tmp_path, '[sim]\nworld = "campus"\nnot_checked_here = 1\n'
                               "[sim.body]\nmax_speed_m_s = 0.5\n")
        assert load_config(path) == VmnavConfig()

    @pytest.mark.parametrize(
        ("text", "fragment"),
        [
            ('[mission]\nbase_lost_action = "stop"\n',
             "mission: base_lost_action must be one of hold, continue, got 'stop'"),
            ("[pioneer]\nreport_timeout_ns = 0\n", "pioneer: report_timeout_ns must be > 0, got 0"),
            ("[controll]\nspeed_m_s = 0.3\n", "unknown key 'controll'"),
            ("[control]\nspeed = 0.3\n", "control: unknown key 'speed'"),
            ("[camera.mount]\npitch_deg = 91\n", "camera.mount: pitch_deg must be within ±90"),
            ("[sim.camera]\npitch_deg = -5\n",
             "sim.camera: moved to [camera.mount] (the camera mount is the robot's"),
            ("[teach_driver]\nspeed_m_s = 0.2\n",
             "teach_driver: moved to [sim.teach_driver] (the scripted teach driver is the "
             "simulator's)"),
            ("[localize]\nmin_matches = 25\n",
             "localize.min_matches: no longer exists, replaced by localize.min_inliers and "
             "localize.min_inlier_ratio (a key image is accepted on the inliers of a relative "
             "pose, never on a match count)"),
            ("[control\n", "not valid TOML"),
        ],
    )
    def test_bad_input_names_file_key_and_problem(
        self, tmp_path: Path, text: str, fragment: str
    ) -> None:
        path = write(tmp_path, text)
        with pytest.raises(ConfigError) as err:
            load_config(path)
        message = str(err.value)
        assert message.startswith(str(path))
        assert fragment in message
        assert "\n" not in message

    def test_missing_file(self, tmp_path: Path) -> None:
        with pytest.raises(ConfigError, match="file not found"):
            load_config(tmp_path / "nope.toml")


class TestConfigFromLog:
    def test_todays_layout_round_trips(self) -> None:
        config = dataclasses.replace(VmnavConfig(), camera=CameraSourceConfig(
            source="http://cam/stream.mjpg", mount=CameraMountConfig(pitch_deg=-5.0)))
        assert config_from_log(dataclasses.asdict(config), "log.mcap", "config") == config

    def test_the_old_layout_reads_as_it_ran(self) -> None:
        # The three-view state's tolerances it ran with (0.02 and 0.012 rad), since tightened.
        expected = VmnavConfig(
            control=ControlConfig(law="paper+ff", max_omega_rad_s=math.radians(25.0)),
            path_state=PathStateConfig(
                point_threshold_rad=0.02,
                pose_before_resection=RelativePoseConfig(refine_passes=1)))
        # Its pixel windows become the angles they were on the default lens: today's defaults.
        assert config_from_log(old_layout(), "log.mcap", "config") == expected
        sizes = PixelSizes.for_camera(expected.features, CameraModel.default())
        assert (sizes.patch_px, sizes.min_distance_px) == (11, pytest.approx(8.0))

    def test_a_pixel_window_in_a_file_names_its_angle(self, tmp_path: Path) -> None:
        for text, old, new in (
            ("[features]\npatch_size_px = 11\n", "features.patch_size_px",
             "features.patch_size_deg"),
            ("[teach.tracking]\nsearch_radius_px = 20.0\n", "teach.tracking.search_radius_px",
             "teach.tracking.search_radius_deg"),
        ):
            with pytest.raises(ConfigError, match=rf"vmnav.toml: {old}: renamed to {new} "
                                                  r"\(vision windows are angles"):
                load_config(write(tmp_path, text))

    def test_the_old_mount_becomes_the_cameras(self) -> None:
        data = old_layout()
        data["sim"]["camera"] = {**data["sim"]["camera"], "pitch_deg": -7.5, "x_m": 0.3}
        config = config_from_log(data, "log.mcap", "config")
        assert config.camera.mount == CameraMountConfig(x_m=0.3, pitch_deg=-7.5)
        assert config.camera.source == data["camera"]["source"]

    def test_a_replaced_key_is_dropped(self) -> None:
        data = dataclasses.asdict(VmnavConfig())
        data["localize"] = {**data["localize"], "min_matches": 25}
        assert config_from_log(data, "log.mcap", "config") == VmnavConfig()

    def test_a_key_unknown_in_both_layouts_is_refused(self) -> None:
        data = {**old_layout(), "warp_drive": {}}
        with pytest.raises(ConfigError, match=r"log\.mcap: config: unknown key 'warp_drive'"):
            config_from_log(data, "log.mcap", "config")
