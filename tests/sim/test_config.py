"""The simulator's configs (sim/config.py): the ``[sim]`` table of a vmnav config file, its
loader, the robot's camera mount it is given, and the emulated Pioneer's table
(``[sim.emulator]``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from shared.config import AriaLinkConfig, CameraMountConfig, from_mapping
from shared.errors import ConfigError
from sim.config import EmulatorConfig, SimConfig, TeachDriverConfig, load_sim_config

MOUNT = CameraMountConfig(x_m=0.25, pitch_deg=-5.0)


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "vmnav.toml"
    path.write_text(text)
    return path


class TestLoadSimConfig:
    def test_none_gives_the_defaults_with_the_robots_mount(self) -> None:
        assert load_sim_config(None, MOUNT) == SimConfig(camera_mount=MOUNT)

    def test_values_and_nested_tables(self, tmp_path: Path) -> None:
        config = load_sim_config(write(
            tmp_path,
            '[sim]\nworld = "campus"\nseed = 7\n'
            "[sim.body]\nmax_speed_m_s = 0.5\n[sim.people]\ncount = 3\n"
            "[sim.teach_driver]\nspeed_m_s = 0.25\n",
        ), MOUNT)
        assert (config.world, config.seed) == ("campus", 7)
        assert config.body.max_speed_m_s == 0.5
        assert config.body.accel_m_s2 == SimConfig().body.accel_m_s2
        assert config.people.count == 3
        assert config.teach_driver == TeachDriverConfig(speed_m_s=0.25)
        assert config.camera_mount == MOUNT

    def test_the_robots_tables_are_left_to_the_robot(self, tmp_path: Path) -> None:
        path = write(tmp_path, '[control]\nlaw = "paper+ff"\n[camera.mount]\npitch_deg = 3\n'
                               "[sim]\nseed = 2\n")
        assert load_sim_config(path, MOUNT) == SimConfig(seed=2, camera_mount=MOUNT)

    def test_int_accepted_for_float(self, tmp_path: Path) -> None:
        path = write(tmp_path, "[sim.sensor]\nread_noise_grey = 3\n")
        assert load_sim_config(path, MOUNT).sensor.read_noise_grey == 3.0

    @pytest.mark.parametrize(
        ("text", "fragment"),
        [
            ('[sim]\nseed = "one"\n', "sim.seed: expected an integer, got str 'one'"),
            ("[sim]\nsed = 1\n", "sim: unknown key 'sed'"),
            ("[sim.body]\nmax_speed_m_s = -1\n", "sim.body: max_speed_m_s must be > 0, got -1.0"),
            ("[sim.sensor]\nread_noise_grey = nan\n",
             "sim.sensor.read_noise_grey: expected a finite number"),
            ("[sim.sensor]\nexposure_time_constant_s = inf\n",
             "sim.sensor.exposure_time_constant_s: expected a finite number"),
            ("[sim.render]\nnoise_sigma = 2\n",
             "sim.render.noise_sigma: the sensor's noise moved to [sim.sensor] read_noise_grey"),
            ("[sim.sensor]\nvignetting_rim = 0\n",
             "sim.sensor: vignetting_rim must be in (0, 1], got 0.0"),
            ("[sim.sensor]\nread_noise_grey = -1\n",
             "sim.sensor: read_noise_grey must be >= 0, got -1.0"),
            ("[sim.sensor]\ntarget_grey = 300\n",
             "sim.sensor: target_grey must be in (0, 255) grey levels, got 300.0"),
            ("[sim.sensor]\nmin_exposure_s = 0.01\nmax_exposure_s = 0.005\n",
             "sim.sensor: max_exposure_s must be >= min_exposure_s (0.01 s), got 0.005"),
            ("[sim.sensor]\ngain = 0.5\n", "sim.sensor: gain must be in [1, max_gain = 8.0]"),
            ("[sim.sensor]\njpeg_quality = 0\n",
             "sim.sensor: jpeg_quality must be in 1..100, got 0"),
            ("[sim.sensor]\nmotion_blur = 1\n",
             "sim.sensor.motion_blur: expected true or false"),
            ("[sim.sensor]\nmax_exposure_s = 0.1\n",
             "sim: sensor.max_exposure_s (0.1 s) must be <= the frame period (0.066666667 s)"),
            ("[sim]\nbody = 3\n", "sim.body: expected a table"),
            ("sim = 3\n", "sim: expected a table"),
            ("[sim.people]\ncount = true\n", "sim.people.count: expected an integer"),
            ("[sim]\nframe_period_ns = 1000\n", "frame_period_ns (1000) must be >= physics_dt_ns"),
            ("[sim.camera_mount]\npitch_deg = 3\n", "sim: unknown key 'camera_mount'"),
            ("[sim.teach_driver]\nwander_wavelength_m = [3, 1]\n",
             "sim.teach_driver: wander_wavelength_m must be (low, high) with 0 < low <= high"),
            ("[sim\n", "not valid TOML"),
        ],
    )
    def test_bad_input_names_file_key_and_problem(
        self, tmp_path: Path, text: str, fragment: str
    ) -> None:
        path = write(tmp_path, text)
        with pytest.raises(ConfigError) as err:
            load_sim_config(path, MOUNT)
        message = str(err.value)
        assert message.startswith(str(path))
        assert fragment in message
        assert "\n" not in message

    def test_missing_file(self, tmp_path: Path) -> None:
        with pytest.raises(ConfigError, match="file not found"):
            load_sim_config(tmp_path / "nope.toml", MOUNT)


def test_emulator_defaults_are_an_arcos_robot() -> None:
    config = SimConfig().emulator
    assert config == EmulatorConfig()
    assert config.watchdog_stops and config.link == AriaLinkConfig()
    assert config.sonar_max_range_m == 5.0 and config.battery_full_v == 13.0


def test_emulator_table_loads_with_its_link() -> None:
    config = from_mapping(SimConfig, {"emulator": {
        "name": "bench", "watchdog_stops": False, "link": {"watchdog_timeout_ns": 1_000_000_000},
    }}, "vmnav.toml", "sim")
    emulator = config.emulator
    assert (emulator.name, emulator.watchdog_stops) == ("bench", False)
    assert emulator.link.watchdog_timeout_ns == 1_000_000_000


@pytest.mark.parametrize(
    ("table", "fragment"),
    [
        ({"name": ""}, "sim.emulator: name must be 1-20 printable ASCII"),
        ({"name": "caf\u00e9"}, "name must be 1-20 printable ASCII"),
        ({"battery_empty_v": 14.0}, "battery_empty_v must be in (0, battery_full_v]"),
        ({"battery_full_v": 30.0, "battery_empty_v": 11.0}, "battery_full_v must be < 25.5"),
        ({"sonar_noise_m": -0.1}, "sonar_noise_m must be >= 0"),
        ({"sonar_max_range_m": 70.0}, "sonar_max_range_m must be in (0, 65]"),
        ({"sonar_cycle_ns": 0}, "sonar_cycle_ns must be > 0"),
        ({"sonar_beam_width_deg": 120.0}, "sonar_beam_width_deg must be in [0, 90]"),
        ({"sonar_beam_width_deg": float("nan")}, "sonar_beam_width_deg: expected a finite"),
        ({"sonar_rays": 0}, "sonar_rays must be in [1, 31]"),
        ({"sonar_min_range_m": 5.0}, "sonar_min_range_m must be in [0, sonar_max_range_m)"),
        ({"sonar_min_range_m": -0.1}, "sonar_min_range_m must be in [0, sonar_max_range_m)"),
        ({"sonar_critical_angle_deg": 0.0}, "sonar_critical_angle_deg must be in (0, 90]"),
    ],
)
def test_emulator_bad_values_name_the_key(table: dict, fragment: str) -> None:
    with pytest.raises(ConfigError, match=r"vmnav\.toml") as info:
        from_mapping(SimConfig, {"emulator": table}, "vmnav.toml", "sim")
    assert fragment in str(info.value)
