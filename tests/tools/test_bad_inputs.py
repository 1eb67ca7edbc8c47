"""Bad input at the command line, table-driven: options, config values, files and addresses
each give one line on stderr naming what is wrong, never a traceback (issue 19: at least
60 of them). Usage errors exit with 2 (argparse's), every other refusal with 1."""

from __future__ import annotations

from pathlib import Path

import pytest

from tools.cli import main

#: Files the cases name, created in the test's folder: name -> text.
FILES = {
    "bad.toml": "not toml [",
    "badlaw.toml": '[control]\nlaw = "pid"\n',
    "badspeed.toml": "[control]\nspeed_m_s = -1\n",
    "badseed.toml": "[sim]\nseed = -4\n",
    "unknown.toml": "[nosuch]\nx = 1\n",
    "badretain.toml": "[log]\nretain_max_age_days = -1\n",
    "badomega.toml": "[control]\nmax_omega_rad_s = nan\n",
    "badsafety.toml": "[safety]\nstop_distance_m = -0.4\n",
    "badcam.json": '{"format": "x"}',
    "notjson.json": "{",
    "notimg.png": "xx",
    "empty.mcap": "",
    "foxnet.toml": '[foxglove]\naddress = "192.0.2.1:8765"\n',
    "badfox.toml": "[foxglove]\njpeg_quality = 0\n",
    "plan.toml": "[axes]\nseed = [1]\n",
    "windplan.toml": "[axes]\nwind = [1]\n",
}
SNAP = ["sim", "snapshot", "--out", "o"]
SERVE = ["sim", "serve", "--aria", "tcp:0", "--duration", "0.1"]
NO_VEHICLE = ["ground", "--timeout", "0.2", "--connect", "udpin:127.0.0.1:0"]
CAL = ["--pattern", "9x6", "--square", "0.025", "-o", "c.json"]

