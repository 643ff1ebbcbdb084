"""Bad input is refused before any work: exit code 2, exactly one ``error:`` line naming the file or flag and the
field, no traceback, and nothing written or flown (no output folder, no plot, inputs unchanged). Real files and the
real command line; out-of-range UAV values, output paths that cannot be written, inputs that are not regular files,
empty stores, a policy that cannot be loaded safely, argparse errors and a ULog whose timestamps were damaged."""
from __future__ import annotations

import argparse
import io
import os
import shutil
import subprocess
import threading
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

import surrealist_gym as sg
from surrealist_gym.cli import main
from tests.conftest import SHARED_DATA, refused

DATA = Path(sg.data_path("case0.plan")).parent
RQ2 = DATA / "rq2-seed.yaml"
CASE0 = DATA / "case0.ulg"
STORE = Path(__file__).resolve().parents[2] / "data" / "stores" / "rq2-rep0.sqlite"


def nothing_in(folder: Path, *kept: str) -> bool:
    return sorted(p.name for p in folder.iterdir()) == sorted(kept)


@pytest.fixture
def work(tmp_path) -> Path:
    """A folder with copies of the RQ2 seed and its companions, and a regular file ``afile``."""
    for name in ("rq2-seed.yaml", "auto1.plan", "auto1-params.csv", "auto-commands.csv"):
        shutil.copy(DATA / name, tmp_path / name)
    (tmp_path / "afile").write_text("a file, not a folder\n")
    return tmp_path


def _test_yaml(folder: Path, params: str = "", commands: str = "commands_file: auto-commands.csv",
               params_file: str = "auto1-params.csv") -> Path:
    path = folder / "t.yaml"
    path.write_text(f"drone:\n  port: ros\n  params_file: {params_file}\n  mission_file: auto1.plan\n"
                    f"  params: {{{params}}}\nsimulation:\n  simulator: ros\n"
                    f"  obstacles: [7.625, 5.0625, 20, 17.1875, 17.53125, 0, 0]\ntest:\n  {commands}\n")
    return path


# --- 1. UAV values outside their physical range, in a profile, a test, a params file, --param ---------------------
PROFILE_FAULTS = [
    ("params: {MPC_XY_CRUISE: 0}", "params.MPC_XY_CRUISE"),
    ("params: {MPC_XY_CRUISE: -5}", "params.MPC_XY_CRUISE"),
    ("params: {MPC_XY_CRUISE: 1.0e9}", "params.MPC_XY_CRUISE"),
    ("params: {MPC_THR_MAX: -1}", "params.MPC_THR_MAX"),
    ("params: {MPC_ACC_HOR: 0}", "params.MPC_ACC_HOR"),
    ("params: {MPC_THR_HOVER: 0, MPC_USE_HTE: 0}", "params.MPC_THR_HOVER"),
    ("params: {MPC_XY_CRUISE: fast}", "params.MPC_XY_CRUISE"),
    ("planner: {cruise_speed: 1.0e9}", "planner.cruise_speed"),
    ("noise: {pos_noise_std: -0.1}", "noise.pos_noise_std"),
    ("noise: {turbulence_std: .nan}", "noise.turbulence_std"),
    ("sensor: {rays_h: 100000}", "sensor.rays_h"),
    ("takeoff_delay_s: -3", "takeoff_delay_s"),
    ("planner: {no_such_field: 1}", "planner.no_such_field"),
]


@pytest.mark.parametrize("body, field", PROFILE_FAULTS, ids=[f for _, f in PROFILE_FAULTS])
def test_a_profile_out_of_range_is_refused_before_flying(work, capsys, body, field):
    profile = work / "uav.yaml"
    profile.write_text(f"name: bad\n{body}\n")
    out = work / "out"
    line = refused(capsys, ["simulate", work / "rq2-seed.yaml", "--uav", profile, "--runs", "1", "--out", out],
                   profile, field)
    assert "expected" in line and not out.exists()


def test_generate_refuses_a_profile_out_of_range_before_any_results_folder(work, capsys):
    profile = work / "uav.yaml"
    profile.write_text("name: slow\nparams: {MPC_XY_CRUISE: 0}\n")
    out = work / "results"
    refused(capsys, ["generate", "--seed", work / "rq2-seed.yaml", "--uav", profile, "--budget", "1", "--runs", "1",
                     "--out", out], profile, "params.MPC_XY_CRUISE")
    assert not out.exists()


