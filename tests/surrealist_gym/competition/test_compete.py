"""``surrealist compete``: the competition's real tools (third_party), the real Aerialist code (0.2.1 and master) and
the real simulator, end to end; the budget; Aerialist's own distances against ours on the same ULogs; one-line
errors; a tool that deletes each run's files and folder (each agent.run() hands it a folder of its own,
``results/logs/<id>/``, and compete's record lies elsewhere), and refusals that name the file and field. Every tool
runs in a copy inside tmp_path, so nothing of theirs is touched."""
from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from surrealist_gym.aerialist import load_test
from surrealist_gym.cli import main
from surrealist_gym.competition.compete import prepare, run, tool_environment
from surrealist_gym.competition.compete.locate import AERIALIST_ENV, find_aerialist, tool_apis
from surrealist_gym.errors import DependencyNotInstalled, SurrealistError
from surrealist_gym.geometry import competition_distances
from surrealist_gym.logs import read_flight
from surrealist_gym.trajectory import Trajectory

ROOT = Path(__file__).resolve().parents[3]
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
SNIPPETS = THIRD_PARTY / "uav-testing-competition" / "snippets"
AMBIEGEN = THIRD_PARTY / "peers" / "ambiegen" / "snippets"
MASTER = THIRD_PARTY / "aerialist-master"
LEGACY = THIRD_PARTY / "aerialist-0.2.1"
AERIALIST_PATH = os.pathsep.join(str(p) for p in (MASTER, LEGACY))

if not THIRD_PARTY.is_dir():
    pytest.skip(f"needs the competition's tools and Aerialist in {THIRD_PARTY}", allow_module_level=True)
for _module in ("munch", "decouple", "ruptures", "requests", "webdav3", "webdav4", "pymoo"):
    pytest.importorskip(_module, reason=f"{_module}: pip install -e '.[compete,compete-tools]' (Aerialist's imports, "
                                        f"AmbieGen's pymoo)")


@pytest.fixture(autouse=True)
def aerialist_folders(monkeypatch):
    """Both Aerialist generations, as the README's set-up exports them; AGENT left to each test."""
    monkeypatch.setenv(AERIALIST_ENV, AERIALIST_PATH)
    monkeypatch.delenv("AGENT", raising=False)


def _one_line(capsys) -> str:
    """The last line on stderr (after the progress bar), with no traceback anywhere."""
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err.strip().splitlines()[-1]


def _check_output_folder(result, budget: int) -> None:
    """The tool's output folder holds a yaml, ulg and png per test, each ULog one the server flew."""
    assert result.output_folder is not None and result.output_folder.is_dir()
    assert result.output_folder.is_relative_to(result.plan.out / "tool")
    assert result.tests, "the tool wrote no test"
    for test in result.tests:
        assert test.yaml.is_file() and test.ulg is not None and test.png is not None
        assert test.png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert test.flight is not None and test.distance is not None and test.points in (0, 1, 2, 5)
    assert 1 <= result.spent <= budget and result.spent == sum(len(f.statuses) for f in result.flights)
    summary = json.loads((result.plan.out / "summary.json").read_text())
    assert summary["simulations"] == result.spent and len(summary["tests"]) == len(result.tests)
    assert (result.plan.out / "flights.csv").read_text().count("\n") == len(result.flights) + 1


