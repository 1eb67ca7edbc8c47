"""The sweep's folder: rows appended and read back, a cut last line dropped, other plans'
and other files' folders refused."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import pytest

from shared.errors import InputError
from tools.sweep.results import (
    COLUMNS,
    PLAN_NAME,
    SAFETY_FIGURES,
    ResultsTable,
    code_version,
    read_rows,
)

PLAN = {"axes": {"seed": [1, 2]}, "routes": None, "goal": None, "config": None,
        "max_omega_deg": None}


def row(case_id: str, **values: object) -> dict[str, object]:
    return {"case_id": case_id, "status": "ok", "seed": 1, "lighting": None,
            "reached_goal": True, "lateral_rms_m": 0.012, "reason": "arrived",
            "scene_change": {"light_scale": 0.7, "doors": {}}, "options": "--seed 1", **values}


def test_rows_come_back_as_written(tmp_path: Path) -> None:
    table = ResultsTable(tmp_path / "s", PLAN, "v1")
    table.append(row("a"))
    table.append(row("b", status="crashed", error="Traceback ...\nValueError: x, \"y\"\n",
                     reached_goal=None))
    again = ResultsTable(tmp_path / "s", PLAN, "v2")
    assert again.done == {"a", "b"}
    first, second = again.rows
    assert first == {**dict.fromkeys(COLUMNS), **row("a")}
    assert second["error"] == "Traceback ...\nValueError: x, \"y\"\n"
    assert second["reached_goal"] is None and first["scene_change"]["light_scale"] == 0.7
    assert json.loads((tmp_path / "s" / PLAN_NAME).read_text())["code_version"] == "v1"
    with pytest.raises(ValueError, match="unknown columns"):
        again.append({"case_id": "c", "colour": "red"})


def test_a_line_cut_short_is_dropped_and_its_case_runs_again(tmp_path: Path) -> None:
    table = ResultsTable(tmp_path, PLAN, "v1")
    table.append(row("a"))
    table.append(row("b"))
    text = table.path.read_text()
    table.path.write_text(text[: len(text) - 40])  # killed while writing b's line
    again = ResultsTable(tmp_path, PLAN, "v1")
    assert again.done == {"a"}
    again.append(row("c"))
    assert [r["case_id"] for r in read_rows(table.path)] == ["a", "c"]


def test_a_table_written_before_the_safety_figures_reads_and_resumes(tmp_path: Path) -> None:
    table = ResultsTable(tmp_path, PLAN, "v1")
    table.append(row("a"))
    # the table as a sweep before the safety figures wrote it: the same columns without
    # the last ones
    old = len(COLUMNS) - len(SAFETY_FIGURES)
    cells = list(csv.reader(io.StringIO(table.path.read_text(), newline="")))
    with table.path.open("w", newline="") as f:
        csv.writer(f).writerows(line[:old] for line in cells)
    (old_row,) = read_rows(table.path)
    assert old_row["case_id"] == "a" and old_row["lateral_rms_m"] == 0.012
    assert all(old_row[k] is None for k in SAFETY_FIGURES)
    again = ResultsTable(tmp_path, PLAN, "v2")  # resumed: rewritten with the new columns
    again.append(row("b", contacts_moving=0, contacts_still=1, obstacle_waits=2,
                     blind_max_m=0.3))
    first, second = read_rows(table.path)
    assert first["contacts_moving"] is None and second["contacts_still"] == 1
    assert table.path.read_text().splitlines()[0] == ",".join(COLUMNS)
    with table.path.open("w", newline="") as f:  # some other subset is not a results table
        csv.writer(f).writerows(line[:old - 1] for line in cells)
    with pytest.raises(InputError, match="its header differs"):
        read_rows(table.path)


def test_another_plan_or_a_foreign_folder_is_refused(tmp_path: Path) -> None:
    ResultsTable(tmp_path / "s", PLAN, "v1")
    with pytest.raises(InputError, match="holds the results of another plan"):
        ResultsTable(tmp_path / "s", {**PLAN, "goal": 3}, "v1")
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("x")
    with pytest.raises(InputError, match="holds files of no sweep"):
        ResultsTable(tmp_path / "mine", PLAN, "v1")
    (tmp_path / "bad.csv").write_text("a,b\n1,2\n")
    with pytest.raises(InputError, match="is not a sweep's results table"):
        read_rows(tmp_path / "bad.csv")


def test_the_code_version_names_the_package_and_the_tree() -> None:
    version = code_version()
    assert version.startswith("vmnav ") and " tree " in version
    assert version == code_version()
