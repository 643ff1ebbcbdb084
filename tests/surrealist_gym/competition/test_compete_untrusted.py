"""``surrealist compete`` treats a tool as untrusted code: real tool folders built in tmp_path (links out, loops,
FIFOs), a hostile tool speaking to the real server (bad fields, pickles, a wrong key, files outside its folder, a
file whose content must not come back), its resource limits and process group, a second compete on one ``--out``,
and SIGTERM to compete. The real Aerialist (master) and the real simulator; nothing of third_party is touched."""
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
from surrealist_gym.competition.compete import prepare, run
from surrealist_gym.competition.compete.locate import AERIALIST_ENV
from surrealist_gym.competition.compete.process import ToolLimits
from surrealist_gym.competition.compete.toolcopy import copy_folder
from surrealist_gym.errors import SurrealistError
from tests.conftest import alive, until

ROOT = Path(__file__).resolve().parents[3]
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
SNIPPETS = THIRD_PARTY / "uav-testing-competition" / "snippets"
MASTER = THIRD_PARTY / "aerialist-master"

if not SNIPPETS.is_dir() or not MASTER.is_dir():
    pytest.skip(f"needs the competition's reference tool and Aerialist master in {THIRD_PARTY}",
                allow_module_level=True)
for _module in ("munch", "decouple", "ruptures", "requests", "webdav4"):
    pytest.importorskip(_module, reason=f"{_module}: pip install -e '.[compete]' (Aerialist's imports)")

HEAD = '''\
import os, sys, time
from aerialist.px4.aerialist_test import AerialistTest
from aerialist.px4.docker_agent import DockerAgent
from aerialist.px4.obstacle import Obstacle

test = AerialistTest.from_yaml(sys.argv[2])
test.simulation.obstacles = [Obstacle(Obstacle.Size(10, 5, 20), Obstacle.Position(-5, 25, 0, 0))]
'''


@pytest.fixture(autouse=True)
def aerialist_folder(monkeypatch):
    monkeypatch.setenv(AERIALIST_ENV, str(MASTER))
    monkeypatch.delenv("AGENT", raising=False)


def _tool(tmp_path, body: str, name: str = "tool", head: str = HEAD) -> Path:
    folder = tmp_path / name
    (folder / "case_studies").mkdir(parents=True)
    for file in ("mission1.yaml", "mission1.plan", "mission-params.csv", "mission-commands.csv"):
        (folder / "case_studies" / file).write_bytes((SNIPPETS / "case_studies" / file).read_bytes())
    (folder / "cli.py").write_text(head + body, encoding="utf-8")
    return folder


