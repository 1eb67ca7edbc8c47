"""``vmnav sweep report`` on a results table: rates with Wilson intervals per axis value,
km per intervention, plots, the worst cases with their rerun commands."""

from __future__ import annotations

from pathlib import Path

import cv2
import pytest

from tools.cli import main
from tools.sweep.results import ResultsTable

PLAN = {"axes": {"seed": [1, 2, 3, 4, 5], "law": ["paper", "paper+ff"]}, "routes": None,
        "goal": None, "config": None, "max_omega_deg": None}


def results(folder: Path) -> None:
    """10 cases: paper+ff reaches 5 of 5, paper 2 of 5; one more crashed."""
    table = ResultsTable(folder, PLAN, "vmnav 0.1.0 tree abc")
    for seed in range(1, 6):
        for law in ("paper", "paper+ff"):
            reached = law == "paper+ff" or seed <= 2
            table.append({"case_id": f"{law}-{seed}", "status": "ok", "seed": seed, "law": law,
                          "reached_goal": reached, "reason": "arrived" if reached else "lost",
                          "distance_m": 100.0, "lateral_rms_m": 0.01 * seed,
                          "lateral_max_m": 0.03 * seed + (0.5 if not reached else 0.0),
                          "lost_events": 0 if reached else 3,
                          "options": f"--seed {seed} --law {law}"})
    table.append({"case_id": "boom", "status": "crashed", "seed": 6, "law": "paper",
                  "error": "Traceback (most recent call last):\nRuntimeError: it broke\n",
                  "options": "--seed 6 --law paper"})


def test_the_report_says_rates_intervals_and_reruns(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    results(tmp_path / "s")
    assert main(["sweep", "report", str(tmp_path / "s" / "results.csv")]) == 0
    assert "wrote" in capsys.readouterr().out
    report = (tmp_path / "s" / "report" / "report.md").read_text()
    assert "11 of 10 cases ran (10 completed, 1 crashed)" in report
    # 7 of 10 reached: Wilson [39.7, 89.2] %; 1 km driven, 3 failures: 0.333 km each,
    # Garwood's limits 0.619 and 8.77 failures per km
    assert "| all | 10 | 7 | 70.0 % [39.7, 89.2] | 1.000 | 0.333 [0.114, 1.62] |" in report
    assert "| paper | 5 | 2 | 40.0 % [11.8, 76.9] |" in report
    assert "| paper+ff | 5 | 5 | 100.0 % [56.6, 100.0] | 0.500 | ∞ [0.136, ∞] |" in report
    worst = report.split("## Worst cases")[1]
    assert worst.index("`paper-5`") < worst.index("`paper-4`") < worst.index("`paper+ff-5`")
    assert ("`vmnav demo --seed 5 --law paper --out out/rerun/paper-5`" in worst)
    assert "* `boom`: RuntimeError: it broke" in report
    for name in ("success_seed.png", "success_law.png", "lateral_law.png"):
        image = cv2.imread(str(tmp_path / "s" / "report" / name))
        assert image is not None and image.shape[0] > 100


def test_a_folder_without_results_is_one_line(tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sweep", "report", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is not a sweep's folder (no sweep.json)" in err


def test_the_report_says_contacts_waits_and_what_people_cost(tmp_path: Path) -> None:
    """Seeds 1-3 with and without people; one old row without the safety figures, which
    did not reach its goal."""
    plan = {"axes": {"seed": [1, 2, 3], "people": [0, 5]}, "routes": None, "goal": None,
            "config": None, "max_omega_deg": None}
    table = ResultsTable(tmp_path / "s", plan, "vmnav 0.1.0 tree abc")
    for seed in (1, 2, 3):
        for people in (0, 5):
            judged = {} if (seed, people) == (3, 5) else {
                "contacts_moving": int(people > 0 and seed == 2), "contacts_still": people // 5,
                "obstacle_waits": 2 if people else 0, "blind_max_m": 0.1}
            cut_short = (seed, people) == (3, 5)  # its RMS is its start's: not compared
            rms = 0.05 if cut_short else 0.01 + 0.002 * seed * (people > 0)
            table.append({"case_id": f"{seed}-{people}", "status": "ok", "seed": seed,
                          "people": people, "reached_goal": not cut_short,
                          "reason": "bumper" if cut_short else "arrived", "distance_m": 50.0,
                          "lateral_rms_m": rms,
                          "lateral_max_m": 0.05, "lost_events": 0,
                          "options": f"--seed {seed} --people {people}", **judged})
    assert main(["sweep", "report", str(tmp_path / "s")]) == 0
    report = (tmp_path / "s" / "report" / "report.md").read_text()
    assert "contacts: robot moving / person walking in | obstacle waits |" in report
    assert "| all | 6 | 5 |" in report and "1 / 2 | 4 (5 of 6 runs judged) |" in report
    assert "| 0 | 3 | 3 |" in report and "0 / 0 | 0 |" in report
    # with minus without, seeds 1 and 2: 0.2 and 0.4 cm
    assert ("Lateral RMS with people minus the same case without (both reached): median "
            "0.3 cm, largest 0.4 cm (2 pairs).") in report
