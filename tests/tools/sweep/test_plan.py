"""Plans: parsing, the cases they expand to, and every bad entry refused in one line before
any case runs (``vmnav sweep run``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tools.cli import main
from tools.sweep.plan import AXES, plan_from_data, read_plan

PLAN = """
[sweep]
routes = ["corridor", "office_loop"]
goal = 12

[axes]
world = ["lab", "worlds/mine.toml"]
seed = {first = 3, count = 2}
lighting = ["none", "scale=0.7"]
calibration = ["default", "cams/wide.json"]
law = ["paper+ff"]
speed_m_s = [0.2]
"""


def test_a_plan_expands_to_every_combination(tmp_path: Path) -> None:
    (tmp_path / "plan.toml").write_text(PLAN)
    plan = read_plan(tmp_path / "plan.toml")
    cases = plan.cases()
    assert len(cases) == 2 * 2 * 2 * 2
    first = cases[0]
    assert first.argv == ("--routes", "corridor,office_loop", "--goal", "12", "--world", "lab",
                          "--seed", "3", "--law", "paper+ff", "--speed", "0.2")
    assert dict(first.values)["lighting"] is None and list(dict(first.values)) == list(AXES)
    assert cases[1].argv[-4:] == ("--law", "paper+ff", "--speed", "0.2")
    assert "--lighting" in cases[2].argv and "--lighting" not in cases[1].argv
    # relative files are taken from the plan's folder; tasks get them as absolute paths
    assert str(tmp_path / "worlds" / "mine.toml") in cases[8].run_argv
    assert str(tmp_path / "cams" / "wide.json") in cases[1].run_argv
    assert str(tmp_path / "cams" / "wide.json") in cases[1].run_memory_argv
    # the same memory for the light levels, another for another camera or seed
    assert cases[0].memory_name == cases[2].memory_name != cases[1].memory_name
    assert len({c.memory_name for c in cases}) == 2 * 2 * 2
    assert cases[0].memory_name.startswith("lab-seed3-")
    assert len({c.case_id for c in cases}) == len(cases)
    assert read_plan(tmp_path / "plan.toml").cases() == cases  # ids are stable


def test_files_are_named_from_the_working_directory_so_ids_hold_in_any_clone(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    ids = []
    for clone in ("a", "b"):
        (tmp_path / clone / "plans" / "cams").mkdir(parents=True)
        (tmp_path / clone / "plans" / "plan.toml").write_text(PLAN)
        monkeypatch.chdir(tmp_path / clone)
        cases = read_plan(Path("plans/plan.toml")).cases()
        assert "plans/cams/wide.json" in cases[1].argv  # as a user types it from the root
        assert str(tmp_path / clone / "plans/cams/wide.json") in cases[1].run_argv
        ids.append([(c.case_id, c.memory_name) for c in cases])
    assert ids[0] == ids[1]
    monkeypatch.chdir(tmp_path / "b")  # a's files do not lie under it: absolute paths
    outside = read_plan(tmp_path / "a" / "plans" / "plan.toml").cases()
    assert str(tmp_path / "a" / "plans" / "cams" / "wide.json") in outside[1].argv


def test_the_shipped_plans_read_and_check(tmp_path: Path) -> None:
    from tools.sweep.plan_check import check_plan

    docs = Path(__file__).resolve().parents[3] / "docs" / "sweeps"
    counts = {}
    for path in sorted(docs.glob("*.toml")):
        plan = read_plan(path)
        check_plan(plan)
        counts[path.name] = len(plan.cases())
    assert counts == {"building-20.toml": 20, "building-campus-20.toml": 40,
                      "lab-campus-1000.toml": 1008,
                      "front-end-teblid.toml": 12, "lab-changes-20.toml": 20,
                      "lab-dim-relocalize.toml": 12,
                      "lab-light.toml": 18, "lab-other-lens.toml": 20,
                      "safety-people-20.toml": 80}


def test_the_plan_is_data_that_compares() -> None:
    plan = plan_from_data({"axes": {"seed": [1, 2], "moved": [0, 0.5]}}, Path("."))
    assert plan.to_dict()["axes"] == {"seed": [1, 2], "moved": [0.0, 0.5]}
    assert plan.to_dict() == plan_from_data({"axes": {"moved": [0.0, 0.5], "seed": [1, 2]}},
                                            Path(".")).to_dict()


#: (plan text, the error line's fragment).
BAD_PLANS = [
    ("[axes]\nwind = [1, 2]\n", "plan.toml: [axes] wind: unknown axis (known: world, seed,"),
    ("[axes]\nseed = []\n", "plan.toml: [axes] seed: is empty"),
    ("[axes]\nworld = ['moon']\n", "plan.toml: [axes] world = 'moon': moon: unknown world"),
    ("[axes]\nworld = ['nothere.toml']\n", "[axes] world = '"),
    ("[axes]\ncalibration = ['nocam.json']\n", "[axes] calibration = '"),
    ("[axes]\ncalibration = ['badcam.json']\n", "badcam.json"),
    ("[axes]\nlighting = ['scale=-1']\n",
     "[axes] lighting = 'scale=-1': --lighting: scale must be > 0, got -1.0"),
    ("[axes]\nlaw = ['pid']\n", "[axes] law = 'pid': argument --law: invalid choice: 'pid'"),
    ("[axes]\nspeed_m_s = [-0.2]\n", "[axes] speed_m_s = -0.2: argument --speed: must be"),
    ("[axes]\npeople = [1.5]\n", "[axes] people: 1.5 is not a integer"),
    ("[axes]\nseed = {first = 1}\n", "[axes] seed: a range is {first = N, count = M}"),
    ("[axes]\nlaw = ['paper', 'paper']\n", "[axes] law: gives a value twice"),
    ("[axes]\ndoors = ['nodoor=open']\n", "[axes] world = 'lab' with doors = 'nodoor=open'"),
    ("[sweep]\nroutes = ['nowhere']\n[axes]\nworld = ['lab']\n",
     "[axes] world = 'lab': --route: unknown route 'nowhere' in world 'lab'"),
    ("[sweep]\nrepeats = 3\n", "plan.toml: [sweep] repeats: unknown key"),
    ("[sweep]\ngoal = 'middle'\n", "plan.toml: [sweep] goal: wrong kind of value 'middle'"),
    ("[other]\nx = 1\n", "plan.toml: [other]: unknown table"),
    ("[axes\n", "plan.toml: not TOML"),
]


@pytest.mark.parametrize(("text", "fragment"), BAD_PLANS, ids=[t for t, _ in BAD_PLANS])
def test_a_bad_plan_is_one_line_before_any_case(text: str, fragment: str, tmp_path: Path,
                                                capsys: pytest.CaptureFixture[str]) -> None:
    (tmp_path / "plan.toml").write_text(text)
    (tmp_path / "badcam.json").write_text('{"format": "x"}')
    out = tmp_path / "sweep"
    code = main(["sweep", "run", str(tmp_path / "plan.toml"), "--out", str(out)])
    err = capsys.readouterr().err
    assert (code, err.count("\n")) == (1, 1), err
    assert "Traceback" not in err and fragment in err, err
    assert not out.exists()  # refused before any case ran (or anything was written)


def test_a_missing_plan_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sweep", "run", str(tmp_path / "none.toml")]) == 1
    assert "none.toml: cannot read: No such file or directory" in capsys.readouterr().err
