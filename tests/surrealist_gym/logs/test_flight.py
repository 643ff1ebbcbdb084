import dataclasses
import math
import warnings

import numpy as np
import pytest

import surrealist_gym as sg
from surrealist_gym import LogFormatError, Trajectory
from surrealist_gym.logs import detect_format, read_flight, read_ulog
from surrealist_gym.mission import Command
from tests.conftest import CASE0_ULG, FORMATS, REFERENCE_CSV


@pytest.fixture(scope="module")
def case0():
    return read_flight(CASE0_ULG)


# --- the real flight ------------------------------------------------------------------------------------------------
def test_case0_trajectory_matches_reference(case0):
    ref = Trajectory.read_csv(REFERENCE_CSV)
    assert len(case0.trajectory) == 86 == len(ref)
    assert np.abs(case0.trajectory.xyz - ref.xyz).max() < 1e-6
    assert np.abs(case0.trajectory.heading - ref.heading).max() < 1e-6
    assert np.abs(case0.trajectory.t - ref.t).max() < 1e-6  # the CSV rounds to whole microseconds


def test_lazy_package_exports():
    assert sg.read_flight is read_flight
    assert sg.FlightLog is type(read_flight(CASE0_ULG))


def test_case0_mission_items(case0):
    items = case0.mission.items
    assert [it.command for it in items] == [Command.TAKEOFF, Command.LAND]
    assert items[0].z == pytest.approx(3.0, abs=1e-3)
    assert math.hypot(items[0].x, items[0].y) < 0.5
    assert math.hypot(items[1].x, items[1].y) == pytest.approx(18.3, abs=0.5)
    assert items[1].x < -16 and items[1].y > 6  # south-east of home, like the trajectory's end
    assert case0.mission.home == case0.home


def test_case0_modes_home_params_vehicle(case0):
    assert [s.mode for s in case0.modes] == ["AUTO_MISSION"]
    assert case0.mode_durations()["AUTO_MISSION"] == pytest.approx(43.1, abs=0.3)
    assert case0.duration == pytest.approx(43.3, abs=0.2)
    lat, lon, alt = case0.home
    assert (lat, lon) == pytest.approx((47.4961, 8.7328), abs=1e-3) and alt == pytest.approx(437.7, abs=0.5)
    assert case0.params["MPC_XY_CRUISE"] == 5.0
    assert case0.params["COM_OBS_AVOID"] == 1 and case0.params["CP_DIST"] == 3.0
    assert case0.vehicle_type == "multirotor (PX4 airframe 4016)"
    assert case0.format == "ulog" and len(case0.positions) == 432


def test_case0_mission_segment(case0):
    seg = case0.mission_trajectory()
    assert case0.mission_mode == "AUTO_MISSION"
    assert len(seg) == 86 and np.abs(seg.xyz - case0.trajectory.xyz).max() < 1e-9
    with pytest.raises(LogFormatError, match="POSCTL never entered .*AUTO_MISSION"):
        case0.segment("POSCTL")


def test_segment_subtracts_its_own_start():
    flight = read_flight(FORMATS / "ulog" / "pyulog_sample_px4_events.ulg")
    assert [s.mode for s in flight.modes][:2] == ["AUTO_LOITER", "AUTO_TAKEOFF"]
    takeoff = flight.segment("AUTO_TAKEOFF")
    assert takeoff.t[0] < 0.5 and np.abs(takeoff.xyz[0]).max() < 0.2
    assert takeoff.z.max() > 1.5  # it climbs
    assert flight.mission_mode is None


def test_flight_log_is_immutable(case0):
    with pytest.raises(dataclasses.FrozenInstanceError):
        case0.path = "x"
    with pytest.raises(TypeError):
        case0.params["MPC_XY_CRUISE"] = 1.0
    with pytest.raises(ValueError):
        case0.positions.x[0] = 1.0


def test_read_ulog_accepts_a_binary_file():
    with open(CASE0_ULG, "rb") as f:
        flight = read_ulog(f)
    assert len(flight.trajectory) == 86


