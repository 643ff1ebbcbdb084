"""Aerialist's YAML both ways, against the real Aerialist (master and 0.2.1 from ../shared/third_party).

Every YAML our commands write (best.yaml of a tiny generate and replicate, a tiny ``generate --case-study``'s
best.yaml and suite, which its confirmation re-flies) is moved to another folder and loaded by each Aerialist's own
``from_yaml`` from that folder, as its README says to run it: every obstacle has Aerialist's geometry, of the right
area and place. Our simulated ULogs go through Aerialist's own ``Trajectory.extract``, distance (master buffers its
polyline by 0.125 m, 0.2.1 does not) and plot; the distances equal each run's ``competition_distance`` and
Aerialist's 0.5 s trajectory equals ours. YAMLs written by Aerialist's own ``to_yaml`` (``size.r``, a cylinder, a
numeric port, a timeout, an agent, an assertion) load and fly. Aerialist runs in one subprocess per version, in
the environment ``surrealist compete`` gives a tool (``compete.tool_environment``: its shim, then Aerialist's
folder), so its plots work with this matplotlib.
"""
from __future__ import annotations

import csv
import json
import math
import shutil
import subprocess
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from surrealist_gym.aerialist import load_test, save_test
from surrealist_gym.cli import main
from surrealist_gym.competition.compete import tool_environment
from surrealist_gym.competition.compete.locate import source_of
from surrealist_gym.errors import InvalidTestCase
from surrealist_gym.logs import read_flight, write_run_ulog
from surrealist_gym.results import export_test
from surrealist_gym.sim.profiles import load_profile
from surrealist_gym.sim.runner import simulate
from surrealist_gym.testcase import Obstacle, Shape, TestCase
from surrealist_gym.trajectory import Trajectory
from tests.conftest import CASE_STUDIES, EXPERIMENTS, SHARED_DATA

ROOT = Path(__file__).resolve().parents[2]
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
VERSIONS = {"master": THIRD_PARTY / "aerialist-master", "0.2.1": THIRD_PARTY / "aerialist-0.2.1"}
BUFFER = {"master": 0.125, "0.2.1": 0.0}  # Aerialist's polyline buffer (master since Oct 2024)
CAMBA = SHARED_DATA / "competition" / "camba-collection"
FLIGHTS = ["04-12-14-10-41-5O9PN", "12-11-18-25-21-5O9PN", "12-11-19-38-28-5O9PN", "19-11-21-10-33-5O9PN",
           "23-11-14-45-10-5O9PN", "26-11-13-35-31-5O9PN"]  # CAMBA's quick flights, each a close pass (0.9-1.5 m)
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

#: Run in Aerialist's process: each check job loads a YAML from its folder, as the folder's README says (and, with a
#: ULog, extracts Aerialist's trajectory, its distance to each obstacle and its plot); each write job writes a test
#: with Aerialist's own to_yaml.
AERIALIST_SCRIPT = r'''
import json, logging, os, sys
from aerialist.px4.obstacle import Obstacle
from aerialist.px4.trajectory import Trajectory
try:
    from aerialist.px4.aerialist_test import AerialistTest as Test, AerialistTestResult as Result, AgentConfig
    from aerialist.px4.aerialist_test import AssertionConfig
    from aerialist.px4.plot import Plot
    plot = Plot.plot_test
except ImportError:
    from aerialist.px4.drone_test import DroneTest as Test, DroneTestResult as Result
    plot = Test.plot
class Logged(logging.Handler):
    messages = []
    def emit(self, record):
        self.messages.append(record.getMessage())
logging.getLogger().addHandler(Logged())
checks, writes = json.loads(sys.argv[1]), json.loads(sys.argv[2])
out = {"checks": [], "writes": []}
for job in checks:
    os.chdir(job["folder"])
    before = len(Logged.messages)
    test = Test.from_yaml(job["yaml"])
    obstacles = test.simulation.obstacles or []
    item = {"obstacles": [[getattr(o, "shape", "box"), o.geometry.area, *o.geometry.centroid.coords[0]]
                          if hasattr(o, "geometry") else None for o in obstacles],
            "logged": Logged.messages[before:]}
    if job.get("ulog"):
        result = Result(job["ulog"])
        item["distances"] = [result.record.min_distance_to_obstacles([o]) for o in obstacles]
        item["trajectory"] = [[p.x, p.y, p.z] for p in result.record.positions]
        item["plot"] = os.path.abspath(plot(test, [result]))
    out["checks"].append(item)
for job in writes:
    os.chdir(job["folder"])
    test = Test.from_yaml(job["case_study"])
    shapes = {"box": getattr(Obstacle, "BOX", "box"), "cylinder": getattr(Obstacle, "CYLINDER", "cylinder")}
    test.simulation.obstacles = [Obstacle(Obstacle.Size(**o["size"]), Obstacle.Position(**o["position"]),
                                          shapes[o["shape"]]) for o in job["obstacles"]]
    if "timeout" in job:
        test.simulation.timeout = job["timeout"]
    if "agent" in job:
        test.agent = AgentConfig(**job["agent"])
    if "assertion" in job:
        test.assertion = AssertionConfig(log_file=job["assertion"])
    out["writes"].append(os.path.abspath(test.to_yaml(job["yaml"])))
print(json.dumps(out))
'''

