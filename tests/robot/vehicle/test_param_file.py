"""Parameter file: atomic JSON of the values that differ from their defaults."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from robot.vehicle.param_file import load_param_file, save_param_file
from shared.errors import ConfigError, InputError
from tests.shared.mavlink.test_params import make_table


def test_round_trip_stores_only_changed_values(tmp_path: Path) -> None:
    path = tmp_path / "params.json"
    table = make_table()
    table.set("CTL_SPEED", 0.30000001192092896)  # a float32 value, as set over the wire
    table.set("FS_GCS_ACTION", 1)
    save_param_file(path, table)
    stored = json.loads(path.read_text())
    assert stored == {"format": "vmnav-params", "format_version": 1,
                      "params": {"CTL_SPEED": 0.30000001192092896, "FS_GCS_ACTION": 1.0}}
    fresh = make_table()
    assert load_param_file(path, fresh)
    assert fresh.values() == table.values()


def test_missing_file_keeps_the_defaults(tmp_path: Path) -> None:
    table = make_table()
    assert not load_param_file(tmp_path / "none.json", table)
    assert table.values() == make_table().values()


@pytest.mark.parametrize(("text", "problem"), [
    ('{"format": "vmnav-params", "format_version": 1, "params": {"CTL_SP',
     "not valid JSON (truncated?)"),
    ('{"format": "vmnav-params", "format_version": 1, "params": {"CTL_SPEED": NaN}}',
     "not valid JSON: NaN is not a JSON number"),
    ('[1, 2]', "not a parameter file"),
    ('{"format": "vmnav-params", "format_version": 2, "params": {}}',
     "format_version 2 is not supported"),
    ('{"format": "vmnav-params", "format_version": 1, "params": []}', "params: expected an object"),
    ('{"format": "vmnav-params", "format_version": 1, "params": {"CTL_SPEED": "fast"}}',
     "params.CTL_SPEED: expected a number, got 'fast'"),
    ('{"format": "vmnav-params", "format_version": 1, "params": {"MIS_LOC_TRIES": 3, "GONE": 1}}',
     "params.GONE: no such parameter"),
    ('{"format": "vmnav-params", "format_version": 1, "params": {"MIS_LOC_TRIES": 0}}',
     "params.MIS_LOC_TRIES: 0 is outside [1, 100]"),
])
def test_bad_file_is_refused_naming_it_and_nothing_changes(tmp_path: Path, text: str,
                                                           problem: str) -> None:
    path = tmp_path / "params.json"
    path.write_text(text)
    table = make_table()
    with pytest.raises(ConfigError, match=re.escape(problem)) as error:
        load_param_file(path, table)
    assert str(error.value).startswith(f"{path}: ")
    assert "\n" not in str(error.value)
    assert table.values() == make_table().values()
    assert path.read_text() == text  # the stored file is never lost


def test_save_into_a_missing_folder_names_the_path(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="cannot write"):
        save_param_file(tmp_path / "no" / "params.json", make_table())
