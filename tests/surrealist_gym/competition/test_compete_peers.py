"""``surrealist compete`` on the public competition tools, unedited: CAMBA, DeepHyperion-UAV, PALM, TGen-UQ and
OptObstacles (2024 and 2025; AmbieGen and the reference generator are in test_compete.py), each on one of the sample
case studies at budget 10, with the real Aerialist 0.2.1 and the real simulator, through the real command. Each runs
in this environment (``--tool-env auto`` finds every module it imports installed: ``[compete-tools]``)."""
from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

from surrealist_gym.cli import main
from surrealist_gym.competition.compete.locate import AERIALIST_ENV
from surrealist_gym.competition.compete.toolenv import choose_env, missing_here

ROOT = Path(__file__).resolve().parents[3]
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
PEERS = THIRD_PARTY / "peers"
LEGACY = THIRD_PARTY / "aerialist-0.2.1"
#: tool -> (its folder, the case study it runs on here, the simulations it asks for past a budget of 10, whether it
#: writes every test it flew or only those it found closer than 1.5 m)
TOOLS = {
    "camba": (PEERS / "camba" / "snippets", "mission1", 0, "close"),
    "deephyperion-uav": (PEERS / "deephyperion-uav" / "DeepHyperion", "mission2", 20, "close"),  # 30 first
    "palm": (PEERS / "palm" / "snippets", "mission3", 1, "close"),  # its root, then one test per unit of budget
    "tgen-uq": (PEERS / "tgen-uq" / "snippets", "mission1", 0, "all"),
    "optobstacles": (PEERS / "optobstacles" / "snippets", "mission3", 0, "close"),
}
BUDGET = 10

if not PEERS.is_dir():
    pytest.skip(f"needs the competition's peer tools in {PEERS}", allow_module_level=True)
for _module in ("munch", "decouple", "ruptures", "requests", "webdav3", "pymoo", "seaborn", "more_itertools"):
    pytest.importorskip(_module, reason=f"{_module}: pip install -e '.[compete,compete-tools]'")


def _snapshot(folder: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.rglob("*")}


@pytest.fixture(scope="module", params=sorted(TOOLS))
def peer_run(request, tmp_path_factory):
    """One tool on its case study, budget 10, through ``surrealist compete`` (AGENT unset, as by default): the exit
    code, what it printed, its summary.json, its own folder before and after, and the output folder."""
    name = request.param
    folder, mission, _, _ = TOOLS[name]
    out = tmp_path_factory.mktemp(name) / "out"
    before = _snapshot(folder)
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(AERIALIST_ENV, str(LEGACY))
        patch.delenv("AGENT", raising=False)
        printed = io.StringIO()
        with contextlib.redirect_stdout(printed):
            code = main(["compete", str(folder), mission, str(BUDGET), "--out", str(out)])
    summary = json.loads((out / "summary.json").read_text())
    return name, code, printed.getvalue(), summary, before, _snapshot(folder), out


@pytest.mark.slow
def test_peer_tool_runs_unchanged(peer_run):
    """Exit code 0, every test the tool wrote (its printed output folder) has its yaml, ULog and PNG, each ULog one
    we flew, judged by the competition's distance: all the tests it flew (TGen-UQ), or those below 1.5 m (the others
    write only what they found that close, which may be none); the tool's own folder untouched."""
    name, code, printed, summary, before, after, _ = peer_run
    assert code == 0 and summary["problem"] is None, (name, summary["problem"])
    assert summary["tool_env"]["kind"] == "ours"
    assert summary["output_folder_found_by"].startswith("printed by the tool")
    assert "/out/tool/generated_tests/" in summary["output_folder"] and Path(summary["output_folder"]).is_dir()
    for test in summary["tests"]:
        assert all(Path(test[k]).is_file() for k in ("yaml", "ulg", "png")), test
        assert Path(test["png"]).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert test["flight"] is not None and test["competition_distance"] is not None
        assert test["points"] in ((1, 2, 5) if TOOLS[name][3] == "close" else (0, 1, 2, 5)), test
    if TOOLS[name][3] == "all":
        assert len(summary["tests"]) == summary["simulations"]
    assert f"simulations: {summary['simulations']} of budget {BUDGET} flown" in printed
    assert before == after  # nothing of theirs written


@pytest.mark.slow
def test_peer_tool_overspending_is_reported(peer_run):
    """A tool that asks past its budget has the excess refused (it sees failed executions), reported in the summary
    line and summary.json, and is scored as usual (exit code 0)."""
    name, code, printed, summary, _, _, out = peer_run
    rows = (out / "flights.csv").read_text().splitlines()[1:]
    unflyable = sum(1 for row in rows if "the test cannot be flown" in row)  # e.g. overlapping boxes (TGen-UQ)
    assert summary["requests"] == len(rows) == summary["simulations"] + summary["refused"] + unflyable
    assert BUDGET - unflyable <= summary["simulations"] <= BUDGET and code == 0
    assert summary["simulations"] >= 5, (name, unflyable)  # several tests flown, not only the first
    if not unflyable:
        assert summary["refused"] == TOOLS[name][2]
    line = f"budget: the tool asked for {summary['refused']} simulations past its budget of {BUDGET}; they were refused"
    assert (line in printed) == (summary["refused"] > 0)


def test_auto_runs_every_public_tool_here():
    """The environment rule picks ours for every public tool: each module they import is installed here."""
    folders = [folder for folder, _, _, _ in TOOLS.values()] + [PEERS / "ambiegen" / "snippets",
                                                             THIRD_PARTY / "uav-testing-competition" / "snippets"]
    for folder in folders:
        assert missing_here(folder) == {}, folder
        assert choose_env(folder, "auto").kind == "ours"
