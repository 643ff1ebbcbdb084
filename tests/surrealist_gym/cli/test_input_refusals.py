"""The command line's refusals of issue 44: one ``error:`` line naming the file and field, exit 2, nothing written,
nothing lost, before any work; and Ctrl-C with workers is one message. Real files and the real command line."""
from __future__ import annotations

import hashlib
import os
import resource
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import surrealist_gym as sg
from surrealist_gym.cli import main
from tests.conftest import CASE_STUDIES, ROOT, SHARED_DATA, refused, sigint_as_a_terminal_gives_it

DATA = Path(sg.data_path("case0.plan")).parent
STORE = ROOT / "tests" / "data" / "stores" / "rq2-rep0.sqlite"
SEED_FILES = ("rq2-seed.yaml", "auto1.plan", "auto1-params.csv", "auto-commands.csv")


def _digest(folder: Path) -> dict:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else None
            for p in sorted(folder.rglob("*"))}


@pytest.fixture
def work(tmp_path, monkeypatch) -> Path:
    for name in SEED_FILES:
        shutil.copy(DATA / name, tmp_path / name)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("value, says", [("etc/passwd", "not found"), ("/etc/passwd", "lies outside"),
                                         ("/proc/self/environ", "lies outside"), ("/proc/kmsg", "lies outside")])
def test_simulate_refuses_what_a_test_should_not_read(work, capsys, value, says):
    text = (work / "rq2-seed.yaml").read_text().replace("experiments/auto1-params.csv", value)
    (work / "t.yaml").write_text(text)
    line = refused(capsys, ["simulate", "t.yaml", "--runs", "1", "--no-plot", "--out", "out"], "params_file",
                   value, says)
    assert "root:" not in line and not (work / "out").exists()


def test_allow_outside_lets_a_test_read_there(work, capsys, tmp_path_factory):
    elsewhere = tmp_path_factory.mktemp("elsewhere")
    shutil.move(work / "auto1-params.csv", elsewhere / "auto1-params.csv")
    text = (work / "rq2-seed.yaml").read_text().replace("experiments/auto1-params.csv",
                                                         str(elsewhere / "auto1-params.csv"))
    (work / "t.yaml").write_text(text)
    argv = ["simulate", "t.yaml", "--runs", "1", "--no-plot", "--no-ulog", "--no-reference", "--out", "out"]
    refused(capsys, argv, "params_file", "--allow-outside")
    refused(capsys, argv + ["--allow-outside", str(elsewhere / "missing")], "--allow-outside", "not found")
    assert main(argv + ["--allow-outside", str(elsewhere)]) == 0
    assert (work / "out").is_dir() and "SURREALIST_ALLOW_OUTSIDE" not in os.environ  # for this command only


def test_a_huge_csv_field_is_refused_by_replicate_before_its_run_file(work, capsys):
    (work / "auto1-params.csv").write_text("MPC_XY_CRUISE, " + "1" * 140_000 + "\n")
    refused(capsys, ["replicate", DATA / "case0.ulg", "--seed", "rq2-seed.yaml", "--budget", "1", "--runs", "1",
                     "--workers", "1", "--out", "out"], "params_file", "auto1-params.csv", "field limit")
    assert not (work / "out").exists()


def test_three_thousand_boxes_answer(work):
    boxes = "".join(f"    - {{size: {{l: 1, w: 1, h: 1}}, position: {{x: {3 * (k % 60)}, y: {3 * (k // 60)}}}}}\n"
                    for k in range(3000))
    boxes += "    - {size: {l: 1, w: 1, h: 1}, position: {x: 0.5, y: 0.5}}\n"
    text = (work / "rq2-seed.yaml").read_text()
    head, _, _ = text.partition("  obstacles:")
    (work / "t.yaml").write_text(head + "  obstacles:\n" + boxes)
    done = subprocess.run([sys.executable, "-m", "surrealist_gym.cli", "simulate", "t.yaml", "--runs", "1",
                           "--out", "out"], cwd=work, capture_output=True, text=True, timeout=60)  # a hang guard
    assert done.returncode == 2 and "obstacles[0] and obstacles[3000] overlap" in done.stderr, done.stderr
    assert not (work / "out").exists()


