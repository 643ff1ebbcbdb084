"""``surrealist evaluate`` stores every run as it completes and owns its folder: an evaluation killed (SIGKILL) or
interrupted (SIGINT) and resumed gives the report an uninterrupted one gives; a second writer, a folder holding
something else and ``--out FILE`` are refused in one line before flying; a full disk while writing the report leaves
no half report and ``--resume`` writes it; runs that end in error are counted apart. Real flights, real processes,
real SQLite; three short CAMBA tests x 2 runs."""
import csv
import dataclasses
import errno
import json
import signal
import sqlite3
import subprocess
import sys
import time

import pytest

from surrealist_gym.cli import main
from surrealist_gym.sim.profiles import load_profile, save_profile
from tests.conftest import CAMBA_FAST, ROOT, SHARED_DATA, sigint_as_a_terminal_gives_it

COMPETITION = SHARED_DATA / "competition"
REPORT = ["report.md", "evaluation.csv", "runs.csv", "distances.png", "top-views.png", "suite-map.png"]
ARGS = ["--runs", "2", "--workers", "2"]


@pytest.fixture(scope="module")
def uninterrupted(camba_fast_folder, tmp_path_factory):
    """The folder of an evaluation flown in one go."""
    out = tmp_path_factory.mktemp("full") / "out"
    assert main(["evaluate", str(camba_fast_folder), *ARGS, "--out", str(out)]) == 0
    return out


def _rows(path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _same_report(a, b) -> None:
    """evaluation.csv and runs.csv alike (runs.csv's durations are simulated time, so they are compared too)."""
    assert _rows(a / "evaluation.csv") == _rows(b / "evaluation.csv")
    assert _rows(a / "runs.csv") == _rows(b / "runs.csv")


def _stored(out) -> int:
    """Runs in the folder's store (0 while it does not exist yet)."""
    try:
        with sqlite3.connect(f"file:{out / 'evaluations.sqlite'}?mode=ro", uri=True) as db:
            return sum(len(json.loads(r[0])) for r in db.execute("SELECT seeds FROM evaluations"))
    except sqlite3.Error:
        return 0


def _start(*argv) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", "import sys; from surrealist_gym.cli import main; "
                             "sys.exit(main(sys.argv[1:]))", "evaluate", *map(str, argv)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=sigint_as_a_terminal_gives_it)


def _wait_for_runs(out, process, at_least: int = 1) -> int:
    deadline = time.monotonic() + 120
    while (n := _stored(out)) < at_least:
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.02)
    return n


