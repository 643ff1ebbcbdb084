"""``surrealist compete`` killed mid-run (SIGKILL, SIGTERM) keeps every flight it stored, takes its tool's process
group with it, and the same command resumes: the tool starts again, each simulation flown before is answered from
``flights.sqlite`` unflown, and the run ends with the flights, summary and scores of an uninterrupted one. The
competition's reference tool (third_party, run in a copy), the real Aerialist (master), the real simulator."""
from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from surrealist_gym.cli import main
from surrealist_gym.competition.compete.locate import AERIALIST_ENV
from surrealist_gym.results import count_rows
from tests.conftest import ROOT, alive, until

THIRD_PARTY = ROOT.parent / "shared" / "third_party"
SNIPPETS = THIRD_PARTY / "uav-testing-competition" / "snippets"
MASTER = THIRD_PARTY / "aerialist-master"
BUDGET = "5"

if not SNIPPETS.is_dir() or not MASTER.is_dir():
    pytest.skip(f"needs the competition's reference tool and Aerialist master in {THIRD_PARTY}",
                allow_module_level=True)
for _module in ("munch", "decouple", "ruptures", "requests", "webdav4"):
    pytest.importorskip(_module, reason=f"{_module}: pip install -e '.[compete]' (Aerialist's imports)")


@pytest.fixture(autouse=True)
def aerialist_folder(monkeypatch):
    monkeypatch.setenv(AERIALIST_ENV, str(MASTER))
    monkeypatch.delenv("AGENT", raising=False)


def _argv(out: Path) -> list[str]:
    return ["compete", str(SNIPPETS), "mission1", BUDGET, "--out", str(out)]


def flights(out: Path) -> list[dict]:
    """flights.csv without its timings."""
    with open(out / "flights.csv", newline="", encoding="utf-8") as f:
        return [{k: v for k, v in row.items() if k != "wall_s"} for row in csv.DictReader(f)]


def figures(out: Path) -> dict:
    """What summary.json says of the run, without times and the names the tool gives by the clock."""
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return {"simulations": summary["simulations"], "refused": summary["refused"], "problem": summary["problem"],
            "requests": summary["requests"],
            "tests": [(t["competition_distance"], t["points"], t["flight"]) for t in summary["tests"]]}


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("full") / "out"
    mp = pytest.MonkeyPatch()
    mp.setenv(AERIALIST_ENV, str(MASTER))
    try:
        assert main(_argv(out)) == 0
    finally:
        mp.undo()
    return out


def _tool_processes(out: Path) -> list[int]:
    """The processes running in the tool's copy (the tool, the processes it started, its watchdog)."""
    work = str(out / "tool")
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if os.readlink(entry / "cwd").startswith(work):
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
def test_killed_compete_resumes_to_the_uninterrupted_result(tmp_path, uninterrupted, capsys, signum):
    out = tmp_path / "out"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    compete = subprocess.Popen([sys.executable, "-m", "surrealist_gym.cli", *_argv(out)], env=env,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    until(lambda: count_rows(out / "flights.sqlite", "flights") >= 2 or compete.poll() is not None,
          "two flights stored")
    assert compete.poll() is None, compete.communicate()[1]
    tool = _tool_processes(out)
    assert tool, "the tool runs"
    compete.send_signal(signum)
    compete.communicate(timeout=120)
    assert compete.returncode != 0
    until(lambda: not any(alive(p) for p in tool), "the tool's processes to end with compete")
    kept = count_rows(out / "flights.sqlite", "flights")
    assert kept >= 2 and not (out / "summary.json").exists()

    # the same command resumes; the lock the killed compete held does not stand in the way
    assert main(_argv(out)) == 0
    printed = capsys.readouterr().out
    assert f"resumed: {kept} of them read back from {out / 'flights.sqlite'}" in printed, printed
    assert flights(out) == [{**row, "test_file": row["test_file"].replace(str(uninterrupted), str(out))}
                            for row in flights(uninterrupted)]
    assert figures(out) == figures(uninterrupted)


def test_a_resume_with_other_settings_is_refused(uninterrupted, capsys):
    before = sorted(p.name for p in uninterrupted.iterdir())
    assert main(["compete", str(SNIPPETS), "mission1", "6", "--out", str(uninterrupted)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"error: --out {uninterrupted}: holds a compete run with other settings (budget: 5 there, 6 "
                       f"here); resume it with the same settings, or choose another folder")
    assert sorted(p.name for p in uninterrupted.iterdir()) == before