def test_evaluate_refuses_one_folder_under_two_names(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t").mkdir()
    shutil.copytree(CASE_STUDIES, tmp_path / "case_studies")
    shutil.copy(next(iter(sorted((SHARED_DATA / "competition" / "camba-collection").glob("*.yaml")))), tmp_path / "t")
    (tmp_path / "link").symlink_to("t")
    refused(capsys, ["evaluate", "t", "link", "--runs", "1", "--workers", "1", "--competition", "2025", "--out",
                     "out"], "link", "same folder")
    assert not (tmp_path / "out").exists()


def test_export_tool_refuses_a_dangling_link(tmp_path, capsys):
    (tmp_path / "tool").symlink_to(tmp_path / "nowhere")
    refused(capsys, ["export-tool", tmp_path / "tool"], "tool", "does not exist")
    assert sorted(os.listdir(tmp_path)) == ["tool"] and not (tmp_path / "nowhere").exists()


def _small_files():
    sigint_as_a_terminal_gives_it()
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails (EFBIG) instead of killing
    resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))


def test_export_tool_on_a_full_disk_leaves_nothing(tmp_path):
    env = {**os.environ, "SURREALIST_CASE_STUDIES": str(CASE_STUDIES)}
    done = subprocess.run([sys.executable, "-m", "surrealist_gym.cli", "export-tool", "a/b/tool"], cwd=tmp_path,
                          env=env, capture_output=True, text=True, timeout=120, preexec_fn=_small_files)
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == 2 and len(errors) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "cannot write the tool" in errors[0] and os.listdir(tmp_path) == []


def test_surrogate_train_keeps_an_existing_model(tmp_path, capsys):
    model = tmp_path / "model"
    argv = ["surrogate", "train", STORE, "--problem", "generate", "--kind", "knn", "--out", model]
    argv = [str(a) for a in argv]
    assert main(argv) == 0
    before = _digest(model)
    refused(capsys, argv + ["--k", "3"], "--out", "holds a model already", "--overwrite")
    assert _digest(model) == before
    assert main(argv + ["--k", "3", "--overwrite"]) == 0 and _digest(model) != before


def test_surrogate_train_reads_a_store_given_twice_once(tmp_path, capsys):
    (tmp_path / "a.sqlite").write_bytes(STORE.read_bytes())
    (tmp_path / "b.sqlite").symlink_to(tmp_path / "a.sqlite")
    refused(capsys, ["surrogate", "train", tmp_path / "a.sqlite", tmp_path / "b.sqlite", "--problem", "generate",
                     "--kind", "knn", "--holdout", "1", "--out", tmp_path / "model"], "--holdout", "given: 1")
    assert not (tmp_path / "model").exists() and (tmp_path / "a.sqlite").read_bytes() == STORE.read_bytes()


def test_train_keeps_an_existing_policy(tmp_path, capsys):
    (tmp_path / "p.zip").write_bytes(b"PK not really")
    refused(capsys, ["train", "--steps", "1", "--episode-budget", "2", "--problem", "generate", "--policy",
                     tmp_path / "p.zip"], "p.zip", "holds a policy already", "--overwrite")
    assert (tmp_path / "p.zip").read_bytes() == b"PK not really"


def test_ctrl_c_with_two_workers_is_one_message(tmp_path):
    process = subprocess.Popen([sys.executable, "-m", "surrealist_gym.cli", "replicate", str(DATA / "case0.ulg"),
                                "--budget", "200", "--runs", "2", "--workers", "2", "--out", "out"], cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                               preexec_fn=sigint_as_a_terminal_gives_it)
    deadline = time.monotonic() + 60
    while not list(tmp_path.glob("out/*.sqlite")) and time.monotonic() < deadline:  # the workers are flying
        time.sleep(0.2)
    time.sleep(1.0)
    os.killpg(process.pid, signal.SIGINT)  # as the terminal sends it: to the command and its workers
    time.sleep(0.02)
    os.killpg(process.pid, signal.SIGINT)  # an impatient second Ctrl-C does not cut the clean-up short
    _, err = process.communicate(timeout=60)
    assert process.returncode == 130, err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert len([line for line in err.splitlines() if line.startswith("interrupted")]) == 1, err


def _pid() -> int:
    return os.getpid()


def _pid_of(*_) -> int:
    return os.getpid()


def test_pool_workers_leave_ctrl_c_to_the_parent():
    from surrealist_gym.executors import LocalPoolExecutor

    executor = LocalPoolExecutor(workers=1)
    try:
        executor.submit(_pid_of, None, [], 0, None).result()  # starts the pool with its initializer
        pid = executor._pool.submit(_pid).result(timeout=60)
        os.kill(pid, signal.SIGINT)  # what the terminal sends the whole group on Ctrl-C
        time.sleep(0.5)
        assert executor._pool.submit(_pid).result(timeout=60) == pid  # the worker lives on, without a traceback
    finally:
        executor.abandon()