# --- every real file in formats/ reads or fails with its one-line reason --------------------------------------------
READS = {
    "ulog/px4tools_19_56_46.ulg": ("ulog", "multirotor (PX4 airframe 4010)"),
    "ulog/pyulog_sample_px4_events.ulg": ("ulog", "multirotor (PX4 airframe 10017)"),
    "tlog/ardusub_small.tlog": ("tlog", "ArduSub (submarine)"),
    "dataflash/pymavlink_test.BIN": ("dataflash", "ArduPlane V3.8.2-dev (fixed-wing)"),
}
FAILS = {
    "ulog/pyulog_sample_appended_multiple.ulg": r"no valid local position in .*appended_multiple\.ulg "
                                                r"\(vehicle_local_position\.xy_valid never set\)",
    "ulog/pyulog_sample_log_small.ulg": r"no valid local position in .*log_small\.ulg .*xy_valid never set",
    "ulog/robologs_test.ulg": r"no valid local position in .*robologs_test\.ulg .*xy_valid never set",
    "tlog/dronekit_log_upload_test.tlog": r"no valid local position in .*dronekit_log_upload_test\.tlog "
                                          r"\(no LOCAL_POSITION_NED; GLOBAL_POSITION_INT has no fix",
    "tlog/pymavlink_capture.mav2.battery_status.tlog": r"no valid local position in .*battery_status\.tlog "
                                                       r"\(no LOCAL_POSITION_NED; no GLOBAL_POSITION_INT\)",
    "dataflash/ardusub_small.BIN": r"no valid local position in .*ardusub_small\.BIN \(XKF1\.PN and XKF1\.PE "
                                   r"are always 0",
}


def test_every_log_in_formats_is_listed():
    logs = {p.relative_to(FORMATS).as_posix() for sub in ("ulog", "tlog", "dataflash")
            for p in (FORMATS / sub).iterdir()}
    assert logs == set(READS) | set(FAILS)


@pytest.mark.parametrize("name", sorted(READS))
def test_format_reads(name):
    flight = read_flight(FORMATS / name)
    fmt, vehicle = READS[name]
    assert flight.format == fmt and flight.vehicle_type == vehicle
    assert len(flight.trajectory) >= 2 and np.all(np.isfinite(flight.trajectory.xyz))
    assert np.abs(flight.trajectory.xyz[0]).max() < 0.1  # origin = first position
    assert flight.modes and flight.params


@pytest.mark.parametrize("name", sorted(FAILS))
def test_format_fails_with_one_line(name):
    with pytest.raises(LogFormatError, match=FAILS[name]) as info:
        read_flight(FORMATS / name)
    assert "\n" not in str(info.value)


def test_tlog_details():
    flight = read_flight(FORMATS / "tlog" / "ardusub_small.tlog")
    assert [s.mode for s in flight.modes] == ["MANUAL"]
    assert flight.home == pytest.approx((48.3861417, -124.630573, 0.16))
    assert flight.trajectory.heading is not None and len(flight.params) > 800


def test_dataflash_mission_from_cmd():
    flight = read_flight(FORMATS / "dataflash" / "pymavlink_test.BIN")
    assert flight.mission.items[0].command == Command.TAKEOFF and flight.mission.items[0].z == 15.0
    assert any("MAV_CMD 177" in s for s in flight.mission.skipped)  # DO_JUMP is not flown


# --- truncated and corrupt files ------------------------------------------------------------------------------------
@pytest.mark.filterwarnings("ignore:.*corrupt data")
@pytest.mark.parametrize("size", [0, 10, 16, 1000, 50_000])
def test_truncated_case0_without_position_fails_cleanly(tmp_path, size):
    path = tmp_path / "cut.ulg"
    path.write_bytes(CASE0_ULG.read_bytes()[:size])
    with pytest.raises(LogFormatError, match=r"cut\.ulg"):
        read_flight(path)