def test_a_zero_hover_thrust_is_an_input_error_not_an_infrastructure_failure(work, capsys):
    test = _test_yaml(work, "MPC_THR_HOVER: 0, MPC_USE_HTE: 0")
    out = work / "results"
    refused(capsys, ["generate", "--seed", test, "--budget", "1", "--runs", "1", "--workers", "1", "--out", out],
            test, "params.MPC_THR_HOVER", "(0, 1)")
    assert not out.exists()


@pytest.mark.parametrize("params, field", [
    ("uav.planner.max_sensor_range: 1.0e9", "params.uav.planner.max_sensor_range"),
    ("uav.takeoff_delay_s: -1", "params.uav.takeoff_delay_s"),
    ("MPC_ACC_HOR: 0", "params.MPC_ACC_HOR"),
    ("NAV_ACC_RAD: .inf", "params.NAV_ACC_RAD"),
])
def test_a_test_setting_out_of_range_names_the_test_file(work, capsys, params, field):
    test = _test_yaml(work, params)
    refused(capsys, ["simulate", test, "--runs", "1", "--out", work / "out"], test, field)
    assert not (work / "out").exists()


def test_an_unknown_uav_setting_is_refused_when_the_test_is_read(work, capsys):
    test = _test_yaml(work, "uav.no_such_setting: 1")
    refused(capsys, ["evaluate", test, "--any-layout", "--runs", "1", "--workers", "1", "--out", work / "out"],
            test, "params.uav.no_such_setting", "unknown UAV setting")
    assert not (work / "out").exists()


def test_a_params_file_out_of_range_names_its_file_and_line(work, capsys):
    (work / "bad-params.csv").write_text("NAV_ACC_RAD, 0.5\nMPC_XY_CRUISE, 0\n")
    test = _test_yaml(work, params_file="bad-params.csv")
    refused(capsys, ["simulate", test, "--runs", "1", "--out", work / "out"], "bad-params.csv", "line 2",
            "MPC_XY_CRUISE")
    assert not (work / "out").exists()


def test_a_param_override_out_of_range_is_refused(work, capsys):
    refused(capsys, ["simulate", work / "rq2-seed.yaml", "--param", "MPC_XY_CRUISE=1e9", "--out", work / "out"],
            "--param", "MPC_XY_CRUISE")
    assert not (work / "out").exists()


@pytest.mark.parametrize("commands, field", [
    ("commands: [{timestamp: 1, mode: 3, x: abc}]", "'x'"),
    ("commands: [{timestamp: one, mode: 3}]", "'timestamp'"),
    ("commands: [{timestamp: 1, mode: 2.5}]", "'mode'"),
    ("commands: [{mode: 3}]", "'timestamp'"),
])
def test_an_inline_command_with_non_numeric_fields_is_refused(work, capsys, commands, field):
    test = _test_yaml(work, commands=commands)
    refused(capsys, ["simulate", test, "--runs", "1", "--out", work / "out"], test, "commands[0]", field)


# --- 2. outputs that cannot be written, checked before anything is read or flown -------------------------------
def test_calibrate_out_under_a_file_is_refused_before_flying(work, capsys):
    refused(capsys, ["calibrate", CASE0, "--profile", work / "afile" / "u.yaml"], "--profile", "afile")
    assert nothing_in(work, "afile", "rq2-seed.yaml", "auto1.plan", "auto1-params.csv", "auto-commands.csv")


def test_calibrate_plot_of_another_kind_is_refused_before_flying(work, capsys):
    refused(capsys, ["calibrate", CASE0, "--profile", work / "u.yaml", "--plot", work / "u.txt"], "--plot", ".png")
    assert not (work / "u.yaml").exists() and not (work / "u.txt").exists()


def test_fidelity_out_that_is_a_file_is_refused_before_flying(work, capsys):
    labels = SHARED_DATA / "competition" / "rilast-mission1" / "tests.csv"
    refused(capsys, ["fidelity", labels, "--limit", "1", "--out", work / "afile"], "--out", "afile")
    assert (work / "afile").read_text() == "a file, not a folder\n"


def test_surrogate_eval_refuses_a_plot_that_is_not_a_png_before_evaluating(work, capsys):
    model = work / "model"
    assert main(["surrogate", "train", str(STORE), "--problem", "generate", "--kind", "knn", "--out", str(model)]) == 0
    capsys.readouterr()
    refused(capsys, ["surrogate", "eval", model, STORE, "--plot", work / "plots" / "eval.txt"], "--plot", ".png")
    assert not (work / "plots").exists()