#: (arguments, exit code, the line's expected fragment).
CASES: list[tuple[list[str], int, str]] = [
    # numbers and choices (argparse)
    ([*SNAP, "--seed", "-1"], 2, "argument --seed: must be an integer >= 0, got '-1'"),
    ([*SNAP, "--people", "-3"], 2, "argument --people: must be an integer >= 0, got '-3'"),
    ([*SNAP, "--x", "nan", "--y", "1"], 2, "argument --x: must be a finite number, got 'nan'"),
    ([*SNAP, "--x", "1", "--y", "1", "--yaw", "inf"], 2, "argument --yaw: must be a finite"),
    (["demo", "--goal", "-5"], 2, "argument --goal: must be an integer in [0, 2147483647]"),
    (["demo", "--max-omega-deg", "0"], 2, "argument --max-omega-deg: must be a finite number > 0"),
    (["demo", "--law", "pid"], 2, "argument --law: invalid choice: 'pid'"),
    (["demo", "--speed", "0"], 2, "argument --speed: must be a finite number > 0"),
    (["demo", "--start-offset", "nan"], 2, "argument --start-offset: must be a finite number"),
    (["bench", "sim", "--frames", "0"], 2, "argument --frames: must be an integer >= 1"),
    (["memory", "route", "--memory", "m", "1", "-2"], 2, "argument GOAL: must be an integer"),
    (["ground", "--system", "300", "status"], 2, "argument --system: must be an integer in"),
    (["ground", "--timeout", "0", "status"], 2, "argument --timeout: must be a finite number"),
    (["robot", "--memory", "m", "--system", "0"], 2, "argument --system: must be an integer"),
    (["pioneer", "--duration", "0"], 2, "argument --duration: must be a finite number > 0"),
    ([*SERVE, "--start", "1,2"], 2, "argument --start: '1,2' is not X,Y,YAW"),
    (["calibrate", "--capture", "x.avi", "--views", "v", *CAL, "--coverage", "2"], 2,
     "argument --coverage: must be a finite number > 0 and <= 1"),
    (["vision", "pair", "notimg.png", "notimg.png"], 2, "required: --calibration"),
    (["nosuchcommand"], 2, "argument COMMAND: invalid choice: 'nosuchcommand'"),
    (["robot"], 2, "the following arguments are required: --memory"),
    # values out of range or not making sense
    ([*SNAP, "--x", "1e9", "--y", "10"], 1, "--x/--y/--yaw: (1000000000.0, 10.0, 0.0 deg) is "
     "outside world 'lab' (x 0 to 30 m, y 0 to 20 m)"),
    ([*SNAP, "--x", "0", "--y", "10"], 1, "--x/--y/--yaw: (0.0, 10.0, 0.0 deg) overlaps a wall"),
    ([*SNAP, "--x", "1"], 1, "--x/--y: give both --x and --y to place the robot"),
    ([*SNAP, "--lighting", "scale=-1"], 1, "--lighting: scale must be > 0, got -1.0"),
    ([*SNAP, "--lighting", "hour=30"], 1, "--lighting: hour must be in [0, 24], got 30.0"),
    ([*SNAP, "--lighting", "dusk"], 1, "--lighting"),
    ([*SNAP, "--moved", "2"], 1, "--moved: moved fraction must be in [0, 1], got 2.0"),
    ([*SNAP, "--doors", "nosuch=open"], 1, "world 'lab' has no door named 'nosuch'"),
    ([*SERVE, "--start", "1e9,0,0"], 1, "--start: (1000000000.0, 0.0, 0.0 deg) is outside"),
    ([*SERVE, "--start", "0,0,0"], 1, "--start: (0.0, 0.0, 0.0 deg) overlaps a wall"),
    ([*SERVE, "--route-start", "attic"], 1, "--route-start: world 'lab' has no route 'attic'"),
    (["sim", "serve", "--duration", "0"], 1, "--duration: must be > 0 seconds, got 0.0"),
    (["sim", "serve", "--video", "http:0", "--jpeg-quality", "101"], 1,
     "--jpeg-quality: must be 1-100, got 101"),
    (["demo", "--routes", ","], 1, "--routes: names no route"),
    (["calibrate", ".", "--pattern", "9", "--square", "0.025", "-o", "c.json"], 1,
     "--pattern: expected inner corners as COLSxROWS like 9x6, got '9'"),
    (["calibrate", ".", "--pattern", "9x6", "--square", "-1", "-o", "c.json"], 1,
     "--square: must be > 0 m, got -1"),
    (["calibrate", ".", *CAL, "--fov", "400"], 1, "--fov: must be in (0, 360) degrees, got 400"),
    (["calibrate", *CAL], 1, "give a folder of board images, --capture SOURCE or "
     "--from-equidistant YAML"),
    (["calibrate", "--capture", "x.avi", *CAL], 1, "--views: --capture needs a new folder"),
    (["calibrate", "--capture", "x.avi", "--views", "v", *CAL, "--min-views", "2"], 1,
     "at least 3 views are needed, got 2"),
    (["bench", "follow", "--seeds", "0"], 1, "--seeds: must be >= 1, got 0"),
    (["bench", "follow", "--laws", "pid"], 1, "--laws: unknown law 'pid' (known: paper, paper+ff)"),
    (["bench", "all", "--only", "nothing"], 1, "--only: unknown benchmark nothing"),
    # config files and values
    ([*SNAP, "--config", "bad.toml"], 1, "bad.toml: not valid TOML"),
    ([*SNAP, "--config", "badseed.toml"], 1, "badseed.toml: sim: seed must be >= 0, got -4"),
    ([*SNAP, "--config", "unknown.toml"], 1, "unknown.toml: unknown key 'nosuch'"),
    ([*SNAP, "--config", "nothere.toml"], 1, "nothere.toml"),
    (["demo", "--config", "badlaw.toml"], 1, "badlaw.toml: control: law must be one of paper"),
    (["demo", "--config", "badspeed.toml"], 1, "badspeed.toml: control: speed_m_s must be > 0"),
    (["demo", "--config", "badomega.toml"], 1, "badomega.toml"),
    (["demo", "--config", "badsafety.toml"], 1, "badsafety.toml: safety: stop_distance_m"),
    (["demo", "--config", "badretain.toml"], 1, "badretain.toml: log: retain_max_age_days"),
    # files
    (["sweep", "run", "windplan.toml"], 1, "windplan.toml: [axes] wind: unknown axis"),
    (["sweep", "run", "nothere.toml"], 1, "nothere.toml: cannot read: No such file"),
    (["sweep", "run", "plan.toml", "--ray", "nohost"], 1,
     "--ray: 'nohost' is not local, auto, HOST:PORT or ray://HOST:PORT"),
    (["sweep", "run", "plan.toml", "--ray", "127.0.0.1:1"], 1,
     "--ray: no Ray cluster answers at 127.0.0.1:1: Connection refused"),
    (["sweep", "report", "nowhere"], 1, "nowhere: is not a sweep's folder (no sweep.json)"),
    (["bench", "sweep", "--cases", "3"], 1, "--cases: must be a multiple of 4, got 3"),
    ([*SNAP, "--world", "moon"], 1, "moon: unknown world (built-in: building, campus, lab"),
    ([*SNAP, "--calibration", "badcam.json"], 1, "badcam.json: missing field 'format_version'"),
    ([*SNAP, "--calibration", "notjson.json"], 1, "notjson.json: not valid JSON"),
    ([*SNAP, "--calibration", "nothere.json"], 1, "nothere.json: file not found"),
    (["teach", "--sim", "--route", "nowhere", "--memory", "m"], 1,
     "--route: unknown route 'nowhere' in world 'lab'"),
    (["teach", "--sim", "--route", "corridor", "--memory", "notimg.png"], 1,
     "notimg.png: is not a folder"),
    (["calibrate", "nowhere", *CAL], 1, "nowhere: folder not found"),
    (["calibrate", "--capture", "nothere.avi", "--views", "v", *CAL], 1,
     "nothere.avi: no such video file (nor a device index or URL)"),
    (["calibrate", "--from-equidistant", "nothere.yaml", "-o", "c.json"], 1,
     "nothere.yaml: file not found"),
    (["memory", "info", "--memory", "nowhere"], 1, "nowhere/manifest.json: no such folder"),
    (["memory", "route", "--memory", "nowhere", "1", "2"], 1, "nowhere/manifest.json"),
    (["memory", "localize", "--memory", "nowhere", "notimg.png"], 1, "nowhere/manifest.json"),
    (["vision", "localize", "notimg.png", "--memory", "nowhere"], 1, "nowhere/manifest.json"),
    (["log", "info", "nothere.mcap"], 1, "nothere.mcap: cannot read: No such file"),
    (["log", "info", "notimg.png"], 1, "notimg.png: not an MCAP file (2 bytes"),
    (["log", "info", "empty.mcap"], 1, "empty.mcap"),
    (["log", "plot", "nothere.mcap", "--out", "p"], 1, "nothere.mcap: cannot read"),
    (["robot", "--memory", "m", "--camera", "nothere.mp4"], 1,
     "nothere.mp4: no such video file (nor a device index or URL)"),
    (["robot", "--memory", "m", "--key", "nothere.key"], 1, "nothere.key: signing key file"),
    (["robot", "--memory", "m", "--calibration", "badcam.json"], 1, "badcam.json: missing field"),
    (["ground", "--key", "nothere.key", "status"], 1, "nothere.key: signing key file not found"),
    (["ground", "keygen", "."], 1, ".: exists: a new key never replaces one"),
    # addresses
    (["sim", "serve", "--aria", "serial:/dev/ttyS0"], 1, "--aria: 'serial:/dev/ttyS0' is not"),
    (["sim", "serve", "--aria", "tcp:99999"], 1, "--aria: 'tcp:99999': the TCP port must be"),
    (["sim", "serve", "--video", "udp:5000"], 1, "--video: 'udp:5000' is not http:PORT"),
    (["robot", "--memory", "m", "--mavlink", "udpin:0.0.0.0:14555"], 1,
     "an unsigned link open to the network lets anyone drive the robot"),
    (["ground", "--connect", "udpin:0.0.0.0:14556", "status"], 1,
     "an unsigned link open to the network lets anyone drive the robot"),
    (["robot", "--memory", "m", "--foxglove", "70000"], 1,
     "--foxglove: '70000': the TCP port must be 0-65535"),
    (["robot", "--memory", "m", "--foxglove", "0.0.0.0:8765"], 1, "--foxglove 0.0.0.0:8765: "
     "live topics open to the network show anyone who reaches them the camera"),
    (["robot", "--memory", "m", "--config", "foxnet.toml"], 1, "[foxglove] address "
     "192.0.2.1:8765: live topics open to the network"),
    (["robot", "--memory", "m", "--config", "badfox.toml"], 1,
     "badfox.toml: foxglove: jpeg_quality must be in 1..100, got 0"),
    ([*NO_VEHICLE, "status"], 1, "no HEARTBEAT from a vehicle within 0.2 s"),
    # checked before connecting: no vehicle needed to be told
    ([*NO_VEHICLE, "goto", "--image", "notimg.png"], 1,
     "notimg.png: not a PNG or JPEG image (the file starts with 78 78)"),
    ([*NO_VEHICLE, "goto", "--image", "nothere.jpg"], 1, "nothere.jpg: cannot read the goal"),
    ([*NO_VEHICLE, "goto"], 1, "goto: give either a key image id KEY or --image PHOTO"),
    ([*NO_VEHICLE, "teach", "start", "\u00e9t\u00e9"], 1,
     "NAME: path name '\u00e9t\u00e9': at most 21 printable ASCII characters"),
]


def test_there_are_at_least_60() -> None:
    assert len(CASES) >= 60


@pytest.mark.parametrize(("argv", "code", "fragment"), CASES,
                         ids=[" ".join(argv) for argv, _, _ in CASES])
def test_one_line_naming_the_problem(argv: list[str], code: int, fragment: str, tmp_path: Path,
                                     monkeypatch: pytest.MonkeyPatch,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    for name, text in FILES.items():
        (tmp_path / name).write_text(text)
    monkeypatch.chdir(tmp_path)
    try:
        got = main(argv)
    except SystemExit as exited:  # argparse's usage errors
        got = exited.code
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert (got, err.count("\n")) == (code, 1), err
    assert fragment in err, err
    assert not (tmp_path / "c.json").exists() and not (tmp_path / "o").exists()