def _aerialist_distances(result, module: str) -> list[list[float]]:
    """Each written test's distances by the tool's own ``TestCase.get_distances()`` on Aerialist's ``Trajectory`` of
    its ULog, in a process with the tool's environment (the tool's folder as working folder, as Aerialist wants)."""
    script = (
        "import json, sys\n"
        f"from aerialist.px4.{module} import {'AerialistTest' if module == 'aerialist_test' else 'DroneTest'} as T\n"
        "from aerialist.px4.trajectory import Trajectory\n"
        "from testcase import TestCase\n"
        "out = []\n"
        "for yaml_file, ulg in json.loads(sys.argv[1]):\n"
        "    test = T.from_yaml(yaml_file)\n"
        "    case = TestCase(test, test.simulation.obstacles)\n"
        "    case.trajectory = Trajectory.extract(ulg)\n"
        "    out.append(case.get_distances())\n"
        "print(json.dumps(out))\n")
    pairs = json.dumps([[str(t.yaml), str(t.ulg)] for t in result.tests])
    env = tool_environment(result.plan.aerialist, "", b"", 1)
    done = subprocess.run([sys.executable, "-c", script, pairs], cwd=result.plan.out / "tool", env=env,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _our_distances(result, buffer: float, aerialist_windows: bool = False) -> list[list[float]]:
    """Our competition distance of each written test's ULog, per obstacle. With ``aerialist_windows``, the 0.5 s
    windows are Aerialist's (``Trajectory.downsample_time``: [0, 0.5], then (0.5, 1.0], ...; ours are [0, 0.5),
    [0.5, 1.0), ...), so that only the geometry differs."""
    flights = {f.number: f for f in result.flights}
    out = []
    for t in result.tests:
        flight = read_flight(t.ulg)
        trajectory = flight.trajectory
        if aerialist_windows:
            p = flight.positions
            times = np.asarray(p.timestamp_us, dtype=np.int64) - 1
            times[0] += 1  # a sample on a window's end falls in that window, as in Aerialist
            trajectory = Trajectory.from_local_position(times, p.x, p.y, p.z)
        obstacles = load_test(flights[t.flight].test_file).obstacles
        out.append(competition_distances(trajectory, obstacles, buffer).tolist())
    return out


def _check_distances(result, module: str, buffer: float) -> None:
    """Aerialist's own distances of the written tests (``get_distances()`` of the tool's TestCase on Aerialist's
    Trajectory of the ULog) against ours on the same ULogs: equal to 5 mm on Aerialist's windows (shapely buffers a
    line with a polygon); on our windows, each of Aerialist's points lies one 0.1 s sample further along the flight,
    so the two differ by at most that step (0.1 s at the flight's top speed; measured up to 0.12 m)."""
    theirs = _aerialist_distances(result, module)
    assert len(theirs) == len(result.tests)
    for a, b in zip(theirs, _our_distances(result, buffer, aerialist_windows=True)):
        assert a == pytest.approx(b, abs=0.005)
    for test, a, b in zip(result.tests, theirs, _our_distances(result, buffer)):
        trajectory = read_flight(test.ulg).trajectory
        step = np.linalg.norm(np.diff(trajectory.xyz[:, :2], axis=0), axis=1) / np.diff(trajectory.t)
        assert a == pytest.approx(b, abs=0.15 * step.max())  # the step, with a margin for speeds within a window


# --- the two generations end to end ----------------------------------------------------------------------------------
@pytest.mark.slow
def test_reference_generator_aerialist_master(tmp_path):
    """The competition's reference generator (cli.py + random_generator.py, AerialistTest) on mission1, budget 10."""
    result = run(prepare(SNIPPETS, "mission1", 10, tmp_path / "ref"))
    assert result.problem is None and result.returncode == 0
    assert result.plan.apis == ("AerialistTest",) and result.plan.case_study == "case_studies/mission1.yaml"
    assert result.plan.aerialist.version == "0.3.0"
    assert any("AerialistTest.plot added" in n for n in result.notes)  # master lacks what the 2025 snippet calls
    _check_output_folder(result, 10)
    assert result.found_by.startswith("printed by the tool") and result.tool_env.kind == "ours"
    assert {f.agent for f in result.flights} == {"DockerAgent"} and {f.api for f in result.flights} == {"AerialistTest"}
    _check_distances(result, "aerialist_test", buffer=0.125)  # master buffers the polyline by 0.125 m
    assert not any(p.name.endswith(".pyc") for p in SNIPPETS.rglob("*"))  # their folder untouched


@pytest.mark.slow
def test_ambiegen_aerialist_0_2_1(tmp_path):
    """AmbieGen (pymoo GA with an RRT surrogate, DroneTest) on mission2, budget 10. It checks its budget between
    generations only, so it may ask for more than 10 in its first one: then compete refuses the excess, says so and
    scores its output as usual."""
    result = run(prepare(AMBIEGEN, "mission2", 10, tmp_path / "ambiegen"))
    assert result.plan.apis == ("DroneTest",) and result.plan.aerialist.version == "0.2.1"
    assert result.returncode == 0 and result.problem is None
    assert json.loads((result.plan.out / "summary.json").read_text())["refused"] == result.refused
    _check_output_folder(result, 10)
    assert {f.api for f in result.flights} == {"DroneTest"}
    assert any("min_distance_to_obstacles added" in n for n in result.notes)
    _check_distances(result, "drone_test", buffer=0.0)  # 0.2.1's geometry, no buffer


@pytest.mark.slow
@pytest.mark.parametrize("agent, mission", [("local", "mission2"), ("k8s", "mission3")])
def test_every_agent_flies_our_simulator(tmp_path, monkeypatch, capsys, agent, mission):
    """AGENT chooses Aerialist's LocalAgent (its PX4 modules are not installed: a stand-in module holds ours) or
    K8sAgent in the reference generator; both fly here. The command line prints where the tool wrote. A relative
    --out works too, though the tool runs in a folder of its own."""
    monkeypatch.setenv("AGENT", agent)
    monkeypatch.chdir(tmp_path)
    out = Path(agent) if agent == "k8s" else tmp_path / agent
    assert main(["compete", str(SNIPPETS), mission, "1", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"output folder: {out.absolute() / 'tool' / 'generated_tests'}" in printed
    assert "(the tool's: 1 tests, 1 with yaml, ulg and png; printed by the tool ('output folder: PATH'))" in printed
    assert "simulations: 1 of budget 1 flown" in printed and "failures by the competition's distance: " in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["problem"] is None and summary["simulations"] == 1 and len(summary["tests"]) == 1
    assert all(Path(summary["tests"][0][k]).is_file() for k in ("yaml", "ulg", "png"))
    agents = [row.split(",")[1] for row in (out / "flights.csv").read_text().splitlines()[1:]]
    assert agents == [{"local": "LocalAgent", "k8s": "K8sAgent"}[agent]]
    assert (agent == "local") == any("stand-in module" in n for n in summary["compat"])


# --- the budget and the runs of an agent ---------------------------------------------------------------------------
TOOL_HEAD = '''\
import sys
from aerialist.px4.aerialist_test import AerialistTest, AgentConfig
from aerialist.px4.docker_agent import DockerAgent
from aerialist.px4.k8s_agent import K8sAgent
from aerialist.px4.obstacle import Obstacle

test = AerialistTest.from_yaml(sys.argv[2])
test.simulation.obstacles = [Obstacle(Obstacle.Size(10, 5, 20), Obstacle.Position(-5, 25, 0, 0))]
'''


def _tool(tmp_path, body: str) -> Path:
    folder = tmp_path / "tool"
    (folder / "case_studies").mkdir(parents=True)
    for name in ("mission1.yaml", "mission1.plan", "mission-params.csv", "mission-commands.csv"):
        (folder / "case_studies" / name).write_bytes((SNIPPETS / "case_studies" / name).read_bytes())
    (folder / "cli.py").write_text(TOOL_HEAD + body, encoding="utf-8")
    return folder


def test_budget_is_enforced(tmp_path, capsys):
    """A tool that asks for two simulations more than its budget gets them refused (an exception in its agent's
    run(), as a failed PX4 run raises); this is reported, and its output is scored as usual (exit code 0)."""
    tool = _tool(tmp_path, '''
got = []
for i in range(int(sys.argv[3]) + 2):
    try:
        got.append(len(DockerAgent(test).run()))
    except RuntimeError as err:
        print("refused:", err)
print("output folder: ./")
''')
    out = tmp_path / "out"
    assert main(["compete", str(tool), "mission1", "1", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "simulations: 1 of budget 1 flown" in printed and ", 2 refused;" in printed
    assert "budget: the tool asked for 2 simulations past its budget of 1; they were refused" in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["simulations"] == 1 and summary["refused"] == 2 and summary["requests"] == 3
    assert summary["problem"] is None
    assert len(list((out / "flights").glob("*.ulg"))) == 1
    assert (out / "tool-stdout.txt").read_text().count("refused: surrealist compete: the budget of 1") == 2


def test_the_output_folder_found_under_generated_tests(tmp_path, capsys):
    """A tool that prints no 'output folder: PATH' (or one that does not exist) is scored from the folder of test
    YAMLs it wrote last under generated_tests*/ (AmbieGen writes generated_tests-01/), as the organisers collect a
    tool's tests."""
    tool = _tool(tmp_path, '''
import os, shutil
for folder in ("generated_tests/old", "generated_tests-01/run/new"):
    os.makedirs(folder)
    result = DockerAgent(test).run()[0]
    test.to_yaml(folder + "/test_0.yaml")
    shutil.copy(result.log_file, folder + "/test_0.ulg")
print("done: tests in generated_tests")
''')
    assert main(["compete", str(tool), "mission1", "2", "--out", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    found = tmp_path / "out" / "tool" / "generated_tests-01" / "run" / "new"
    assert f"output folder: {found} (the tool's: 1 tests, 0 with yaml, ulg and png; the newest folder of test " \
           f"YAMLs under generated_tests-01/ (it printed no 'output folder: PATH'))" in printed
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["problem"] is None and summary["output_folder"] == str(found)
    assert summary["tests"][0]["flight"] == 2 and summary["tests"][0]["competition_distance"] is not None


def test_a_tool_that_keeps_asking_is_stopped(tmp_path, capsys):
    tool = _tool(tmp_path, '''
while True:
    try:
        DockerAgent(test).run()
    except RuntimeError:
        pass
''')
    assert main(["compete", str(tool), "mission1", "1", "--out", str(tmp_path / "out")]) == 2
    assert "kept asking for simulations past its budget of 1 and was stopped" in _one_line(capsys)


def test_agent_count_and_runs_per_test(tmp_path):
    """A test's agent.count decides how many runs K8sAgent returns (Aerialist's k8s job runs count pods); without an
    agent section, --runs does; every run counts in the budget."""
    tool = _tool(tmp_path, '''
counts = [len(DockerAgent(test).run())]
test.agent = AgentConfig(engine="k8s", count=3)
results = K8sAgent(test).run()
counts.append(len(results))
assert type(results[0]).__name__ == "AerialistTestResult" and len(results[2].record.positions) > 10
print("runs:", counts)
print("output folder: ./")
''')
    result = run(prepare(tool, "mission1", 5, tmp_path / "out", runs_per_test=2))
    assert result.problem is None, result.problem
    assert "runs: [2, 3]" in (result.plan.out / "tool-stdout.txt").read_text()
    assert result.spent == 5 and [len(f.logs) for f in result.flights] == [2, 3]
    first, second = result.flights[1].logs[:2]
    assert Path(first).read_bytes() != Path(second).read_bytes()  # two runs, each with its own noise


# --- one-line errors, checked before anything starts ---------------------------------------------------------------
def test_errors_before_anything_starts(tmp_path, capsys):
    no_cli = tmp_path / "no-cli"
    no_cli.mkdir()
    exists = tmp_path / "exists"
    exists.mkdir()
    (exists / "notes.txt").write_text("someone else's\n")
    cases = [
        (["compete", str(no_cli), "mission1", "5"], f"tool {no_cli}: no cli.py in it"),
        (["compete", str(tmp_path / "nowhere"), "mission1", "5"], "no such folder"),
        (["compete", str(SNIPPETS), "mission9", "5", "--out", str(tmp_path / "a")], "case study 'mission9': not found"),
        (["compete", str(SNIPPETS), "mission1", "5", "--out", str(exists)],
         f"--out {exists}: holds something else (notes.txt)"),
        (["compete", str(SNIPPETS), "mission1", "0", "--out", str(tmp_path / "b")], "BUDGET: expected a whole number"),
        (["compete", str(SNIPPETS), "mission1", "5", "--aerialist", str(tmp_path), "--out", str(tmp_path / "c")],
         "not an Aerialist folder"),
        (["compete", str(SNIPPETS), "mission1", "5", "--aerialist", str(LEGACY), "--out", str(tmp_path / "d")],
         "the tool imports Aerialist's AerialistTest"),
    ]
    for argv, expected in cases:
        assert main(argv) == 2, argv
        line = _one_line(capsys)
        assert line.startswith("error: ") and expected in line, (argv, line)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["exists", "no-cli"]  # nothing was started or written


def test_a_tool_that_crashes_or_names_no_output_folder(tmp_path, capsys):
    crash = _tool(tmp_path, 'raise ValueError("boom in the tool")\n')
    assert main(["compete", str(crash), "mission1", "3", "--out", str(tmp_path / "crash")]) == 2
    line = _one_line(capsys)
    assert "the tool crashed (exit code 1): ValueError: boom in the tool" in line
    assert (tmp_path / "crash" / "tool-stderr.txt").is_file()

    (crash / "cli.py").write_text(TOOL_HEAD + 'print("done")\n', encoding="utf-8")
    (crash / "generated_tests" / "shipped").mkdir(parents=True)  # YAMLs older than the run: not the tool's output
    (crash / "generated_tests" / "shipped" / "test_0.yaml").write_bytes((crash / "case_studies" / "mission1.yaml")
                                                                       .read_bytes())
    assert main(["compete", str(crash), "mission1", "3", "--out", str(tmp_path / "silent")]) == 2
    assert "no output folder: it printed no 'output folder: PATH', and wrote no test YAML under " \
           f"{tmp_path / 'silent' / 'tool' / 'generated_tests'}*/ (see " in _one_line(capsys)


def test_aerialist_lookup(tmp_path, monkeypatch):
    assert tool_apis(SNIPPETS) == ("AerialistTest",) and tool_apis(AMBIEGEN) == ("DroneTest",)
    assert find_aerialist(("DroneTest",)).version == "0.2.1"  # the second folder of $SURREALIST_AERIALIST
    # the package folder works too
    assert find_aerialist(("AerialistTest",), MASTER / "aerialist").path == MASTER.resolve()
    monkeypatch.setenv(AERIALIST_ENV, str(tmp_path))
    with pytest.raises(SurrealistError, match="not an Aerialist folder"):
        find_aerialist(("DroneTest",))
    fake = tmp_path / "fake" / "aerialist" / "px4"  # an Aerialist whose imports are not all installed here
    fake.mkdir(parents=True)
    (fake / "drone_test.py").write_text("import math\nimport surely_not_installed_here\n")
    (fake / "local_agent.py").write_text("import mavsdk\n")  # the local agent's imports are the shim's business
    with pytest.raises(DependencyNotInstalled, match="its drone_test.py imports surely_not_installed_here, which is "
                                                     "not installed; install .* pip install -e '.\\[compete\\]'"):
        prepare(AMBIEGEN, "mission1", 5, tmp_path / "out", aerialist=tmp_path / "fake")
    assert not (tmp_path / "out").exists()

# --- a tool that cleans up: each agent.run() hands it a folder of its own; compete's record is elsewhere -----------
#: After each execute(), the run's ULog is kept under the tool's own name, then Aerialist's runtime files are
#: removed: the log returned, every YAML in its folder, and the folder (os.rmdir: it must hold nothing else).
CLEAN_UP = '''
    def clean_up(self, test, i):
        import glob, os, shutil
        log = test.log_file
        folder = os.path.dirname(os.path.abspath(log))
        os.makedirs("kept", exist_ok=True)
        test.log_file = shutil.copy2(log, f"kept/test_{i}.ulg")
        os.remove(log)
        for yaml_file in glob.glob(os.path.join(folder, "*.yaml")):
            os.remove(yaml_file)
        os.rmdir(folder)
        print(f"cleaned up:{folder}")
'''


def _cleaning_tool(tmp_path) -> Path:
    """The reference generator, copied, with :data:`CLEAN_UP` called right after each ``test.execute()``."""
    tool = tmp_path / "cleaning-tool"
    shutil.copytree(SNIPPETS, tool, ignore=shutil.ignore_patterns("*.png", "__pycache__"))
    source = (tool / "random_generator.py").read_text(encoding="utf-8")
    assert source.count("                test.execute()\n") == 1
    source = source.replace("                test.execute()\n",
                            "                test.execute()\n                self.clean_up(test, i)\n")
    head = "    def generate(self, budget: int)"
    source = source.replace(head, CLEAN_UP.lstrip("\n") + "\n" + head)
    (tool / "random_generator.py").write_text(source, encoding="utf-8")
    return tool


@pytest.mark.slow
def test_a_tool_that_deletes_each_runs_folder_flies_and_writes_every_test(tmp_path):
    budget = 6
    result = run(prepare(_cleaning_tool(tmp_path), "mission2", budget, tmp_path / "out"))
    out = result.plan.out
    assert result.problem is None and result.returncode == 0, result.problem
    assert result.spent == budget and result.refused == 0
    assert [f.error for f in result.flights] == [""] * budget  # none refused: every later test flew too
    printed = (out / "tool-stdout.txt").read_text(encoding="utf-8")
    cleaned = [Path(line.split(":", 1)[1]) for line in printed.splitlines() if line.startswith("cleaned up:")]
    assert len(cleaned) == budget and len(set(cleaned)) == budget  # a folder of its own for each run
    logs = out / "tool" / "results" / "logs"
    for folder in cleaned:
        assert folder.parent == logs and not folder.exists()
    assert logs.is_dir() and not any(logs.iterdir())
    # the tool wrote every test, each judged on a ULog compete flew and kept
    assert len(result.tests) >= 5 and len(result.tests) == budget
    for test in result.tests:
        assert test.yaml.is_file() and test.ulg is not None and test.png is not None
        assert test.flight is not None and test.distance is not None and test.points in (0, 1, 2, 5), test
    assert sorted(p.name for p in (out / "flights").iterdir()) == sorted(
        [f"sim-{n:04d}.yaml" for n in range(1, budget + 1)] + [f"sim-{n:04d}-run0.ulg" for n in range(1, budget + 1)])
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["simulations"] == budget and len(summary["tests"]) == budget


def test_compete_makes_its_record_folder_again_when_it_is_removed(tmp_path):
    """A tool that removes what it should not (compete's own flights/, found beside its working folder) after each
    run: the next run is flown all the same, and each run still gets a folder of its own."""
    tool = _tool(tmp_path, '''
import os, shutil
folders = []
for i in range(3):
    log = DockerAgent(test).run()[0].log_file
    folders.append(os.path.dirname(log))
    shutil.rmtree("../flights")
print("folders:", len(set(folders)), all(os.path.isfile(os.path.join(f, os.path.basename(f) + ".yaml"))
                                         for f in folders))
handed = [AerialistTest.from_yaml(os.path.join(f, os.path.basename(f) + ".yaml")) for f in folders]  # by Aerialist
print("read back:", [len(t.simulation.obstacles) for t in handed])
print("output folder: ./")
''')
    result = run(prepare(tool, "mission1", 3, tmp_path / "out"))
    assert result.problem is None, result.problem
    assert result.spent == 3 and [f.error for f in result.flights] == ["", "", ""]
    printed = (result.plan.out / "tool-stdout.txt").read_text(encoding="utf-8")
    assert "folders: 3 True" in printed and "read back: [1, 1, 1]" in printed


def test_a_refusal_names_the_file_and_the_field_and_quotes_neither(tmp_path):
    """A test whose params file is no params file, and one whose obstacle has a negative length: each refused in a
    line naming our YAML of the test (kept in flights/, where ``surrealist simulate`` says more), the field, and for
    a file field the file it names and the line; nothing of the file's content."""
    tool = _tool(tmp_path, '''
with open("case_studies/bad-params.csv", "w") as f:
    f.write("SECRET-LINE, not a number\\n")
for change in ("params", "size"):
    bad = AerialistTest.from_yaml(sys.argv[2])
    bad.simulation.obstacles = test.simulation.obstacles
    if change == "params":
        bad.robot.params, bad.robot.params_file = None, "case_studies/bad-params.csv"  # so to_dict() names it
    else:
        bad.simulation.obstacles = [Obstacle(Obstacle.Size(-3, 5, 20), Obstacle.Position(-5, 25, 0, 0))]
    try:
        DockerAgent(bad).run()
    except RuntimeError as err:
        print("refused:", err)
DockerAgent(test).run()
print("output folder: ./")
''')
    result = run(prepare(tool, "mission1", 3, tmp_path / "out"))
    assert result.problem is None, result.problem
    out, work = result.plan.out, result.plan.out / "tool"
    first, second = (out / "flights" / "sim-0001.yaml"), (out / "flights" / "sim-0002.yaml")
    params = work / "case_studies" / "bad-params.csv"
    assert [f.error for f in result.flights] == [
        f"the test cannot be flown: {first}: field 'params_file' (it names {params}, line 1) is not what our loader "
        f"reads (InvalidTestCase; surrealist simulate {first} says why)",
        f"the test cannot be flown: {second}: field 'obstacles[0]' is not what our loader reads (InvalidTestCase; "
        f"surrealist simulate {second} says why)",
        ""]
    assert first.is_file() and second.is_file() and result.spent == 1
    printed = (out / "tool-stdout.txt").read_text(encoding="utf-8")
    assert printed.count("refused: surrealist compete: the test cannot be flown: ") == 2
    records = (out / "flights.csv").read_text(encoding="utf-8") + (out / "summary.json").read_text(encoding="utf-8")
    assert "SECRET" not in records and "SECRET" not in printed
    rows = list(csv.DictReader(open(out / "flights.csv", encoding="utf-8")))
    assert [r["test_file"] for r in rows[:2]] == [str(first), str(second)]