@pytest.fixture
def read_only(tmp_path) -> Path:
    """A read-only tmpfs (refused even to root, unlike a chmod); skipped where mounting is not allowed."""
    folder = tmp_path / "ro"
    folder.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(folder)],
                             capture_output=True).returncode == 0
    if not mounted:
        pytest.skip("cannot mount a read-only tmpfs here")
    yield folder
    subprocess.run(["umount", str(folder)], check=True)


@pytest.mark.parametrize("argv, flag", [
    (["simulate", RQ2, "--runs", "1", "--out", "{ro}/sim"], "--out"),
    (["calibrate", CASE0, "--profile", "{ro}/u.yaml"], "--profile"),
    (["calibrate", CASE0, "--profile", "{tmp}/u.yaml", "--plot", "{ro}/u.png"], "--plot"),
    (["compare", "--budget", "1", "--repetitions", "1", "--agents", "random", "--out", "{ro}/cmp"], "--out"),
    (["surrogate", "train", STORE, "--problem", "generate", "--kind", "knn", "--out", "{ro}/model"], "--out"),
    (["train", "--steps", "1", "--policy", "{ro}/policy.zip"], "--policy"),
    (["inspect", CASE0, "--out", "{ro}/plots"], "--out"),
    (["fidelity", SHARED_DATA / "competition" / "rilast-mission1" / "tests.csv", "--out", "{ro}/fid"], "--out"),
], ids=lambda v: v[0] if isinstance(v, list) else v)
def test_a_read_only_output_is_refused_before_any_work(read_only, tmp_path, capsys, argv, flag):
    argv = [str(a).format(ro=read_only, tmp=tmp_path) for a in argv]
    refused(capsys, argv, flag, "read-only")
    assert nothing_in(tmp_path, "ro")


# --- 3. inputs are read only: a store is an existing, non-empty regular file, never created or changed ----------
@pytest.mark.parametrize("action", ["train", "eval"])
def test_an_empty_store_is_refused_and_left_empty(work, capsys, action):
    empty = work / "empty.sqlite"
    empty.touch()
    argv = (["surrogate", "train", empty, "--out", work / "model"] if action == "train"
            else ["surrogate", "eval", work, empty])
    refused(capsys, argv, "empty.sqlite", "empty")
    assert empty.stat().st_size == 0 and not (work / "model").exists()


def test_training_on_a_store_leaves_it_unchanged(work, capsys):
    store = work / "rq2.sqlite"
    shutil.copy(STORE, store)
    before = store.read_bytes()
    assert main(["surrogate", "train", str(store), "--problem", "generate", "--kind", "knn",
                 "--out", str(work / "model")]) == 0
    assert store.read_bytes() == before and not list(work.glob("rq2.sqlite-*"))  # no journal either


# --- 4, 5. compare's agents --------------------------------------------------------------------------------------
def test_compare_with_no_agents_is_one_line(work, capsys):
    refused(capsys, ["compare", "--agents", "", "--out", work / "cmp"], "--agents")
    assert not (work / "cmp").exists()


def test_compare_makes_its_env_once_before_any_folder(work, capsys):
    refused(capsys, ["compare", "--env", "Surrealist-Generate-v0", "--log", CASE0, "--agents", "random",
                     "--out", work / "cmp"], "--log: applies only to Surrealist-Replicate-v0",
            "not to Surrealist-Generate-v0")
    test = _test_yaml(work, "uav.planner.no_such_field: 1")
    refused(capsys, ["compare", "--env", "Surrealist-Generate-v0", "--seed", test, "--agents", "random",
                     "--out", work / "cmp"], test, "params.uav.planner.no_such_field")
    assert not (work / "cmp").exists()


def test_a_policy_holding_a_pickle_is_not_loaded(work, capsys):
    import torch

    buffer = io.BytesIO()
    torch.save({"action_net.weight": torch.zeros(2, 2), "payload": argparse.Namespace(code=1)}, buffer)
    policy = work / "policy.zip"
    with zipfile.ZipFile(policy, "w") as archive:
        archive.writestr("policy.pth", buffer.getvalue())
    line = refused(capsys, ["compare", "--agents", f"ppo:{policy}", "--budget", "1", "--repetitions", "1",
                            "--out", work / "cmp"], policy, "cannot be loaded safely")
    assert "weights_only" not in line and not (work / "cmp").exists()


# --- 6. argparse errors are one line; --help still prints the usage ---------------------------------------------
@pytest.mark.parametrize("argv, words", [
    ([], "required: COMMAND"),
    (["nope"], "invalid choice"),
    (["simulate"], "required: TEST.yaml"),
    (["simulate", "t.yaml", "--runs", "many"], "--runs"),
    (["surrogate", "eval"], "required: MODEL, STORE"),
    (["generate", "--budget"], "--budget"),
])
def test_argparse_errors_are_one_line(capsys, argv, words):
    refused(capsys, argv, words)


