"""``surrealist compete`` and a tool that cleans up Aerialist's runtime files: each ``agent.run()`` hands the tool its
ULogs in a folder of the run's own (``results/logs/<id>/`` in the tool's working folder, as Aerialist master's
``DockerAgent`` names it), which the tool may delete with everything in it; ``compete``'s own record
(``flights/``, ``flights.sqlite``) is elsewhere, and made again should it be removed. A test our loader refuses is
refused in one line naming our YAML of it and the field, never the words of the error. The competition's reference
generator (copied into tmp_path, a clean-up added to its generator), the real Aerialist (master), the real
simulator."""
from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

from surrealist_gym.competition.compete import prepare, run
from surrealist_gym.competition.compete.locate import AERIALIST_ENV
from tests.conftest import ROOT

THIRD_PARTY = ROOT.parent / "shared" / "third_party"
SNIPPETS = THIRD_PARTY / "uav-testing-competition" / "snippets"
MASTER = THIRD_PARTY / "aerialist-master"

if not SNIPPETS.is_dir() or not MASTER.is_dir():
    pytest.skip(f"needs the competition's reference tool and Aerialist master in {THIRD_PARTY}",
                allow_module_level=True)
for _module in ("munch", "decouple", "ruptures", "requests", "webdav4"):
    pytest.importorskip(_module, reason=f"{_module}: pip install -e '.[compete]' (Aerialist's imports)")


@pytest.fixture(autouse=True)
def aerialist_folder(monkeypatch):
    monkeypatch.setenv(AERIALIST_ENV, str(MASTER))
    monkeypatch.delenv("AGENT", raising=False)


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


HEAD = '''\
import os, shutil, sys
from aerialist.px4.aerialist_test import AerialistTest
from aerialist.px4.docker_agent import DockerAgent
from aerialist.px4.obstacle import Obstacle

test = AerialistTest.from_yaml(sys.argv[2])
test.simulation.obstacles = [Obstacle(Obstacle.Size(10, 5, 20), Obstacle.Position(-5, 25, 0, 0))]
'''


def _tool(tmp_path, body: str) -> Path:
    folder = tmp_path / "tool"
    (folder / "case_studies").mkdir(parents=True)
    for name in ("mission1.yaml", "mission1.plan", "mission-params.csv", "mission-commands.csv"):
        (folder / "case_studies" / name).write_bytes((SNIPPETS / "case_studies" / name).read_bytes())
    (folder / "cli.py").write_text(HEAD + body, encoding="utf-8")
    return folder


def test_compete_makes_its_record_folder_again_when_it_is_removed(tmp_path):
    """A tool that removes what it should not (compete's own flights/, found beside its working folder) after each
    run: the next run is flown all the same, and each run still gets a folder of its own."""
    tool = _tool(tmp_path, '''
folders = []
for i in range(3):
    log = DockerAgent(test).run()[0].log_file
    folders.append(os.path.dirname(log))
    shutil.rmtree("../flights")
print("folders:", len(set(folders)), all(os.path.isfile(os.path.join(f, os.path.basename(f) + ".yaml"))
                                         for f in folders))
print("output folder: ./")
''')
    result = run(prepare(tool, "mission1", 3, tmp_path / "out"))
    assert result.problem is None, result.problem
    assert result.spent == 3 and [f.error for f in result.flights] == ["", "", ""]
    assert "folders: 3 True" in (result.plan.out / "tool-stdout.txt").read_text(encoding="utf-8")


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