def test_truncated_case0_reads_the_part_before_the_cut(tmp_path):
    data = CASE0_ULG.read_bytes()
    path = tmp_path / "half.ulg"
    path.write_bytes(data[: len(data) // 2])
    part = read_flight(path).trajectory
    ref = Trajectory.read_csv(REFERENCE_CSV)
    assert 10 < len(part) < 86
    assert np.abs(part.xyz[:-1] - ref.xyz[: len(part) - 1]).max() < 1e-6


def test_corrupt_block_in_case0_is_skipped_with_a_warning(tmp_path):
    data = bytearray(CASE0_ULG.read_bytes())
    rng = np.random.default_rng(1)
    data[1_500_000:1_500_500] = rng.integers(0, 256, 500, dtype=np.uint8).tobytes()
    path = tmp_path / "corrupt.ulg"
    path.write_bytes(bytes(data))
    with pytest.warns(UserWarning, match="corrupt data"):
        flight = read_flight(path)
    assert 80 <= len(flight.trajectory) <= 86


@pytest.mark.parametrize("suffix, message", [
    (".ulg", "not a ULog file"), (".tlog", "not a MAVLink telemetry log"),
    (".bin", "not an ArduPilot DataFlash log"), (".dat", "unknown log format"),
])
def test_random_bytes(tmp_path, suffix, message):
    path = tmp_path / f"random{suffix}"
    path.write_bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8).tobytes())
    with pytest.raises(LogFormatError, match=message):
        read_flight(path)


def test_ulog_magic_then_garbage(tmp_path):
    path = tmp_path / "garbage.ulg"
    path.write_bytes(CASE0_ULG.read_bytes()[:16] + np.random.default_rng(2).bytes(5000))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(LogFormatError, match="garbage.ulg"):
            read_flight(path)


def test_missing_file(tmp_path):
    with pytest.raises(LogFormatError, match="cannot read log file"):
        read_flight(tmp_path / "nope.ulg")


def test_detect_format_by_content_not_extension(tmp_path):
    path = tmp_path / "flight.dat"
    path.write_bytes(CASE0_ULG.read_bytes()[:64])
    assert detect_format(path) == "ulog"
    assert detect_format(FORMATS / "tlog" / "ardusub_small.tlog") == "tlog"
    assert detect_format(FORMATS / "dataflash" / "ardusub_small.BIN") == "dataflash"


@pytest.mark.parametrize("share", [0.1, 0.5, 0.9])
def test_a_truncated_ulog_says_so(tmp_path, share):
    data = CASE0_ULG.read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[:int(len(data) * share)])
    with pytest.warns(UserWarning, match="cut.ulg: the file ends inside a message at byte .*: truncated, positions"):
        flight = read_ulog(cut)
    assert flight.end_us <= flight.positions.timestamp_us[-1] + 60_000_000
    readable = (flight.positions.timestamp_us[-1] - flight.start_us) / 1e6
    assert flight.damage.endswith(f"truncated, positions readable for {readable:.1f} s")


def test_a_search_refuses_a_truncated_log_unless_allowed(tmp_path, capsys):
    from surrealist_gym.cli import main

    cut = tmp_path / "cut.ulg"
    cut.write_bytes(CASE0_ULG.read_bytes()[:int(CASE0_ULG.stat().st_size * 0.9)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["replicate", str(cut), "--budget", "1", "--runs", "1", "--out", str(tmp_path / "r")]) == 2
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert "truncated, positions readable for" in err and "--allow-partial" in err
        assert main(["inspect", str(cut), "--no-plot"]) == 0
        assert "damaged     the file ends inside a message" in capsys.readouterr().out
        assert main(["replicate", str(cut), "--allow-partial", "--budget", "1", "--runs", "1", "--workers", "1",
                     "--out", str(tmp_path / "r")]) == 0


def test_whole_ulogs_are_not_called_truncated():
    for path in [CASE0_ULG, *sorted((FORMATS / "ulog").glob("*.ulg"))]:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                read_flight(path)
            except LogFormatError:  # a sample log without a valid local position
                pass
        assert not [w for w in caught if "truncated" in str(w.message)], path