if not all(path.is_dir() for path in VERSIONS.values()):
    pytest.skip(f"needs Aerialist master and 0.2.1 in {THIRD_PARTY}", allow_module_level=True)
for _module in ("munch", "decouple", "ruptures", "requests", "webdav3", "webdav4", "tslearn", "similaritymeasures"):
    pytest.importorskip(_module, reason=f"{_module}: pip install -e '.[compete]' (what Aerialist's modules import)")


def run_aerialist(version: str, checks: list[dict], writes: list[dict], workdir: Path) -> tuple[dict, str]:
    """Aerialist ``version``'s answers to the jobs (AERIALIST_SCRIPT), and what it logged on stderr."""
    env = tool_environment(source_of(VERSIONS[version]), "", b"", 1)
    env["RESULTS_DIR"] = f"{workdir / 'plots' / version}/"  # Aerialist's plot folder (default results/ in the cwd)
    done = subprocess.run([sys.executable, "-c", AERIALIST_SCRIPT, json.dumps(checks), json.dumps(writes)],
                          cwd=workdir, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"Aerialist {version} failed:\n{done.stderr[-3000:]}"
    return json.loads(done.stdout.strip().splitlines()[-1]), done.stderr


def _quiet_load(path) -> TestCase:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # the competition missions' MAV_CMD 530, as known
        return load_test(path)


# --- what our commands write, then moved: the YAMLs, and flights of them -------------------------------------------
@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """Results folders of a tiny generate, replicate and generate --case-study, moved to another folder after they
    were written; the YAMLs in them (and the files the confirmation re-flew, by name)."""
    made, moved = tmp_path_factory.mktemp("written"), tmp_path_factory.mktemp("moved")
    commands = {"generate": ["generate", "--budget", "2", "--runs", "1"],
                "replicate": ["replicate", "--budget", "2", "--runs", "1"],
                "case-study": ["generate", "--case-study", str(CASE_STUDIES / "mission1.yaml"), "--budget", "6",
                               "--obstacles", "3", "--confirm", "1"]}
    for name, argv in commands.items():
        assert main([*argv, "--workers", "1", "--out", str(made / name)]) == 0
    with open(made / "case-study" / "suite" / "confirmation" / "evaluation.csv", newline="") as f:
        confirmed = [Path(row["file"]).name for row in csv.DictReader(f)]
    shutil.move(made, moved / "results")  # the folders travel: nothing may name where they were written
    root = moved / "results"
    yamls = sorted(root.rglob("*.yaml"))
    return root, yamls, confirmed


@pytest.fixture(scope="module")
def flights(tmp_path_factory, written):
    """ULogs of our flights, each with its test's YAML and the run's competition distance flown unbuffered and
    with master's buffer: the CAMBA tests' and the suite's."""
    folder = tmp_path_factory.mktemp("flights")
    shutil.copytree(SHARED_DATA / "competition" / "case_studies", folder / "case_studies")
    root, yamls, _ = written
    tests = [shutil.copy(CAMBA / f"{name}.yaml", folder) for name in FLIGHTS]
    tests += [p for p in yamls if p.parent.name == "suite"]
    config = load_profile("px4-v1.12-sitl-iris").sim_config()
    out = []
    for i, path in enumerate(map(Path, tests)):
        test = load_test(path)
        plain = simulate(test, runs=1, seed=0, config=config)[0]
        buffered = simulate(test, runs=1, seed=0, config=replace(config, competition_buffer_m=0.125))[0]
        assert np.array_equal(plain.local_position.x, buffered.local_position.x)  # the buffer flies nothing else
        ulog = folder / f"flight-{i}.ulg"
        write_run_ulog(ulog, plain, mission=test.mission)
        out.append({"yaml": path, "test": test, "ulog": ulog, "ours": {"0.2.1": plain.competition_distance,
                                                                      "master": buffered.competition_distance}})
    return out


@pytest.fixture(scope="module")
def tool_folder(tmp_path_factory):
    """A folder like a competition tool's: the case studies in case_studies/ and a real flight log."""
    folder = tmp_path_factory.mktemp("tool")
    shutil.copytree(SHARED_DATA / "competition" / "case_studies", folder / "case_studies")
    shutil.copy(EXPERIMENTS / "case0.ulg", folder / "case0.ulg")
    return folder


BOX = {"shape": "box", "size": {"l": 6, "w": 4, "h": 20}, "position": {"x": 5, "y": 22, "z": 0, "r": 30}}
CYLINDER = {"shape": "cylinder", "size": {"l": 0, "w": 0, "h": 20, "r": 2.5}, "position": {"x": -12, "y": 30, "z": 0,
                                                                                          "r": 0}}


@pytest.fixture(scope="module")
def aerialist(tmp_path_factory, written, flights, tool_folder):
    """Each Aerialist's answers: loading every YAML we wrote (from its folder, as the README says) and each flight's
    YAML with its ULog; and the YAMLs it wrote itself with its to_yaml."""
    work = tmp_path_factory.mktemp("aerialist")  # the process starts here, in no folder of the YAMLs
    root, yamls, _ = written
    checks = [{"folder": str(p.parent), "yaml": p.name} for p in yamls]
    checks += [{"folder": str(f["yaml"].parent), "yaml": f["yaml"].name, "ulog": str(f["ulog"])} for f in flights]
    writes = {"master": [{"folder": str(tool_folder), "case_study": "case_studies/mission1.yaml",
                          "yaml": "master-written.yaml", "obstacles": [BOX, CYLINDER], "timeout": 400,
                          "agent": {"engine": "k8s", "count": 1, "id": "t1"}},
                         {"folder": str(tool_folder), "case_study": "case_studies/mission1.yaml",
                          "yaml": "master-assertion.yaml", "obstacles": [BOX], "assertion": "case0.ulg"}],
              "0.2.1": [{"folder": str(tool_folder), "case_study": "case_studies/mission1.yaml",
                         "yaml": "legacy-written.yaml", "obstacles": [BOX]}]}
    return {version: run_aerialist(version, checks, writes[version], work) for version in VERSIONS}


# --- our YAMLs in Aerialist ----------------------------------------------------------------------------------------
def test_every_yaml_we_write_loads_in_both_aerialists_with_geometry(written, aerialist):
    root, yamls, confirmed = written
    names = {p.relative_to(root).as_posix() for p in yamls}
    assert {"generate/best.yaml", "replicate/best.yaml", "case-study/best.yaml"} <= names
    suite = [p for p in yamls if p.parent.name == "suite"]
    assert suite, "the tiny case-study search kept no failure: nothing of the suite was checked"
    assert confirmed and set(confirmed) <= {p.name for p in suite}  # the confirmation re-flew the suite's YAMLs
    for version, (answers, _) in aerialist.items():
        for path, answer in zip(yamls, answers["checks"]):
            ours = _quiet_load(path).obstacles
            assert len(answer["obstacles"]) == len(ours), (version, path)
            for o, theirs in zip(ours, answer["obstacles"]):
                assert theirs is not None, f"Aerialist {version} built {path} obstacle without geometry"
                shape, area, cx, cy = theirs
                assert shape == o.shape.value, (version, path)
                assert area == pytest.approx(o.l * o.w, rel=1e-9), (version, path)
                assert (cx, cy) == pytest.approx((o.x, o.y), abs=1e-6), (version, path)


def test_aerialist_loads_our_files_without_a_warning(written, aerialist):
    """Master reads robot/mission and ignores drone/test beside them (it warns only when it reads drone or test, as
    on the competition's own case studies); 0.2.1 reads drone/test and ignores the rest."""
    yamls = written[1]
    for version, (answers, _) in aerialist.items():
        assert [a["logged"] for a in answers["checks"][:len(yamls)]] == [[]] * len(yamls), version
    assert any("'drone' key is deprecated" in m for a in aerialist["master"][0]["checks"] for m in a["logged"])


def test_the_files_travel_with_their_folder(written):
    """Every path in a written YAML is relative, names a copy inside the YAML's folder, and the folder's README says
    to run Aerialist from it; our loader reads them there too."""
    root, yamls, _ = written
    for path in yamls:
        doc = yaml.safe_load(path.read_text())
        for section, keys in (("robot", ("params_file", "mission_file")), ("drone", ("params_file", "mission_file")),
                              ("mission", ("commands_file",)), ("test", ("commands_file",)),
                              ("assertion", ("log_file",))):
            for key in keys:
                value = (doc.get(section) or {}).get(key)
                if value is not None:
                    assert not Path(value).is_absolute() and (path.parent / value).is_file(), (path, key, value)
                    assert (path.parent / value).resolve().is_relative_to(path.parent.resolve())
        assert doc["robot"] == doc["drone"] and doc["mission"] == doc["test"]
        assert all(o["shape"] in ("box", "cylinder") and "r" in o["size"] for o in doc["simulation"]["obstacles"])
        assert "run it from this folder" in (path.parent / "README.md").read_text()
        assert _quiet_load(path).mission is not None
    replicated = yaml.safe_load((root / "replicate" / "best.yaml").read_text())
    assert replicated["assertion"]["log_file"] == "case_studies/case0.ulg"  # the real flight travels too
    generated = yaml.safe_load((root / "generate" / "best.yaml").read_text())
    assert "assertion" not in generated  # its log (auto1.ulg) is not at hand: Aerialist could not load the test
    assert generated["surrealist"] == {"assertion_log": "experiments/auto1.ulg"}
    assert _quiet_load(root / "generate" / "best.yaml").replicates_flight


# --- Aerialist's distance, trajectory and plot on our ULogs -----------------------------------------------------------
def test_aerialist_distance_on_our_ulogs_equals_ours(flights, aerialist):
    """Each run's competition distance is Aerialist's get_distances() on the run's ULog: unbuffered for 0.2.1, with
    master's 0.125 m buffer for master (SimConfig.competition_buffer_m)."""
    n = len(next(iter(aerialist.values()))[0]["checks"]) - len(flights)
    for version, (answers, _) in aerialist.items():
        for flight, answer in zip(flights, answers["checks"][n:]):
            assert min(answer["distances"]) == pytest.approx(flight["ours"][version], abs=0.02), (version, flight)
            assert min(answer["distances"]) == pytest.approx(flight["ours"][version], abs=1e-3)  # polygon buffer


def test_aerialist_trajectory_is_ours_on_its_windows(flights, aerialist):
    """Aerialist's extract of our ULog (its 0.5 s windows, closed on the right) is Trajectory.aerialist of the same
    samples, point for point; the paper's windows differ."""
    n = len(aerialist["master"][0]["checks"]) - len(flights)
    for version, (answers, _) in aerialist.items():
        for flight, answer in zip(flights, answers["checks"][n:]):
            p = read_flight(flight["ulog"]).positions
            ours = Trajectory.aerialist(p.timestamp_us, p.x, p.y, p.z, p.heading)
            assert np.allclose(ours.xyz, answer["trajectory"], atol=1e-9), version
    paper = read_flight(flights[0]["ulog"]).trajectory
    assert not np.allclose(paper.xyz[1:3], aerialist["master"][0]["checks"][n]["trajectory"][1:3], atol=1e-3)


def test_aerialist_plots_our_flights(flights, aerialist):
    n = len(aerialist["master"][0]["checks"]) - len(flights)
    for version, (answers, _) in aerialist.items():
        for answer in answers["checks"][n:]:
            assert Path(answer["plot"]).read_bytes()[:8] == PNG_MAGIC, version


def test_aerialist_windows_are_closed_on_the_right():
    """[0, 0.5], (0.5, 1.0], ...: a sample on a window's end is in it; one earlier than its predecessor joins the
    open window; an empty window gives no point. The paper's [0, 0.5), [0.5, 1.0) are unchanged."""
    t = np.array([0, 100_000, 500_000, 600_000, 400_000, 1_000_000, 2_100_000])
    x = np.arange(len(t), dtype=float)
    zero = np.zeros(len(t))
    ours = Trajectory.aerialist(t, x, zero, zero)
    assert ours.x.tolist() == [1.0, 4.0, 6.0]  # samples {0, 1, 2}, {3, 4 (late), 5}, {6}
    paper = Trajectory.from_local_position(t, x, zero, zero)  # sorted: {0, 1, 4}, {2, 3}, {5}, {6}
    assert paper.x.tolist() == pytest.approx([5 / 3, 2.5, 5.0, 6.0])


# --- Aerialist's YAMLs in ours -------------------------------------------------------------------------------------
def test_a_yaml_aerialist_master_wrote_loads_and_flies(aerialist, tool_folder, tmp_path, capsys):
    master_written, with_assertion = map(Path, aerialist["master"][0]["writes"])
    doc = yaml.safe_load(master_written.read_text())
    assert doc["robot"]["port"] == 14541 and doc["simulation"]["obstacles"][1]["size"]["r"] == 2.5
    test = _quiet_load(master_written)
    box, cylinder = test.obstacles
    assert (box.shape, box.l, box.w, box.r) == (Shape.BOX, 6, 4, 30)
    assert (cylinder.shape, cylinder.l, cylinder.x, cylinder.y) == (Shape.CYLINDER, 5.0, -12, 30)
    assert test.params["COM_OBS_AVOID"] == 1 and test.timeout == 400  # port 14541: PX4-Avoidance
    assert main(["simulate", str(master_written), "--runs", "1", "--no-plot", "--out", str(tmp_path / "sim")]) == 0
    assert main(["evaluate", str(master_written), "--any-layout", "--runs", "1", "--workers", "1",
                 "--out", str(tmp_path / "ev")]) == 0
    assert "Traceback" not in capsys.readouterr().err
    replicated = _quiet_load(with_assertion)  # master's to_yaml tags the variable with its Trajectory class
    assert replicated.reference_log == str(tool_folder / "case0.ulg") and replicated.replicates_flight
    legacy = _quiet_load(aerialist["0.2.1"][0]["writes"][0])
    assert legacy.obstacles == (Obstacle(6, 4, 20, 5, 22, 0, 30),) and legacy.mission is not None


# --- our loader on the rest of Aerialist's schema ------------------------------------------------------------------
def _yaml(tmp_path, text: str, name: str = "t.yaml") -> Path:
    shutil.copy(EXPERIMENTS / "case0.plan", tmp_path / "case0.plan")
    path = tmp_path / name
    path.write_text("robot:\n  mission_file: case0.plan\n" + text)
    return path


def test_the_whole_schema_is_read(tmp_path):
    path = _yaml(tmp_path, "  port: '14541'\n  params: {NAV_ACC_RAD: 2}\n"
                           "simulation:\n  simulator: ros\n  world: default\n  speed: 2\n  headless: false\n"
                           "  timeout: 20\n  home_position: [47.39, 8.54, 488]\n"
                           "  obstacles:\n  - shape: cylinder\n    size: {l: 3, w: 3, h: 9, r: 1.5}\n"
                           "    position: {x: 1, y: 2, z: 0, r: 0}\n"
                           "mission:\n  speed: 2\n  waypoints: [{x: 1, y: 2, z: 3, r: 0}]\n"
                           "  commands: [{timestamp: 1, mode: 3, x: 0, y: 0, z: 0.5, r: 0}]\n"
                           "agent: {engine: docker, path: /tmp, id: x}\nassertion: {variable: trajectory}\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing here is read with a warning
        test = load_test(path)
    assert test.obstacles == (Obstacle(3, 3, 9, 1, 2, 0, 0, Shape.CYLINDER),)
    assert test.timeout == 40.0  # Aerialist's timeout is wall-clock: at speed 2, 40 s of the flight
    assert test.home == (47.39, 8.54, 488.0) and test.params["COM_OBS_AVOID"] == 1
    save_test(test, tmp_path / "again.yaml")
    assert load_test(tmp_path / "again.yaml").key() == test.key()


def test_the_timeout_ends_the_flight(tmp_path):
    test = _quiet_load(_yaml(tmp_path, "simulation:\n  timeout: 12\n"))
    run = simulate(test, runs=1, seed=0)[0]
    assert run.status.value == "timeout" and run.duration == pytest.approx(12.0, abs=0.05)


@pytest.mark.parametrize("text, warning", [
    ("simulation:\n  obstacles:\n  - {shape: BOX, size: {l: 2, w: 3, h: 4}, position: {x: 9, y: 9}}\n",
     "obstacles 0: shape 'BOX' is read as box, but Aerialist builds no geometry for it (write 'box')"),
    ("simulation:\n  obstacles:\n  - {shape: TREE, size: {l: 2, h: 4}, position: {x: 9, y: 9}}\n",
     "shape 'TREE' is read as cylinder"),
    ("simulation:\n  obstacles:\n  - {shape: cylinder, size: {l: 9, w: 1, h: 4, r: 1}, position: {x: 9, y: 9}}\n",
     "a cylinder's l and w other than 2 r are ignored"),
    ("simulation:\n  obstacles:\n  - {shape: box, size: {l: 2, w: 3, h: 4, r: 1}, position: {x: 9, y: 9}}\n",
     "size.r of a box is ignored"),
    ("simulation:\n  simulator: jmavsim\n", "simulation.simulator jmavsim: flown as gazebo is"),
    ("agent: {engine: k8s, count: 3}\n", "agent.count 3: Aerialist's agent would fly 3 runs"),
])
def test_what_aerialist_would_not_miss_is_one_warning_line(tmp_path, text, warning):
    with pytest.warns(UserWarning) as caught:
        load_test(_yaml(tmp_path, text))
    lines = [str(w.message) for w in caught if "t.yaml" in str(w.message)]
    assert len(lines) == 1 and warning in lines[0] and "\n" not in lines[0]


@pytest.mark.parametrize("text, error", [
    ("  port: cf\n", "robot.port: 'cf' is a real vehicle's (Aerialist's cf/hw port 14550), which cannot be simulated"),
    ("  port: 14542\n", "robot.port: 14542 is no PX4 SITL port of Aerialist's"),
    ("simulation:\n  simulator: airsim\n", "simulation.simulator: 'airsim': expected gazebo, ros"),
    ("simulation:\n  obstacles:\n  - {shape: cylinder, size: {l: 2, w: 2, h: 4}, position: {x: 9, y: 9}}\n",
     "obstacles[0]: size 'r': a cylinder needs its radius r > 0"),
    ("simulation:\n  obstacles:\n  - {shape: Cube, size: {l: 2, w: 2, h: 4}, position: {x: 9, y: 9}}\n",
     "unknown shape 'Cube'"),
    ("simulation:\n  world_file_name: x\n", "simulation.world_file_name: unknown field"),
    ("simulation:\n  speed: 0\n", "simulation.speed: expected a positive number"),
    ("simulation:\n  timeout: soon\n", "simulation.timeout: expected a number of seconds"),
    ("agent: {engine: cloud}\n", "agent.engine: 'cloud': expected one of local, docker, k8s"),
    ("assertion: {variable: battery}\n", "assertion.variable: 'battery': only 'trajectory' is supported"),
    ("drone:\n  mission_file: case0.plan\n  port: sitl\n", "sections 'robot' and 'drone' differ"),
])
def test_what_cannot_be_flown_is_one_error_line(tmp_path, text, error):
    with pytest.raises(InvalidTestCase) as err:
        load_test(_yaml(tmp_path, text))
    assert error in str(err.value) and "t.yaml" in str(err.value) and "\n" not in str(err.value)


def test_both_key_sets_written_and_read(tmp_path):
    """One file for both generations: each section under both names, no YAML alias (we refuse them)."""
    test = _quiet_load(EXPERIMENTS / "rq1-seed1.yaml")
    test = replace(test, obstacles=test.obstacles + (Obstacle(2, 2, 5, 40, -20, 0, 0, Shape.CYLINDER),))
    export_test(test, tmp_path / "out" / "t.yaml")
    text = (tmp_path / "out" / "t.yaml").read_text()
    assert "&id" not in text and "*id" not in text
    doc = yaml.safe_load(text)
    assert doc["robot"] == doc["drone"] and doc["mission"] == doc["test"]
    assert doc["simulation"]["obstacles"][1] == {"shape": "cylinder", "size": {"l": 2.0, "w": 2.0, "h": 5.0, "r": 1.0},
                                                 "position": {"x": 40.0, "y": -20.0, "z": 0.0, "r": 0.0}}
    again = _quiet_load(tmp_path / "out" / "t.yaml")
    assert again.key() == test.key() and again.reference_log.endswith("out/case_studies/case0.ulg")


# --- --buffer: generate and evaluate as fidelity ---------------------------------------------------------------------
def test_buffer_of_evaluate_and_generate(tmp_path, capsys):
    folder = tmp_path / "tests"
    shutil.copytree(SHARED_DATA / "competition" / "case_studies", tmp_path / "case_studies")
    folder.mkdir()
    shutil.copy(CAMBA / f"{FLIGHTS[2]}.yaml", folder)
    distances = {}
    for buffer in ("0", "0.125"):
        out = tmp_path / f"ev-{buffer}"
        assert main(["evaluate", str(folder), "--runs", "1", "--workers", "1", "--buffer", buffer,
                     "--out", str(out)]) == 0
        assert json.loads((out / "run.json").read_text())["buffer"] == float(buffer)
        with open(out / "runs.csv", newline="") as f:
            distances[buffer] = float(next(csv.DictReader(f))["distance"])
    assert distances["0.125"] == pytest.approx(distances["0"] - 0.125, abs=1e-3)
    out = tmp_path / "gen"
    assert main(["generate", "--seed", str(folder / f"{FLIGHTS[2]}.yaml"), "--budget", "1", "--runs", "1",
                 "--workers", "1", "--buffer", "0.125", "--out", str(out)]) == 0
    assert json.loads((out / "run.json").read_text())["buffer"] == 0.125
    seed_run = json.loads((out / "summary.json").read_text())["seed_runs"][0]
    assert seed_run["competition_distance"] == pytest.approx(distances["0.125"], abs=1e-3)
    capsys.readouterr()
    for argv in (["evaluate", str(folder), "--buffer", "-1"], ["generate", "--buffer", "nan"],
                 ["fidelity", str(folder), "--buffer", "-0.1"]):
        assert main([*argv, "--out", str(tmp_path / "never")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: --buffer: expected a non-negative number of metres") and "\n" not in err
    assert not (tmp_path / "never").exists()
    assert math.isfinite(distances["0"])


def test_aerialist_master_reads_the_bundled_case_studies_and_their_wind(tmp_path):
    """The case studies that ship with the package, copied into a tool's case_studies/ as compete gives them, load in
    Aerialist master from the tool's folder (its working folder, as the competition runs it), wind included."""
    from surrealist_gym.competition.rules import bundled_case_studies

    shutil.copytree(bundled_case_studies(), tmp_path / "tool" / "case_studies")
    script = r'''
import json, os, sys
from aerialist.px4.aerialist_test import AerialistTest
os.chdir(sys.argv[1])
out = {}
for name in ("mission1", "mission2", "mission3", "mission1-wind", "mission2-wind", "mission3-wind"):
    test = AerialistTest.from_yaml(f"case_studies/{name}.yaml")
    wind = test.simulation.wind
    out[name] = [test.robot.mission_file, None if wind is None else
                 [wind.velocity_mean, wind.velocity_max, list(wind.direction)]]
print(json.dumps(out))
'''
    env = tool_environment(source_of(VERSIONS["master"]), "", b"", 1)
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path / "tool")], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    read = json.loads(done.stdout.strip().splitlines()[-1])
    for n in (1, 2, 3):
        assert read[f"mission{n}"] == [f"case_studies/mission{n}.plan", None]
        assert read[f"mission{n}-wind"] == [f"case_studies/mission{n}.plan", [3, 5.0, [1, 0, 0]]]
