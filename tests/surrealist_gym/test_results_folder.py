"""``results.ResultsFolder``: made, refused when it holds something else, locked by one writer (a dead writer's lock
taken over, even while a process it forked holds the file), resumed with the same settings and refused with others,
kept on failure once its store holds a row. Real files, real flock, real SQLite, real processes."""
import json
import os
import sqlite3
import subprocess
import sys

import pytest

from surrealist_gym.errors import SurrealistError
from surrealist_gym.results import ResultsFolder
from tests.conftest import alive, until


def test_a_new_folder_records_its_settings_and_the_same_claim_resumes_it(tmp_path):
    out = tmp_path / "out"
    first = ResultsFolder.claim(out, "evaluate", {"runs": 2, "workers": 1}, free=("workers",))
    assert first.fresh and not first.resumed
    assert json.loads((out / "run.json").read_text()) == {"command": "evaluate", "runs": 2, "workers": 1}
    first.release()
    again = ResultsFolder.claim(out, "evaluate", {"runs": 2, "workers": 4}, free=("workers",))
    assert again.resumed and again.settings == {"runs": 2, "workers": 1}
    again.release()
    with pytest.raises(SurrealistError, match=r"holds a evaluate run with other settings \(runs: 2 there, 3 here\)"):
        ResultsFolder.claim(out, "evaluate", {"runs": 3, "workers": 1})
    (out / ".lock").unlink()
    with pytest.raises(SurrealistError, match="holds 'evaluate' run, not a run of compete"):
        ResultsFolder.claim(out, "compete", {"runs": 2})
    assert sorted(p.name for p in out.iterdir()) == ["run.json"]  # a folder refused is left as it was


def test_a_folder_holding_something_else_is_refused_and_left_as_it_is(tmp_path):
    (tmp_path / "notes.txt").write_text("mine\n")
    with pytest.raises(SurrealistError, match=r"holds something else \(notes.txt\), not a run of fidelity"):
        ResultsFolder.claim(tmp_path, "fidelity", {"runs": 1})
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]  # nothing written in it
    afile = tmp_path / "notes.txt"
    with pytest.raises(SurrealistError, match="exists and is not a folder"):
        ResultsFolder.claim(afile, "fidelity", {"runs": 1})


def test_a_fresh_folder_is_removed_on_failure_unless_it_stores_a_row(tmp_path):
    empty = ResultsFolder.claim(tmp_path / "empty", "generate", {"budget": 1})
    with pytest.raises(SurrealistError, match=r"cannot write \(disk full\); nothing was stored, so .* is removed"):
        with empty.keeping("--resume it"):
            raise OSError(28, "disk full")
    assert not (tmp_path / "empty").exists()
    kept = ResultsFolder.claim(tmp_path / "kept", "generate", {"budget": 1})
    with pytest.raises(SurrealistError, match=r"1 evaluation\(s\) are stored in .*kept: --resume it"):
        with kept.keeping("--resume it", "evaluation(s)"):
            with sqlite3.connect(kept.path / "evaluations.sqlite") as db:
                db.execute("CREATE TABLE evaluations (id INTEGER)")
                db.execute("INSERT INTO evaluations VALUES (1)")
            raise OSError(28, "disk full")
    assert (tmp_path / "kept" / "evaluations.sqlite").is_file()


def test_one_writer_and_the_lock_of_a_killed_writer_is_taken_over(tmp_path):
    out = tmp_path / "out"
    holder = ResultsFolder.claim(out, "compare", {"budget": 1})
    with pytest.raises(SurrealistError, match=f"another process \\(process {os.getpid()}\\) is writing"):
        ResultsFolder.claim(out, "compare", {"budget": 1})
    holder.release()
    # a writer that locks the folder, forks a worker (which inherits the lock) and is killed: the worker lives on
    script = ("import os, sys, time\n"
              "from surrealist_gym.results import ResultsFolder\n"
              "ResultsFolder.claim(sys.argv[1], 'compare', {'budget': 1})\n"
              "if os.fork() == 0:\n"
              "    open(sys.argv[2], 'w').write(str(os.getpid()))\n"
              "    time.sleep(60)\n"
              "    os._exit(0)\n"
              "time.sleep(60)\n")
    worker_file = tmp_path / "worker.pid"
    writer = subprocess.Popen([sys.executable, "-c", script, str(out), str(worker_file)],
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    try:
        until(lambda: worker_file.is_file() and worker_file.read_text(), "the writer's worker")
        worker = int(worker_file.read_text())
        writer.kill()
        writer.wait()
        assert alive(worker)  # it still holds the lock file the killed writer opened
        taken = ResultsFolder.claim(out, "compare", {"budget": 1})
        assert (out / ".lock").read_text().strip() == str(os.getpid())
        taken.release()
    finally:
        writer.kill()
        if worker_file.is_file():
            try:
                os.kill(int(worker_file.read_text()), 9)
            except (ProcessLookupError, ValueError):
                pass
