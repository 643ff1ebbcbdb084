import numpy as np
import pytest
from pyulog import ULog

from surrealist_gym import Trajectory
from tests.conftest import CASE0_ULG, REFERENCE_CSV


def test_pipeline_reproduces_reference_csv():
    data = ULog(str(CASE0_ULG), ["vehicle_local_position"]).get_dataset("vehicle_local_position").data
    traj = Trajectory.from_local_position(data["timestamp"], data["x"], data["y"], data["z"], data["heading"])
    reference = np.loadtxt(REFERENCE_CSV, delimiter=",", skiprows=1)
    assert len(traj) == 86 == len(reference)
    assert np.abs(traj.xyz - reference[:, 1:4]).max() < 1e-6
    assert np.abs(traj.heading - reference[:, 4]).max() < 1e-6
    assert np.abs(traj.t * 1e6 - reference[:, 0]).max() <= 0.5


def test_windows_average_samples():
    t_us = np.arange(0, 2_000_000, 100_000)  # 10 Hz for 2 s
    x = np.arange(20, dtype=float)
    traj = Trajectory.from_local_position(t_us, x, 0 * x, -x, None)
    assert len(traj) == 4
    assert traj.x.tolist() == [2.0, 7.0, 12.0, 17.0]
    assert traj.z.tolist() == [2.0, 7.0, 12.0, 17.0]  # z flipped to up
    assert traj.t[0] == pytest.approx(0.2)


def test_csv_round_trip(tmp_path):
    ref = Trajectory.read_csv(REFERENCE_CSV)
    ref.write_csv(tmp_path / "t.csv")
    again = Trajectory.read_csv(tmp_path / "t.csv")
    assert np.allclose(again.xyz, ref.xyz, atol=1e-6) and len(again) == 86


def test_immutable_and_shift():
    ref = Trajectory.read_csv(REFERENCE_CSV)
    with pytest.raises(ValueError):
        ref.xyz[0, 0] = 1.0
    moved = ref.shifted(dx=0.5)
    assert np.allclose(moved.x - ref.x, 0.5) and moved != ref and ref == Trajectory.read_csv(REFERENCE_CSV)
    assert ref.between(0, 10).t.max() <= 10


def test_shape_checks():
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        Trajectory(np.zeros(3), np.zeros((3, 2)))
