"""``surrealist simulate``: table, ULogs that read_flight loads, plot, comparison with the reference log."""
from __future__ import annotations

import json

import surrealist_gym as sg
from surrealist_gym.cli import main
from tests.conftest import EXPERIMENTS


def test_simulate_writes_table_ulogs_and_plot(tmp_path, capsys):
    code = main(["simulate", str(EXPERIMENTS / "rq1-seed2.yaml"), "--runs", "2", "--random-seed", "3", "--out",
                 str(tmp_path), "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert [row["run"] for row in out["runs"]] == [0, 1]
    assert all(row["status"] == "success" and row["dtw"] > 0 and row["frechet_m"] > 0 for row in out["runs"])
    assert (tmp_path / "rq1-seed2.png").stat().st_size > 0
    flight = sg.read_flight(out["runs"][0]["ulog"])
    assert abs(flight.trajectory.duration - out["runs"][0]["duration_s"]) < 1.0
    assert flight.params["MPC_XY_CRUISE"] == 5.0


def test_simulate_bad_param_is_a_clean_error(tmp_path, capsys):
    code = main(["simulate", str(EXPERIMENTS / "rq1-seed2.yaml"), "--param", "MPC_XY_P", "--out", str(tmp_path)])
    assert code == 2
    assert "NAME=number" in capsys.readouterr().err


def test_simulate_picks_the_uav_from_the_test(tmp_path, capsys, shared_data):
    """A test naming a real flight flies the PX4 Vision of case0; a competition test the PX4 SITL Iris."""
    assert main(["simulate", str(EXPERIMENTS / "rq1-seed2.yaml"), "--runs", "1", "--out", str(tmp_path),
                 "--no-ulog", "--no-plot", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["uav"] == "px4-vision-case0"
    mission1 = EXPERIMENTS.parent.parent / "competition" / "case_studies" / "mission1.yaml"
    assert main(["simulate", str(mission1), "--runs", "1", "--out", str(tmp_path), "--no-ulog", "--no-plot",
                 "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    assert run["uav"] == "px4-v1.12-sitl-iris" and run["runs"][0]["status"] == "success"
    assert json.loads((tmp_path / "uav.json").read_text())["reasons"] == ["px4-v1.12-sitl-iris: the default UAV"]