def _refused(capsys, argv, *expected: str) -> None:
    """Exit code 2 and exactly one line on stderr, ``error: ...`` holding each of ``expected``; no traceback."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and all(e in lines[0] for e in expected), err


# --- the tool's folder ----------------------------------------------------------------------------------------------
def test_links_out_of_the_folder_and_loops_are_refused_before_anything_is_written(tmp_path, capsys):
    secret = tmp_path / "secret.txt"
    secret.write_text("SECRET-LINE\n")
    cases = [("etc", "/etc", "is a link to /etc, outside the tool's folder"),
             ("case_studies/key.csv", str(secret), "outside the tool's folder"),
             ("up", "..", "outside the tool's folder"),
             ("loop", ".", "a folder that holds it (a loop)"),
             ("case_studies/back", "..", "a folder that holds it (a loop)"),
             ("dangling", "nowhere", "a broken link or a loop of links")]
    for i, (link, target, expected) in enumerate(cases):
        tool = _tool(tmp_path, "", f"tool{i}")
        os.symlink(target, tool / link)
        _refused(capsys, ["compete", str(tool), "mission1", "1", "--out", str(tmp_path / f"out{i}")],
                 f"tool {tool}: {link} is a", expected)
        with pytest.raises(SurrealistError, match=expected.replace("(", r"\(").replace(")", r"\)")):
            prepare(tool, "mission1", 1, tmp_path / f"out{i}")
        assert not (tmp_path / f"out{i}").exists()
    fifo = _tool(tmp_path, "", "fifo")
    os.mkfifo(fifo / "pipe")
    _refused(capsys, ["compete", str(fifo), "mission1", "1", "--out", str(tmp_path / "out-fifo")],
             "pipe is not a file, folder or link")
    assert not (tmp_path / "out-fifo").exists()


def test_links_inside_the_folder_are_copied_as_links_inside_the_copy(tmp_path):
    tool = _tool(tmp_path, "")
    (tool / "lib").mkdir()
    (tool / "lib" / "helper.py").write_text("X = 1\n")
    os.symlink("lib", tool / "lib-link")
    os.symlink(str(tool / "lib" / "helper.py"), tool / "case_studies" / "helper.py")  # absolute, inside
    (tool / ".venv" / "bin").mkdir(parents=True)
    os.symlink(sys.executable, tool / ".venv" / "bin" / "python")  # a tool's own venv: left out
    copy_folder(tool, tmp_path / "copy")
    copy = tmp_path / "copy"
    assert os.readlink(copy / "lib-link") == "lib"
    assert os.readlink(copy / "case_studies" / "helper.py") == os.path.join("..", "lib", "helper.py")
    assert (copy / "case_studies" / "helper.py").resolve() == (copy / "lib" / "helper.py").resolve()
    assert not (copy / ".venv").exists() and (copy / "cli.py").read_bytes() == (tool / "cli.py").read_bytes()


# --- a hostile tool against the server ------------------------------------------------------------------------------
HOSTILE = '''
import importlib, json, pickle, resource, shutil, socket, struct
shim = importlib.import_module("surrealist_compete_shim")  # the shim's own, from the PYTHONPATH compete gives
wire = importlib.import_module("surrealist_compete_wire")

said = {"pgid_is_pid": os.getpgid(0) == os.getpid(), "sid_is_pid": os.getsid(0) == os.getpid(),
        "as": resource.getrlimit(resource.RLIMIT_AS)[0], "fsize": resource.getrlimit(resource.RLIMIT_FSIZE)[0],
        "cpu": resource.getrlimit(resource.RLIMIT_CPU)[0]}
try:
    with open("big.bin", "wb") as f:
        f.truncate(40 * 2 ** 20)
    said["big_write"] = "written"
except OSError as err:
    said["big_write"] = type(err).__name__
doc = test.to_dict()
doc.pop("assertion", None); doc.pop("agent", None)
doc = shim._plain(doc)
base = {"op": "fly", "agent": "DockerAgent", "api": "AerialistTest", "cwd": os.getcwd(), "test": doc, "runs": 1}
replies = {}
for name, change in [("runs -5", {"runs": -5}), ("runs 0", {"runs": 0}), ("runs str", {"runs": "1"}),
                     ("runs true", {"runs": True}), ("runs 10**30", {"runs": 10 ** 30}), ("agent", {"agent": "x"}),
                     ("op", {"op": "exec"}), ("extra", {"code": "import os"}), ("cwd", {"cwd": 5}),
                     ("test", {"test": [1]})]:
    replies[name] = shim._ask({**base, **change})
for name, params in [("outside", os.environ["SECRET_FILE"]), ("inside", "secret-inside.csv"),
                     ("passwd", "/etc/passwd")]:
    with open("secret-inside.csv", "w") as f:
        f.write("SECRET-INSIDE: not, a, params, file\\n")
    bad = json.loads(json.dumps(doc))
    bad["robot" if "robot" in bad else "drone"]["params_file"] = params
    replies[name] = shim._ask({**base, "test": bad})

def raw(payload, hello=True):
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    conn.connect(os.environ["SURREALIST_COMPETE_ADDRESS"])
    key = os.environ["SURREALIST_COMPETE_AUTHKEY"] if hello else "00" * 32
    wire.send(conn, {"op": "hello", "key": key})
    if hello:
        wire.receive(conn)
    try:
        conn.sendall(payload)
        conn.shutdown(socket.SHUT_WR)  # a message cut short: the server must not wait on
        return conn.recv(100)
    except OSError as err:
        return type(err).__name__.encode()
    finally:
        conn.close()

data = pickle.dumps({"op": "fly"})
replies["pickle"] = raw(struct.pack(">I", len(data)) + data).decode("latin-1")
replies["cut"] = raw(struct.pack(">I", 100) + b"{").decode("latin-1")
replies["huge"] = raw(struct.pack(">I", 2 ** 31)).decode("latin-1")
replies["wrong key"] = raw(b"", hello=False).decode("latin-1")
flown = DockerAgent(test).run()
said["flown"] = len(flown)
os.makedirs("out")
test.to_yaml("out/test_0.yaml")
shutil.copy(flown[0].log_file, "out/test_0.ulg")
test.to_yaml("out/test_1.yaml")
with open("out/test_1.ulg", "wb") as f:
    f.truncate(int(os.environ["SPARSE_BYTES"]))  # a sparse ULog larger than compete reads
os.symlink("/etc/passwd", "out/test_2.yaml")
print("said:", json.dumps(said))
print("replies:", json.dumps(replies))
print("output folder: out")
'''


def test_a_hostile_tool_gets_one_line_refusals_and_no_file_content(tmp_path, monkeypatch):
    from surrealist_gym.competition.compete import tool as tool_module

    secret = tmp_path / "secret.csv"
    secret.write_text("SECRET-OUTSIDE: not, a, params, file\n")
    monkeypatch.setenv("SECRET_FILE", str(secret))
    monkeypatch.setattr(tool_module, "MAX_READ_BYTES", 16 * 2 ** 20)  # a smaller limit, as cheap to test
    monkeypatch.setenv("SPARSE_BYTES", str(16 * 2 ** 20 + 1))
    tool = _tool(tmp_path, HOSTILE)
    limits = ToolLimits(file_gb=1 / 32)  # 32 MB: the tool's 40 MB file fails
    result = run(prepare(tool, "mission1", 2, tmp_path / "out", limits=limits))
    assert result.problem is None, result.problem
    printed = (tmp_path / "out" / "tool-stdout.txt").read_text()
    said = json.loads(printed.split("said: ", 1)[1].splitlines()[0])
    replies = json.loads(printed.split("replies: ", 1)[1].splitlines()[0])
    assert said["pgid_is_pid"] and said["sid_is_pid"] and said["flown"] == 1
    assert said["as"] == 8 * 2 ** 30 and said["fsize"] == 2 ** 25 and said["cpu"] == int(1.5 * 7200)
    assert said["big_write"] == "OSError" and (tmp_path / "out" / "tool" / "big.bin").stat().st_size == 0
    for name in ("runs -5", "runs 0", "runs str", "runs true", "runs 10**30"):
        assert replies[name] == {"ok": False, "error": replies[name]["error"]}
        assert replies[name]["error"].startswith("bad request: field 'runs': expected a whole number from 1 to "
                                                 "the budget (2)"), replies[name]
    for name, field in (("agent", "agent"), ("op", "op"), ("cwd", "cwd"), ("test", "test")):
        assert replies[name]["error"].startswith(f"bad request: field {field!r}"), replies[name]
    assert replies["extra"]["error"] == "bad request: unknown field 'code'"
    for name in ("outside", "passwd"):
        assert replies[name]["error"] == "the test cannot be flown: its field 'params_file' names a file outside " \
                                         "the tool's folder"
    assert replies["inside"]["ok"] is False and "SECRET" not in replies["inside"]["error"]
    for name in ("pickle", "cut", "huge", "wrong key"):  # the connection dropped, unanswered
        assert replies[name] in ("", "ConnectionResetError", "BrokenPipeError"), (name, replies[name])
    records = (tmp_path / "out" / "flights.csv").read_text() + (tmp_path / "out" / "summary.json").read_text()
    assert "SECRET" not in records and "root:" not in records
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["simulations"] == 1 and result.spent == 1 and summary["refused"] == 0
    rows = list(csv.DictReader(open(tmp_path / "out" / "flights.csv", encoding="utf-8")))
    assert [r["error"].split(":")[0] for r in rows][:10] == ["bad request"] * 10 and rows[-1]["error"] == ""
    assert [t.name for t in result.tests] == ["test_0", "test_1"]  # the linked test_2.yaml is not the tool's
    assert result.tests[0].distance is not None
    assert result.tests[1].distance is None and "over the" in result.tests[1].note and "not read" in \
        result.tests[1].note


# --- the tool's process ---------------------------------------------------------------------------------------------
def _compete(tool: Path, out: Path, *extra: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    return subprocess.Popen([sys.executable, "-m", "surrealist_gym.cli", "compete", str(tool), "mission1", "1",
                             "--out", str(out), *extra], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


PLAIN = "import os, subprocess, sys, time\n"
WAITING = '''
import subprocess
child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
with open("pids.txt", "w") as f:
    f.write(f"{os.getpid()} {child.pid}")
while not os.path.exists(os.environ["GO_FILE"]):
    time.sleep(0.1)
DockerAgent(test).run()
print("output folder: ./")
'''


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_signal_to_compete_ends_the_tool_and_its_children(tmp_path, monkeypatch, signum):
    """SIGTERM: compete stops the tool's group; kill -9: the tool's watchdog ends the group (its child too, which
    no PR_SET_PDEATHSIG reaches)."""
    monkeypatch.setenv("GO_FILE", str(tmp_path / "never"))
    tool = _tool(tmp_path, WAITING.replace("DockerAgent(test).run()", ""), head=PLAIN)
    out = tmp_path / "out"
    compete = _compete(tool, out)
    pids_file = out / "tool" / "pids.txt"
    until(lambda: pids_file.is_file() and len(pids_file.read_text().split()) == 2, "the tool to start")
    pids = [int(p) for p in pids_file.read_text().split()]
    assert all(alive(p) for p in pids)
    compete.send_signal(signum)
    compete.communicate(timeout=120)
    assert compete.returncode != 0
    until(lambda: not any(alive(p) for p in pids), "the tool's processes to end")


def test_a_second_compete_on_one_out_is_refused_and_the_first_goes_on(tmp_path, monkeypatch, capsys):
    go = tmp_path / "go"
    monkeypatch.setenv("GO_FILE", str(go))
    tool = _tool(tmp_path, WAITING)
    out = tmp_path / "out"
    second_plan = prepare(tool, "mission1", 1, out)  # checked before the first made the folder: the race
    first = _compete(tool, out)
    until(lambda: (out / "tool" / "pids.txt").is_file(), "the first tool to start")
    before = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    _refused(capsys, ["compete", str(tool), "mission1", "1", "--out", str(out)],
             f"--out {out}: another process (process {first.pid}) is writing to this folder")
    with pytest.raises(SurrealistError, match="another process .* is writing to this folder"):
        run(second_plan)
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == before
    go.touch()
    stdout, stderr = first.communicate(timeout=300)
    assert first.returncode == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["simulations"] == 1 and summary["problem"] is None


def test_a_tool_past_its_time_limit_is_stopped(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("GO_FILE", str(tmp_path / "never"))
    tool = _tool(tmp_path, WAITING.replace("DockerAgent(test).run()", ""), head=PLAIN)
    assert main(["compete", str(tool), "mission1", "1", "--out", str(tmp_path / "out"), "--tool-timeout", "5"]) == 2
    assert "the tool ran past its time limit of 5 s and was stopped" in capsys.readouterr().err
    pids = [int(p) for p in (tmp_path / "out" / "tool" / "pids.txt").read_text().split()]
    until(lambda: not any(alive(p) for p in pids), "the tool's processes to end")
