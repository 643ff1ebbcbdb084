"""``surrealist simulate``: table, ULogs that read_flight loads, plot, comparison with the reference log."""
from __future__ import annotations

import json

import surrealist_gym as sg
from surrealist_gym.cli import main
from tests.conftest import EXPERIMENTS


def test_simulate_writes_table_ulogs_and_plot(tmp_path, capsys):
    code = main(["simulate", str(EXPERIMENTS / "rq1-seed2.yaml"), "--runs", "2", "--seed", "3", "--out",
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
