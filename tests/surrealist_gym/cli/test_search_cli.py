"""`surrealist replicate` and `surrealist generate` end to end on the real simulator (tiny budgets)."""
import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import surrealist_gym as sg
from surrealist_gym.cli import main
from surrealist_gym.store import EvaluationStore


def _rows(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def test_generate_writes_the_results_folder(tmp_path, capsys):
    out = tmp_path / "gen"
    assert main(["generate", "--budget", "3", "--runs", "2", "--workers", "1", "--out", str(out)]) == 0
    for name in ("best.yaml", "evaluations.csv", "summary.json", "figure1.png", "fitness.png", "min_distances.png"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["evaluations"] == 3 and summary["runs_per_evaluation"] == 2
    assert len(_rows(out / "evaluations.csv")) == 3
    best = sg.load_test(out / "best.yaml")
    assert len(best.obstacles) == 2 and best.mission is not None
    assert "results in" in capsys.readouterr().out
    # the best test runs in the simulator as it is
    assert main(["simulate", str(out / "best.yaml"), "--runs", "1", "--out", str(tmp_path / "sim")]) == 0


def test_generate_on_a_competition_test_flies_the_sitl_iris_and_judges_by_the_competition_distance(
        tmp_path, capsys, shared_data):
    from tests.conftest import SHARED_DATA

    seed = sorted((SHARED_DATA / "competition" / "camba-collection").glob("*.yaml"))[0]
    out = tmp_path / "gen"
    assert main(["generate", "--seed", str(seed), "--budget", "2", "--runs", "1", "--workers", "1",
                 "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["uav"] == "px4-v1.12-sitl-iris" and summary["distance"] == "competition"
    assert json.loads((out / "run.json").read_text())["uav"] == "px4-v1.12-sitl-iris"
    best = summary["best_runs"][0]
    assert summary["best_terms"]["min_dist"] == [pytest.approx(best["competition_distance"])]
    rows = _rows(out / "evaluations.csv")
    assert float(rows[0]["min_distance"]) == pytest.approx(summary["seed_runs"][0]["competition_distance"])
    assert "(competition distance)" in capsys.readouterr().out


def test_generate_flies_and_records_a_uav_profile(tmp_path, capsys):
    out = tmp_path / "gen-sitl"
    assert main(["generate", "--uav", "px4-v1.12-sitl-iris", "--budget", "2", "--runs", "1", "--workers", "1",
                 "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["uav"] == "px4-v1.12-sitl-iris"
    assert json.loads((out / "run.json").read_text())["uav"] == "px4-v1.12-sitl-iris"
    assert main(["generate", "--uav", "no-such-uav", "--budget", "2", "--out", str(tmp_path / "bad")]) == 2
    assert "no-such-uav" in capsys.readouterr().err and not (tmp_path / "bad").exists()


def test_replicate_with_a_seed(tmp_path):
    out = tmp_path / "rep"
    seed = sg.data_path("rq1-seed2.yaml")
    assert main(["replicate", "--seed", seed, "--budget", "3", "--runs", "1", "--workers", "1",
                 "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["best_terms"]["dtw"] <= summary["seed_terms"]["dtw"]
    assert summary["seed_obstacles"][0]["position"]["x"] == -7.56


def test_killed_search_resumes_without_losing_evaluations(tmp_path):
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "surrealist_gym.cli", "generate", "--budget", "8", "--runs", "1", "--workers", "1",
           "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    store = out / "evaluations.sqlite"
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None:
        if store.is_file() and len(EvaluationStore(store)) >= 3:
            break
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    time.sleep(0.5)  # its pool worker ends with it (PR_SET_PDEATHSIG)
    before = [e.test_key for e in EvaluationStore(store)]
    assert len(before) >= 3
    assert main(["generate", "--resume", str(out)]) == 0
    after = [e.test_key for e in EvaluationStore(store)]
    assert after[:len(before)] == before  # nothing lost, nothing simulated twice
    assert len(after) == len(set(after)) and len(_rows(out / "evaluations.csv")) == len(after)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["evaluations"] == 8 and summary["simulations_since_start"] == 8 - len(before)
    assert summary["simulations"] == 8  # the whole search's, before the kill and after


@pytest.mark.parametrize("argv,needle", [
    (["replicate", "/nonexistent/flight.ulg"], "flight.ulg"),
    (["generate", "--resume", "/nonexistent/folder"], "not a results folder"),
])
def test_bad_input_is_one_line_exit_2(argv, needle, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert not (tmp_path / "results").exists() or not any((tmp_path / "results").iterdir())  # nothing left behind
    err = capsys.readouterr().err.strip()
    assert needle in err and "\n" not in err and err.startswith("error:")


def test_bad_yaml_via_subprocess(tmp_path):
    bad = tmp_path / "bad.yaml"
    bad.write_text("simulation:\n  obstacles: [3,3,-1, 0,0,0, 0]\n")
    proc = subprocess.run([sys.executable, "-m", "surrealist_gym.cli", "generate", "--seed", str(bad), "--out",
                           str(tmp_path / "o")], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "bad.yaml" in lines[0] and "'h' must be positive" in lines[0]


def test_another_agent_from_the_command_line(tmp_path):
    out = tmp_path / "rand"
    assert main(["generate", "--agent", "random", "--budget", "3", "--runs", "1", "--workers", "1",
                 "--out", str(out)]) == 0
    assert json.loads((out / "summary.json").read_text())["evaluations"] <= 3
    assert main(["generate", "--agent", "randon", "--out", str(tmp_path / "bad")]) == 2
    assert not (tmp_path / "bad").exists()


def test_generate_with_common_noise(tmp_path):
    # common random numbers: the greedy's first moves slide the RQ2 box along the path, which leaves every run's
    # flight and score unchanged, so they tie the seed test exactly (with each test's own noise they never do)
    out = tmp_path / "crn"
    assert main(["generate", "--budget", "3", "--runs", "2", "--workers", "1", "--common-noise",
                 "--out", str(out)]) == 0
    assert json.loads((out / "run.json").read_text())["common_noise"] is True
    fitness = [float(row["fitness"]) for row in _rows(out / "evaluations.csv")]
    assert len(fitness) == 3 and len(set(fitness)) < 3


def test_generate_races_candidates_in_stages(tmp_path, capsys):
    # racing in stages from the command line: under common noise the greedy's first moves tie the seed test on
    # their first run and are dropped after it (one run each instead of three)
    # (--screen none: nothing is skipped without a flight); with --skips-spend-budget each drop spends a whole
    # evaluation of the greedy's budget, so it stops after as many candidates as without racing
    out = tmp_path / "race"
    assert main(["generate", "--budget", "3", "--runs", "3", "--workers", "1", "--common-noise", "--screen", "none",
                 "--first-runs", "1,2", "--skips-spend-budget", "--out", str(out)]) == 0
    options = json.loads((out / "run.json").read_text())
    assert options["first_runs"] == [1, 2] and options["screen"] == "none" and options["skips_spend_budget"]
    dropped = json.loads((out / "skipped.json").read_text())
    assert dropped and all(s["rule"] == "race" and s["tie"] and s["first_runs"] == 1 for s in dropped)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["evaluations"] + len(dropped) == 3
    assert summary["simulations"] == 3 * summary["evaluations"] + len(dropped)
    assert "dropped after their first 1/2 runs" in capsys.readouterr().out


def test_race_stages_reads_the_command_line_and_older_run_files():
    import argparse

    from surrealist_gym.cli.options import race_stages

    assert race_stages("1,2,3,4") == (1, 2, 3, 4) and race_stages("2") == (2,) and race_stages("0") == ()
    assert race_stages(0) == () and race_stages(1) == (1,) and race_stages([1, 2]) == (1, 2)  # from a run.json
    for bad in ("2,1", "a", [3, 3], "-1"):
        with pytest.raises(argparse.ArgumentTypeError, match="increasing numbers of runs"):
            race_stages(bad)


@pytest.mark.parametrize("stages", ["2,1", "1,3"])
def test_racing_stages_must_increase_below_the_runs(tmp_path, stages):
    with pytest.raises(SystemExit) as failed:  # argparse or the search's own check: one line, exit 2
        code = main(["generate", "--budget", "1", "--runs", "3", "--first-runs", stages, "--out", str(tmp_path / "x")])
        raise SystemExit(code)
    assert failed.value.code == 2


def test_a_results_folder_holds_one_search(tmp_path, capsys):
    """Another search into a results folder is refused before anything is written, naming the option that differs;
    the same command again resumes it (here: finished, so nothing is flown); a store holds one search's evaluations
    (its identity: problem, runs, seed, simulator) even when reached without the command line."""
    from surrealist_gym.envs.generate import GenerateEnv
    from surrealist_gym.errors import SurrealistError

    out = tmp_path / "crn"
    assert main(["generate", "--budget", "1", "--runs", "1", "--workers", "1", "--common-noise",
                 "--out", str(out)]) == 0
    saved = (out / "run.json").read_text()
    for other, flag in ((["--runs", "2"], "--runs"), (["--random-seed", "5"], "--random-seed"),
                        (["--budget", "3"], "--budget")):
        assert main(["generate", "--runs", "1", "--budget", "1", *other, "--workers", "1", "--out", str(out)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"error: {flag}: the search in {out} was started with"), err
    assert (out / "run.json").read_text() == saved
    assert main(["generate", "--budget", "1", "--runs", "1", "--common-noise", "--out", str(out)]) == 0
    assert (out / "run.json").read_text() == saved
    store = out / "evaluations.sqlite"
    with pytest.raises(SurrealistError, match="common noise"):  # each test's own noise: the noise mode differs
        GenerateEnv(runs=1, budget=1, store=str(store), executor="inline")
    with pytest.raises(SurrealistError, match="holds the evaluations of another search \\(runs: 1 there, 2 here"):
        GenerateEnv(runs=2, budget=1, store=str(store), executor="inline", sim_config={"common_noise": True})


def test_a_second_writer_is_refused(tmp_path):
    from surrealist_gym.errors import SurrealistError
    from surrealist_gym.results import ResultsFolder

    first = ResultsFolder.claim(tmp_path / "out", "generate", {"budget": 1})
    try:
        with pytest.raises(SurrealistError, match=f"another process \\(process {os.getpid()}\\) is writing"):
            ResultsFolder.claim(tmp_path / "out", "generate", {"budget": 1})
    finally:
        first.release()
    ResultsFolder.claim(tmp_path / "out", "generate", {"budget": 1}).release()


def test_compare_refuses_an_unknown_env_before_writing(tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", "--env", "Typo", "--agents", "greedy", "--out", str(out)]) == 2
    assert "--env 'Typo'" in capsys.readouterr().err and not out.exists()


def test_search_options_are_typed_once_for_arguments_run_json_and_resume(tmp_path):
    import argparse

    from surrealist_gym.cli.options import GenerateOptions, ReplicateOptions
    from surrealist_gym.errors import SurrealistError

    parser = argparse.ArgumentParser()
    GenerateOptions.add_arguments(parser)
    args = parser.parse_args(["--seed", "seed.yaml", "--budget", "7", "--first-runs", "1,2", "--common-noise"])
    options = GenerateOptions.from_args(args)
    assert (options.test, options.budget, options.runs, options.first_runs, options.common_noise) == \
        ("seed.yaml", 7, 10, (1, 2), True)
    assert options.prescreened and not GenerateOptions().prescreened
    path = tmp_path / "run.json"
    path.write_text(json.dumps(options.to_json()))
    assert GenerateOptions.from_json(path) == options
    with pytest.raises(SurrealistError, match="not a 'replicate' search"):
        ReplicateOptions.from_json(path)
    old = {k: v for k, v in options.to_json().items() if k not in ("uav", "screen")}  # an older run file
    path.write_text(json.dumps(old))
    assert GenerateOptions.from_json(path).uav is None
    path.write_text(json.dumps({**options.to_json(), "speed": 3}))
    with pytest.raises(SurrealistError, match="unknown option 'speed'"):
        GenerateOptions.from_json(path)
    assert ReplicateOptions().budget == 100 and ReplicateOptions().runs == 5


@pytest.mark.parametrize("argv, message", [
    (["--budget", "0"], "--budget: expected a whole number >= 1, got 0"),
    (["--runs", "0"], "--runs: expected a whole number >= 1, got 0"),
    (["--workers", "-1"], "--workers: expected a whole number >= 1, got -1"),
    (["--random-seed", "-1"], "--random-seed: expected a whole number >= 0, got -1")])
def test_bad_search_values_are_one_line_errors(tmp_path, capsys, argv, message):
    out = tmp_path / "gen"
    assert main(["generate", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and not out.exists()


@pytest.mark.parametrize("argv, message", [
    (["compare", "--repetitions", "0"], "--repetitions: expected a whole number >= 1, got 0"),
    (["compare", "--parallel", "0"], "--parallel: expected a whole number >= 1, got 0"),
    (["train", "--steps", "-5"], "--steps: expected a whole number >= 1, got -5"),
    (["simulate", "TEST", "--random-seed", "-1"], "--random-seed: expected a whole number >= 0, got -1"),
    (["simulate", "TEST", "--runs", "0"], "--runs: expected a whole number >= 1, got 0"),
    (["simulate", "TEST", "--param", "MPC_XY_CRUISE=1e400"], "expected NAME=number (a finite number)")])
def test_bad_numbers_of_other_commands_are_one_line_errors(tmp_path, capsys, argv, message):
    argv = [sg.data_path("rq1-seed1.yaml") if a == "TEST" else a for a in argv]
    written = ["--policy", str(tmp_path / "out" / "p.zip")] if argv[0] == "train" else ["--out", str(tmp_path / "out")]
    assert main([*argv, *written]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and not (tmp_path / "out").exists()


def test_out_that_is_a_file_is_refused(tmp_path, capsys):
    afile = tmp_path / "results.txt"
    afile.write_text("not a folder")
    assert main(["generate", "--out", str(afile)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err


def test_resume_does_not_import_an_agent_module_from_a_run_file(tmp_path, capsys):
    """A run.json can be edited by anyone: its module:Class agent is imported only when the command line names it."""
    from surrealist_gym.cli.options import GenerateOptions

    out = tmp_path / "gen"
    out.mkdir()
    (out / "run.json").write_text(json.dumps(GenerateOptions(agent="evil_module:Agent").to_json()))
    assert main(["generate", "--resume", str(out)]) == 2
    assert "resuming would import it: give --agent evil_module:Agent to confirm" in capsys.readouterr().err


def test_resume_takes_new_workers_and_refuses_a_new_identity(tmp_path, capsys):
    from surrealist_gym.cli.options import GenerateOptions

    out = tmp_path / "gen"
    out.mkdir()
    (out / "run.json").write_text(json.dumps(GenerateOptions(budget=2, runs=1, workers=1).to_json()))
    assert main(["generate", "--resume", str(out), "--budget", "9"]) == 2
    assert "--budget: the search in" in capsys.readouterr().err
    assert main(["generate", "--resume", str(out), "--budget", "100"]) == 2  # the default, typed: a change too
    assert "--budget: the search in" in capsys.readouterr().err
    assert main(["generate", "--resume", str(out), "--workers", "2"]) == 0
    assert json.loads((out / "summary.json").read_text())["evaluations"] <= 2


def test_resume_on_local_workers_leaves_a_lost_cluster(tmp_path):
    """A search whose Dask scheduler was lost resumes on local workers: --workers alone replaces the cluster."""
    from surrealist_gym.cli.options import GenerateOptions

    out = tmp_path / "gen"
    out.mkdir()
    lost = GenerateOptions(budget=2, runs=1, dask_scheduler="tcp://127.0.0.1:9").to_json()
    (out / "run.json").write_text(json.dumps(lost))
    assert main(["generate", "--resume", str(out), "--workers", "1"]) == 0
    assert json.loads((out / "summary.json").read_text())["evaluations"] <= 2
    dask = pytest.importorskip("dask")
    pytest.importorskip("distributed")  # its defaults join dask's config first: set() would remove them on exit
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}):
        assert main(["generate", "--budget", "1", "--dask-scheduler", "tcp://127.0.0.1:9", "--out",
                     str(tmp_path / "g2")]) == 2  # an unreachable scheduler: one line, no folder left behind
    assert not (tmp_path / "g2").exists()
