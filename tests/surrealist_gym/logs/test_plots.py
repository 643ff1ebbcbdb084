"""Plots of real and simulated flights (surrealist_gym/logs/plots.py draws FlightLogs and trajectories)."""
import pytest

from surrealist_gym import Obstacle, Shape
from surrealist_gym.logs import read_flight
from surrealist_gym.logs.plots import plot_flight, plot_trajectories
from tests.conftest import CASE0_ULG

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_plot_flight(tmp_path):
    plot_flight(read_flight(CASE0_ULG), tmp_path / "case0.png")
    assert (tmp_path / "case0.png").read_bytes()[:8] == PNG_MAGIC


def test_plot_trajectories_many_runs_reference_and_obstacles(tmp_path):
    real = read_flight(CASE0_ULG).trajectory
    runs = [real.shifted(dx=0.2 * i, dy=-0.1 * i) for i in range(6)]
    obstacles = [Obstacle(3, 3, 3, -8.64, 1.74, 0, 158.8), Obstacle(2, 2, 10, -5, 8, shape=Shape.CYLINDER)]
    plot_trajectories(tmp_path / "runs.png", runs, obstacles=obstacles, title="seed 1", reference=real)
    plot_trajectories(tmp_path / "two.png", runs[:2], labels=["a", "b"], styles={"color": "red"})
    assert (tmp_path / "runs.png").read_bytes()[:8] == PNG_MAGIC
    assert (tmp_path / "two.png").read_bytes()[:8] == PNG_MAGIC


def test_plot_trajectories_checks_lengths(tmp_path):
    real = read_flight(CASE0_ULG).trajectory
    with pytest.raises(ValueError, match="1 labels for 2 trajectories"):
        plot_trajectories(tmp_path / "x.png", [real, real], labels=["only one"])
