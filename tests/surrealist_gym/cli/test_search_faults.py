"""A results folder outlives every fault once its first evaluation is stored, and ``--resume`` finishes it with the
evaluations of an uninterrupted search: pool workers killed twice, a full disk (a real tmpfs where this machine lets
the test mount one), a plot that cannot be written, Ctrl-C. Real searches on the real simulator (tiny budgets)."""
import csv
import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from surrealist_gym.cli import main
from surrealist_gym.cli._search import stored_evaluations
from tests.conftest import sigint_as_a_terminal_gives_it

BUDGET = "12"
SEARCH = ["generate", "--budget", BUDGET, "--runs", "1", "--workers", "1"]


def _evaluations(folder: Path) -> list[dict]:
    """evaluations.csv without its timings."""
    with open(folder / "evaluations.csv") as f:
        return [{k: v for k, v in row.items() if k != "sim_seconds"} for row in csv.DictReader(f)]


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> list[dict]:
    """The search flown undisturbed, in its own process as the faulted ones are (a pool forked from the test
    process would inherit the threads earlier tests left in it: torch's, Dask's)."""
    out = tmp_path_factory.mktemp("uninterrupted") / "search"
    done = subprocess.run([sys.executable, "-m", "surrealist_gym.cli", *SEARCH, "--out", str(out)],
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return _evaluations(out)


def _start(out: Path) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "surrealist_gym.cli", *SEARCH, "--out", str(out)],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            preexec_fn=sigint_as_a_terminal_gives_it)


def _wait_for_stored(proc: subprocess.Popen, out: Path, n: int) -> None:
    deadline = time.time() + 120
    while stored_evaluations(out) < n:
        assert proc.poll() is None and time.time() < deadline, "the search ended before storing enough"
        time.sleep(0.05)


def _children(pid: int) -> list[int]:
    """The pool workers of process ``pid`` (its children, not multiprocessing's resource tracker)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmdline = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == pid and b"resource_tracker" not in cmdline:
            found.append(int(entry.name))
    return found


def _one_error_line(stderr: str) -> str:
    errors = [line for line in stderr.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "Traceback" not in stderr, stderr
    return errors[0]


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="finds pool workers through /proc")
def test_a_fresh_search_whose_workers_die_keeps_its_folder_and_resumes(tmp_path, uninterrupted):
    out = tmp_path / "workers-die"
    proc = _start(out)
    _wait_for_stored(proc, out, 2)
    deadline = time.time() + 180
    while proc.poll() is None:  # every pool the search starts loses its worker: it fails twice and stops
        if time.time() > deadline:
            proc.kill()
            pytest.fail(f"the search did not stop after its workers died: {proc.communicate()[1][-2000:]}")
        for pid in _children(proc.pid):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        time.sleep(0.02)
    line = _one_error_line(proc.stderr.read())
    stored = stored_evaluations(out)
    assert proc.returncode == 2 and "failed twice outside the simulator" in line
    assert f"{stored} evaluation(s) are stored in {out}" in line and f"--resume {out}" in line and stored >= 2
    assert main(["generate", "--resume", str(out)]) == 0
    assert _evaluations(out) == uninterrupted


def test_ctrl_c_keeps_the_folder_and_resumes(tmp_path, uninterrupted):
    out = tmp_path / "interrupted"
    proc = _start(out)
    _wait_for_stored(proc, out, 2)
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)
    stderr = proc.stderr.read()
    assert proc.returncode == 130 and "Traceback" not in stderr and f"--resume {out}" in stderr
    assert stored_evaluations(out) >= 2
    assert main(["generate", "--resume", str(out)]) == 0
    assert _evaluations(out) == uninterrupted


def test_kill_9_keeps_the_folder_and_the_same_command_resumes(tmp_path, uninterrupted):
    """SIGKILL: no clean-up of any kind; its pool worker may outlive it a moment, holding the lock file it
    inherited: the lock of a process that no longer runs is taken over."""
    out = tmp_path / "killed"
    proc = _start(out)
    _wait_for_stored(proc, out, 2)
    proc.kill()
    proc.wait(timeout=60)
    proc.stderr.close()
    stored = stored_evaluations(out)
    assert stored >= 2 and not (out / "evaluations.csv").exists()
    assert main([*SEARCH, "--out", str(out)]) == 0  # the same command
    assert _evaluations(out) == uninterrupted


def test_a_plot_that_cannot_be_written_keeps_the_folder(tmp_path, uninterrupted, monkeypatch, capsys):
    """The disk fills while figure1.png is written (an injected ENOSPC: where it strikes is the point here)."""
    import surrealist_gym.results.search as results

    def full_disk(out, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(out / "figure1.png"))

    out = tmp_path / "plot"
    with monkeypatch.context() as patched:
        patched.setattr(results, "plot_search", full_disk)
        assert main([*SEARCH, "--out", str(out)]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "figure1.png: cannot write (No space left on device)" in line and f"--resume {out}" in line
    assert stored_evaluations(out) == len(uninterrupted)
    assert main(["generate", "--resume", str(out)]) == 0
    assert _evaluations(out) == uninterrupted and (out / "figure1.png").is_file()


@pytest.fixture
def small_disk(tmp_path):
    """A 2 MB tmpfs (root on Linux), unmounted afterwards; skipped where mounting is not allowed."""
    mount = tmp_path / "disk"
    mount.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", str(mount)], capture_output=True)
    if done.returncode:
        pytest.skip("cannot mount a tmpfs here")
    yield mount
    subprocess.run(["umount", "-l", str(mount)], capture_output=True)


def test_a_full_disk_keeps_the_folder_and_resume_finishes_it(small_disk, uninterrupted):
    out = small_disk / "search"
    proc = _start(out)
    _wait_for_stored(proc, out, 3)
    filler = small_disk / "filler"
    with open(filler, "wb") as f:  # fill the disk while the search runs
        try:
            while True:
                f.write(b"\0" * 65536)
                f.flush()
        except OSError as err:
            assert err.errno == errno.ENOSPC
    proc.wait(timeout=120)
    line = _one_error_line(proc.stderr.read())
    stored = stored_evaluations(out)
    assert proc.returncode == 2 and f"{stored} evaluation(s) are stored in {out}" in line and stored >= 3
    filler.unlink()
    assert main(["generate", "--resume", str(out)]) == 0
    assert _evaluations(out) == uninterrupted


def test_a_read_only_results_folder_is_refused_before_any_work(tmp_path, capsys):
    disk = tmp_path / "ro"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(disk)],
                      capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here")
    try:
        assert main([*SEARCH, "--out", str(disk / "search")]) == 2
    finally:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)
    line = _one_error_line(capsys.readouterr().err)
    assert f"--out {disk / 'search'}: cannot write in {disk} (a read-only file system)" in line


def test_a_failure_before_the_first_evaluation_removes_the_fresh_folder(tmp_path, capsys):
    """Nothing stored yet: the folder this command made is removed, and the line does not promise a resume."""
    out = tmp_path / "unreachable"
    assert main([*SEARCH, "--dask-scheduler", "tcp://127.0.0.1:1", "--out", str(out)]) == 2
    line = _one_error_line(capsys.readouterr().err)
    assert "--dask-scheduler" in line and "--resume" not in line and not out.exists()