def test_help_still_prints_the_usage(capsys):
    with pytest.raises(SystemExit) as done:
        main(["simulate", "--help"])
    assert done.value.code == 0 and "usage: surrealist simulate" in capsys.readouterr().out


# --- 7. a FIFO (or a folder) where a file is expected is refused without being opened --------------------------
@pytest.fixture
def fifo(tmp_path):
    """Make a FIFO and watch it: a reader that opens it is noticed (a writer opens it then, and closes at once, so
    such a reader ends instead of hanging the test)."""
    opened, stop, made = [], threading.Event(), []

    def watch():
        while not stop.is_set():
            for path in made:
                try:
                    fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK)  # succeeds only with a reader waiting
                except OSError:
                    continue
                opened.append(path)
                os.close(fd)
            time.sleep(0.05)

    def make(name: str) -> Path:
        path = tmp_path / name
        os.mkfifo(path)
        made.append(path)
        return path

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    yield make, opened
    stop.set()
    watcher.join()


def test_fifo_inputs_are_refused_before_they_are_opened(work, fifo, capsys):
    make, opened = fifo
    log, test, profile, store, labels = (make(n) for n in ("log.ulg", "test.yaml", "uav.yaml", "e.sqlite",
                                                           "labels.csv"))
    refused(capsys, ["inspect", log, "--no-plot"], log, "FIFO")
    refused(capsys, ["simulate", test, "--out", work / "out"], test, "FIFO")
    refused(capsys, ["simulate", RQ2, "--uav", profile, "--out", work / "out"], profile, "FIFO")
    refused(capsys, ["surrogate", "train", store, "--out", work / "model"], store, "FIFO")
    yamls = work / "yamls"
    yamls.mkdir()
    refused(capsys, ["fidelity", yamls, "--labels", labels, "--out", work / "fid"], labels, "FIFO")
    refused(capsys, ["calibrate", log, "--profile", work / "u.yaml"], log, "FIFO")
    time.sleep(0.2)
    assert opened == [] and not (work / "out").exists() and not (work / "model").exists()


def test_a_folder_given_as_a_log_is_refused(work, capsys):
    refused(capsys, ["inspect", work, "--no-plot"], work, "a folder")


# --- 9. a ULog with flipped bits is not read as a long flight -------------------------------------------------
def _flipped(seed: int, bits: int = 2000) -> bytes:
    data = bytearray(CASE0.read_bytes())
    for bit in np.random.default_rng(seed).integers(0, len(data) * 8, bits):
        data[bit // 8] ^= 1 << (bit % 8)
    return bytes(data)


def test_a_ulog_with_flipped_timestamps_reads_as_damaged_not_as_a_long_flight(tmp_path, capsys):
    import json

    log = tmp_path / "flipped.ulg"
    log.write_bytes(_flipped(7))  # read as a 17,260 s flight before the timeline check
    assert main(["inspect", str(log), "--json", "--no-plot"]) == 0
    captured = capsys.readouterr()
    info = json.loads(captured.out)
    assert info["duration_s"] < 44.0 and "timeline" in info["damage"]
    out = tmp_path / "results"
    refused(capsys, ["replicate", log, "--budget", "1", "--runs", "1", "--out", out], log, "timeline")
    assert not out.exists()


@pytest.mark.parametrize("seed", range(8))
def test_flipped_ulogs_never_read_longer_than_their_flight(tmp_path, seed):
    import warnings

    log = tmp_path / "flipped.ulg"
    log.write_bytes(_flipped(seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            flight = sg.read_flight(log)
        except sg.SurrealistError as err:
            assert "\n" not in str(err)
            return
    assert flight.duration < 44.0 and flight.damage


def test_the_timeline_sets_aside_samples_whose_timestamps_jumped():
    from surrealist_gym.logs.ulog import on_timeline

    ts = np.arange(0, 40_000_000, 100_000)  # 40 s at 10 Hz
    assert on_timeline(ts).all()
    jumped = ts.copy()
    jumped[150] += 2 ** 30  # a flipped bit: 1,074 s ahead, in the middle
    jumped[-1] += 2 ** 34  # and at the end
    jumped[5] -= 2 ** 22  # and 4 s back
    keep = on_timeline(jumped)
    assert not keep[[5, 150, len(ts) - 1]].any() and keep.sum() == len(ts) - 3
