import json
import subprocess
import sys
from pathlib import Path

import pytest

from surrealist_gym.cli import main
from tests.conftest import CASE0_ULG, FORMATS

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_case0_golden_facts(tmp_path, capsys):
    out = tmp_path / "plots" / "case0.png"  # --out DIR: the plot, named after the log, in that folder
    assert main(["inspect", str(CASE0_ULG), "--out", str(out.parent)]) == 0
    text = capsys.readouterr().out
    for fact in ("multirotor (PX4 airframe 4016)", "duration    43.3 s", "AUTO_MISSION 43.1 s",
                 "86 points of 0.5 s from 432 samples", "mission     2 items", "takeoff", "z   3.0 m",
                 "land", "(18.3 m from home)", "MPC_XY_CRUISE   5", "COM_OBS_AVOID   1", "CP_DIST         3",
                 "NAV_ACC_RAD     2", f"plot        {out}"):
        assert fact in text, fact
    assert out.read_bytes()[:8] == PNG_MAGIC


def test_default_plot_goes_to_the_current_directory(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["inspect", str(CASE0_ULG)]) == 0
    assert (tmp_path / "case0.png").read_bytes()[:8] == PNG_MAGIC
    assert str(tmp_path / "case0.png") in capsys.readouterr().out


def test_json(capsys):
    assert main(["inspect", str(CASE0_ULG), "--json", "--no-plot"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["vehicle"] == "multirotor (PX4 airframe 4016)" and info["format"] == "ulog"
    assert info["mode_durations_s"]["AUTO_MISSION"] == pytest.approx(43.1, abs=0.3)
    assert [it["command"] for it in info["mission"]["items"]] == ["takeoff", "land"]
    assert info["mission"]["items"][0]["z"] == pytest.approx(3.0)
    assert info["mission"]["items"][1]["distance_m"] == pytest.approx(18.3, abs=0.5)
    assert info["trajectory"]["points"] == 86 and info["mission_segment"]["points"] == 86
    assert info["params"]["MPC_XY_CRUISE"] == 5.0 and "plot" not in info


def test_mavlink_log(capsys):
    assert main(["inspect", str(FORMATS / "tlog" / "ardusub_small.tlog"), "--no-plot"]) == 0
    text = capsys.readouterr().out
    assert "ArduSub (submarine)" in text and "MANUAL" in text and "mission     none in the log" in text


@pytest.mark.parametrize("log, message", [
    (FORMATS / "ulog" / "robologs_test.ulg", "error: no valid local position in "),
    (FORMATS / "tlog" / "pymavlink_capture.mav2.battery_status.tlog", "error: no valid local position in "),
    (Path("missing.ulg"), "error: missing.ulg: cannot read log file"),
])
def test_bad_input_exits_2_with_one_line(log, message, capsys):
    assert main(["inspect", str(log), "--no-plot"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith(message) and captured.err.count("\n") == 1


def test_unwritable_plot_exits_2(tmp_path, capsys):
    (tmp_path / "afile").write_text("a file")
    assert main(["inspect", str(CASE0_ULG), "--out", str(tmp_path / "afile" / "plots")]) == 2
    assert "--out" in capsys.readouterr().err and not any(tmp_path.rglob("*.png"))


def test_a_plot_file_as_out_is_refused_with_its_folder(tmp_path, capsys):
    assert main(["inspect", str(CASE0_ULG), "--out", str(tmp_path / "plot.png")]) == 2
    err = capsys.readouterr().err
    assert f"--out is a folder; inspect writes <log name>.png in it: --out {tmp_path}" in err
    assert err.count("\n") == 1 and not any(tmp_path.iterdir())


def test_console_script_exit_code_and_single_stderr_line(tmp_path):
    script = Path(sys.executable).with_name("surrealist")
    random_log = tmp_path / "random.ulg"
    random_log.write_bytes(bytes(range(256)) * 8)
    proc = subprocess.run([str(script), "inspect", str(random_log), "--no-plot"], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 2
    assert proc.stderr.splitlines() == [f"error: {random_log}: not a ULog file "
                                        f"(the file does not start with the ULog magic bytes)"]
