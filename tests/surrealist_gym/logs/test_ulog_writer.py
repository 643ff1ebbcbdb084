import io

import numpy as np
import pytest
from pyulog import ULog

from surrealist_gym import Trajectory, read_mission
from surrealist_gym.logs import read_flight, write_ulog
from surrealist_gym.mission import Command
from tests.conftest import CASE0_ULG, EXPERIMENTS, REFERENCE_CSV


@pytest.fixture(scope="module")
def case0_samples():
    return ULog(str(CASE0_ULG), ["vehicle_local_position"]).get_dataset("vehicle_local_position").data


def _write(path, d, **kwargs):
    write_ulog(path, d["timestamp"], d["x"], d["y"], d["z"], d["vx"], d["vy"], d["vz"], d["heading"], **kwargs)


def test_round_trip_of_case0_samples(tmp_path, case0_samples):
    real = read_flight(CASE0_ULG)
    path = tmp_path / "run.ulg"
    _write(path, case0_samples, params=dict(real.params), mission=real.mission)
    again = read_flight(path)
    assert again.trajectory == real.trajectory  # float32 in, float32 out: bit-identical
    ref = Trajectory.read_csv(REFERENCE_CSV)
    assert np.abs(again.trajectory.xyz - ref.xyz).max() < 1e-6
    assert again.params["MPC_XY_CRUISE"] == 5.0 and again.params["SYS_AUTOSTART"] == 4016
    assert isinstance(again.params["SYS_AUTOSTART"], int)
    assert [it.command for it in again.mission.items] == [Command.TAKEOFF, Command.LAND]
    for a, b in zip(again.mission.items, real.mission.items):
        assert (a.x, a.y, a.z) == pytest.approx((b.x, b.y, b.z), abs=1e-6)
    assert again.home == pytest.approx(real.home, abs=1e-4)
    assert [s.mode for s in again.modes] == ["AUTO_MISSION"]
    assert again.vehicle_type == "multirotor (PX4 airframe 4016)"
    assert len(again.mission_trajectory()) == 86


def test_pyulog_reads_the_written_file(tmp_path, case0_samples):
    path = tmp_path / "run.ulg"
    _write(path, case0_samples, params={"MPC_XY_CRUISE": 5.0, "COM_OBS_AVOID": 1})
    ulog = ULog(str(path))
    assert not ulog.file_corruption
    lp = ulog.get_dataset("vehicle_local_position").data
    for field in ("timestamp", "x", "y", "z", "vx", "vy", "vz", "heading", "xy_valid", "z_valid"):
        assert field in lp
    assert np.array_equal(lp["timestamp"], case0_samples["timestamp"])
    assert np.array_equal(lp["z"], case0_samples["z"]) and lp["xy_valid"].all()
    assert ulog.initial_parameters == {"MPC_XY_CRUISE": 5.0, "COM_OBS_AVOID": 1}
    assert ulog.start_timestamp == case0_samples["timestamp"][0]
    assert ulog.msg_info_dict["sys_name"] == "surrealist-gym"


def test_simulated_straight_line(tmp_path):
    t = np.arange(0, 10_000_000, 20_000)  # 50 Hz for 10 s
    north = 1.5 * t / 1e6
    zeros = np.zeros_like(north)
    mission = read_mission(EXPERIMENTS / "case0.plan")
    buffer = io.BytesIO()
    write_ulog(buffer, t, north, zeros, zeros - 3.0, zeros + 1.5, zeros, zeros, zeros, mission=mission,
               nav_state="POSCTL")
    path = tmp_path / "line.ulg"
    path.write_bytes(buffer.getvalue())
    flight = read_flight(path)
    direct = Trajectory.from_local_position(t, north, zeros, zeros - 3.0, zeros)
    assert np.allclose(flight.trajectory.xyz, direct.xyz, atol=1e-5) and len(flight.trajectory) == 20
    assert np.allclose(flight.trajectory.z, 0.0)  # origin at the first position: z up relative to it
    assert [s.mode for s in flight.modes] == ["POSCTL"] and flight.duration == pytest.approx(9.98)
    assert flight.mission.items[1].command == Command.LAND
    assert flight.mission.items[1].x == pytest.approx(mission.items[1].x, abs=1e-6)


def test_invalid_samples_are_marked_invalid(tmp_path):
    t = np.arange(5) * 100_000
    x = np.array([0.0, np.nan, 1.0, 2.0, 3.0])
    zeros = np.zeros(5)
    write_ulog(tmp_path / "nan.ulg", t, x, zeros, zeros, zeros, zeros, zeros, zeros)
    flight = read_flight(tmp_path / "nan.ulg")
    assert len(flight.positions) == 4 and flight.home is None and flight.mission is None


@pytest.mark.parametrize("kwargs, message", [
    ({"timestamp_us": [2, 1]}, "non-decreasing"),
    ({"timestamp_us": []}, "no samples"),
    ({"x": [0.0]}, "x must have shape"),
    ({"nav_state": "HOVER"}, "unknown nav_state"),
])
def test_bad_arguments(tmp_path, kwargs, message):
    args = {"timestamp_us": [0, 1], "x": [0.0, 0.0], "y": [0.0, 0.0], "z": [0.0, 0.0], "vx": [0.0, 0.0],
            "vy": [0.0, 0.0], "vz": [0.0, 0.0], "heading": [0.0, 0.0]}
    args.update(kwargs)
    if "timestamp_us" in kwargs and not kwargs["timestamp_us"]:
        args.update({k: [] for k in ("x", "y", "z", "vx", "vy", "vz", "heading")})
    with pytest.raises(ValueError, match=message):
        write_ulog(tmp_path / "bad.ulg", **args)
