"""The results folder shows time: figure1.png's time panels and summary.json's profiles (real simulator)."""
import json

import pytest

import surrealist_gym as sg
from surrealist_gym.cli import main

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
KEYS = {"duration_s", "samples", "mean_horizontal_speed_mps", "max_horizontal_speed_mps",
        "horizontal_speed_percentiles_mps", "final_distance_to_goal_m"}


def _check(profiles: dict, names: set[str]) -> None:
    assert set(profiles) == names
    for name, p in profiles.items():
        assert set(p) == KEYS, name
        assert p["duration_s"] > 10 and p["samples"] > 20, name
        assert 0 < p["mean_horizontal_speed_mps"] <= p["max_horizontal_speed_mps"] < 10, name


def test_replicate_summary_has_real_seed_and_best_profiles_and_figure1(tmp_path):
    out = tmp_path / "r"
    assert main(["replicate", "--budget", "2", "--runs", "1", "--workers", "1", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    _check(summary["profiles"], {"real", "seed", "best"})
    real = sg.read_flight(sg.data_path("case0.ulg")).trajectory
    assert summary["profiles"]["real"]["duration_s"] == pytest.approx(real.duration, abs=0.01)
    assert summary["profiles"]["real"]["final_distance_to_goal_m"] == 0.0  # the goal: the real flight's end
    assert summary["goal"] == pytest.approx(real.xyz[-1].tolist(), abs=1e-3)
    assert (out / "figure1.png").read_bytes()[:8] == PNG_MAGIC


def test_generate_summary_has_seed_and_best_profiles_toward_the_mission_end(tmp_path):
    out = tmp_path / "g"
    assert main(["generate", "--budget", "2", "--runs", "1", "--workers", "1", "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    _check(summary["profiles"], {"seed", "best"})
    mission = sg.load_test(out / "best.yaml").mission
    assert summary["goal"] == pytest.approx(list(mission.waypoints[-1]), abs=1e-3)
    assert summary["profiles"]["best"]["final_distance_to_goal_m"] < 3  # the generated flights reach the goal
    assert (out / "figure1.png").read_bytes()[:8] == PNG_MAGIC