def _one_line(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "Traceback" not in err
    return err


@pytest.mark.slow
def test_killed_evaluation_resumes_to_the_same_report(camba_fast_folder, uninterrupted, tmp_path, capsys):
    out = tmp_path / "out"
    process = _start(camba_fast_folder, *ARGS, "--out", out)
    _wait_for_runs(out, process)
    process.kill()  # SIGKILL: no clean-up of any kind
    process.wait()
    kept = _stored(out)
    assert 1 <= kept < 6 and not (out / "report.md").exists()

    # the same command resumes: the killed run's lock (its pid gone) does not stand in the way
    assert main(["evaluate", str(camba_fast_folder), *ARGS, "--out", str(out)]) == 0
    assert f"({kept} runs read back from the store)" in capsys.readouterr().out
    assert _stored(out) == 6  # only the missing runs were flown
    _same_report(uninterrupted, out)


@pytest.mark.slow
def test_second_writer_refused_and_ctrl_c_keeps_the_runs(camba_fast_folder, uninterrupted, tmp_path, capsys):
    out = tmp_path / "out"
    first = _start(camba_fast_folder, *ARGS, "--out", out)
    _wait_for_runs(out, first)
    assert main(["evaluate", str(camba_fast_folder), *ARGS, "--out", str(out)]) == 2  # a second evaluation into it
    assert _one_line(capsys) == f"error: --out {out}: another process (process {first.pid}) is writing to this folder"
    assert main(["evaluate", "--resume", str(out)]) == 2  # or resuming it while it runs
    assert _one_line(capsys) == (f"error: --resume {out}: another process (process {first.pid}) is writing to this "
                                 f"folder")

    first.send_signal(signal.SIGINT)  # Ctrl-C
    _, err = first.communicate(timeout=60)
    assert first.returncode == 130, err
    assert err.strip().splitlines()[-1] == (f"interrupted: the runs flown are stored in {out / 'evaluations.sqlite'}; "
                                            f"surrealist evaluate --resume {out} flies the rest and writes the report")
    assert "Traceback" not in err and 1 <= _stored(out)
    assert main(["evaluate", "--resume", str(out)]) == 0
    _same_report(uninterrupted, out)


def test_out_holding_anything_else_is_refused_before_flying(camba_fast_folder, uninterrupted, tmp_path, capsys):
    test = str(camba_fast_folder / f"{CAMBA_FAST[0]}.yaml")
    assert main(["evaluate", test, "--out", str(uninterrupted)]) == 2  # an earlier evaluation, of other tests
    assert _one_line(capsys) == (f"error: TESTS: the evaluation in {uninterrupted} was started with other tests "
                                 f"({uninterrupted / 'run.json'} lists them); resuming keeps its options (only "
                                 f"--workers changes)")
    search = tmp_path / "generate"  # a search's results folder, or any files
    search.mkdir()
    for name in ("run.json", "evaluations.sqlite", "best.yaml", ".lock"):
        (search / name).write_text("{}\n")
    assert main(["evaluate", test, "--out", str(search)]) == 2
    assert _one_line(capsys) == (f"error: --out {search}: holds another run, not a run of evaluate; choose another "
                                 f"folder")
    (search / "run.json").unlink()
    assert main(["evaluate", test, "--out", str(search)]) == 2
    assert _one_line(capsys) == (f"error: --out {search}: holds something else (best.yaml and 1 more), not a run of "
                                 f"evaluate; choose a new or empty folder")
    assert sorted(p.name for p in search.iterdir()) == [".lock", "best.yaml", "evaluations.sqlite"]
    (search / "run.json").write_text("{}\n")
    afile = tmp_path / "report.txt"
    afile.write_text("x\n")
    assert main(["evaluate", test, "--out", str(afile)]) == 2
    assert _one_line(capsys) == f"error: --out {afile}: exists and is not a folder"
    assert main(["evaluate", test, "--out", str(afile / "sub")]) == 2
    assert _one_line(capsys) == f"error: --out {afile / 'sub'}: {afile} is a file, not a folder"
    assert main(["evaluate", "--resume", str(uninterrupted), "--runs", "3"]) == 2
    assert _one_line(capsys) == (f"error: --runs: the evaluation in {uninterrupted} was started with 2; resuming "
                                 f"keeps its options (only --workers changes)")
    assert main(["evaluate", "--resume", str(search)]) == 2
    assert _one_line(capsys) == f"error: {search}: holds no evaluation to resume (run.json is another command's)"
    assert main(["evaluate"]) == 2
    assert _one_line(capsys) == "error: TESTS: give the tests to evaluate (YAMLs or folders of them), or --resume DIR"


@pytest.mark.slow
def test_full_disk_leaves_no_half_report_and_resume_writes_it(camba_fast_folder, uninterrupted, tmp_path, capsys,
                                                              monkeypatch):
    disk = tmp_path / "disk"
    disk.mkdir()
    room = (uninterrupted / "evaluations.sqlite").stat().st_size + 64 * 1024  # the store fits, the report does not
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={room}", "tmpfs", str(disk)],
                             capture_output=True).returncode == 0
    if not mounted:  # no tmpfs here: the figure that does not fit is a full disk raised by the writing function
        def full(*args, **kwargs):
            raise OSError(errno.ENOSPC, "No space left on device")
        monkeypatch.setattr("surrealist_gym.competition.reports.plots.plot_suite_map", full)
    out = disk / "out"
    try:
        assert main(["evaluate", str(camba_fast_folder), *ARGS, "--out", str(out)]) == 2
        assert _one_line(capsys) == (f"error: {out}: cannot write the report (No space left on device); every run "
                                     f"is stored in {out / 'evaluations.sqlite'}: surrealist evaluate --resume "
                                     f"{out} writes the report")
        assert [p.name for p in out.iterdir() if p.name in REPORT or p.name.startswith(".report")] == []
        assert _stored(out) == 6
        if mounted:
            subprocess.run(["mount", "-o", "remount,size=16m", str(disk)], check=True)
        else:
            monkeypatch.undo()
        assert main(["evaluate", "--resume", str(out)]) == 0
        assert "(6 runs read back from the store)" in capsys.readouterr().out
        _same_report(uninterrupted, out)
    finally:
        if mounted:
            subprocess.run(["umount", str(disk)], check=True)


def test_runs_in_error_are_counted_apart(camba_fast_folder, tmp_path, capsys):
    """A UAV whose pitch-rate damping flips it in the air: every run ends in error, none passes or fails."""
    iris = load_profile("px4-v1.12-sitl-iris")
    profile = tmp_path / "flipping.yaml"
    save_profile(dataclasses.replace(iris, name="flipping", params={**iris.params, "MC_PITCHRATE_D": 1.0}), profile)
    out = tmp_path / "out"
    code = main(["evaluate", str(camba_fast_folder / f"{CAMBA_FAST[0]}.yaml"), "--runs", "2", "--workers", "1", "--uav",
                 str(profile), "--out", str(out)])
    if code == 2:
        pytest.skip(f"this UAV profile is refused before flying: {capsys.readouterr().err.strip()}")
    assert code == 0
    printed = capsys.readouterr().out
    assert "no run flown" in printed and "runs that ended in error" in printed
    row, = _rows(out / "evaluation.csv")
    assert (row["runs"], row["failures"], row["errors"], row["statuses"]) == ("2", "0", "2", "error:2")
    assert (row["p"], row["ci_low"], row["ci_high"], row["points_mean"], row["min_distance"]) == ("",) * 5
    runs = _rows(out / "runs.csv")
    assert [(r["status"], r["failed"], r["points"]) for r in runs] == [("error", "", "")] * 2
    assert all(r["message"].startswith("vehicle flipped") for r in runs)
    assert "| 0/0 | 2 | - (no run flown) |" in (out / "report.md").read_text()
