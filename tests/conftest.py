"""Shared fixtures: the real data in ../shared/data (beside the project root)."""
from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data"
EXPERIMENTS = SHARED_DATA / "surrealist" / "experiments"
FORMATS = SHARED_DATA / "formats"
CASE0_ULG = EXPERIMENTS / "case0.ulg"
REFERENCE_CSV = SHARED_DATA / "reference" / "case0_reference_trajectory.csv"
CASE_STUDIES = SHARED_DATA / "competition" / "case_studies"


def refused(capsys, argv, *names) -> str:
    """Run the command line; assert exit 2 with exactly one ``error:`` line that names each of ``names`` and no
    traceback; return that line."""
    from surrealist_gym.cli import main

    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    for name in names:
        assert str(name) in lines[0], (name, lines[0])
    return lines[0]


def until(condition, what: str, limit_s: float = 180.0) -> None:
    """Poll ``condition`` until it holds (a bounded wait for another process, not a timing assertion)."""
    import time

    end = time.monotonic() + limit_s
    while not condition():
        if time.monotonic() > end:
            raise AssertionError(f"gave up waiting for {what}")
        time.sleep(0.05)


def alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie, killed and not yet reaped, does not)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state not in ("Z", "X")


def killed_and_resumed(argv, out: Path, stored, at_least: int = 1, signum=None) -> subprocess.Popen:
    """Run ``surrealist ARGV`` in a process of its own until ``stored()`` (what its folder ``out`` holds) reaches
    ``at_least``, then kill it (SIGKILL unless ``signum``) and wait for its end; returns the process (its stderr
    read). The caller resumes with the same command."""
    import os
    import signal
    import sys

    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    process = subprocess.Popen([sys.executable, "-m", "surrealist_gym.cli", *map(str, argv)], env=env, cwd=ROOT,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    until(lambda: stored() >= at_least or process.poll() is not None, f"{at_least} result(s) stored in {out}")
    assert process.poll() is None, f"it ended before it was killed: {process.communicate()[1]}"
    process.send_signal(signal.SIGKILL if signum is None else signum)
    process.communicate(timeout=120)
    assert process.returncode != 0
    return process


def fly_the_python_outer_loop(mp: pytest.MonkeyPatch) -> None:
    """Let the compiled physics fly ``runner._fly_compiled_outer``, the compiled loop's bit-identical reference, which
    calls the Python classes (the navigator, both planners, the tree) that the compiled loop runs as kernels: for
    tests that record or swap those classes."""
    from surrealist_gym.sim import runner

    mp.setattr(runner, "_fly_compiled", runner._fly_compiled_outer)


def sigint_as_a_terminal_gives_it() -> None:
    """``Popen(preexec_fn=...)``: the child takes SIGINT as Ctrl-C (KeyboardInterrupt), even when these tests run as a
    background job, whose children inherit SIGINT ignored (and Python keeps an ignored SIGINT ignored)."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_DFL)


#: Three CAMBA tests that fly quickly (about 0.6 s a run each).
CAMBA_FAST = ("26-11-13-35-31-5O9PN", "04-12-14-10-41-5O9PN", "24-11-07-48-39-5O9PN")


@pytest.fixture(scope="module")
def camba_fast_folder(tmp_path_factory) -> Path:
    """A folder ``tests/`` holding the three CAMBA_FAST tests, with ``case_studies/`` beside it (their
    ``mission_file`` is relative)."""
    import shutil

    competition = SHARED_DATA / "competition"
    if not competition.is_dir():
        pytest.skip(_MISSING)
    root = tmp_path_factory.mktemp("suite")
    shutil.copytree(competition / "case_studies", root / "case_studies")
    (root / "tests").mkdir()
    for name in CAMBA_FAST:
        shutil.copy(competition / "camba-collection" / f"{name}.yaml", root / "tests")
    return root / "tests"


_SHARED_PATHS = (SHARED_DATA, EXPERIMENTS, FORMATS, CASE0_ULG, REFERENCE_CSV, CASE_STUDIES)
_MISSING = f"needs the shared data folder {SHARED_DATA} (clone the project beside ../shared)"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip(_MISSING)
    return SHARED_DATA


def pytest_collection_modifyitems(config, items):
    """Without ../shared, the tests that read it (through the fixture or a path imported from here) skip with the
    reason; the others still run."""
    if SHARED_DATA.is_dir():
        return
    skip = pytest.mark.skip(reason=_MISSING)
    for item in items:
        module = vars(getattr(item, "module", None) or object())
        if "shared_data" in item.fixturenames or any(isinstance(v, Path) and v in _SHARED_PATHS
                                                     for v in module.values()):
            item.add_marker(skip)
