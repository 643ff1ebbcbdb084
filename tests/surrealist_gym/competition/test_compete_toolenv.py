"""``surrealist compete --tool-env``: which Python runs a tool (ours when every module it imports is installed here,
else an environment of its own built from its requirements.txt), the cache of own environments, and the one-line
errors before anything starts."""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest

from surrealist_gym.cli import main
from surrealist_gym.competition.compete import toolenv
from surrealist_gym.competition.compete.toolenv import choose_env, env_key, own_env, requirement_lines, tool_imports
from surrealist_gym.errors import DependencyNotInstalled, SurrealistError

ROOT = Path(__file__).resolve().parents[3]
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
CAMBA = THIRD_PARTY / "peers" / "camba" / "snippets"
SNIPPETS = THIRD_PARTY / "uav-testing-competition" / "snippets"

if not THIRD_PARTY.is_dir():
    pytest.skip(f"needs the competition's tools in {THIRD_PARTY}", allow_module_level=True)


def _tool(tmp_path, body: str, requirements: str | None = "surely-not-a-package-xyz==1.0\n") -> Path:
    folder = tmp_path / "tool"
    (folder / "helpers").mkdir(parents=True)
    (folder / "case_studies").mkdir()
    for name in ("mission1.yaml", "mission1.plan", "mission-params.csv", "mission-commands.csv"):
        (folder / "case_studies" / name).write_bytes((SNIPPETS / "case_studies" / name).read_bytes())
    (folder / "helpers" / "__init__.py").write_text("")
    (folder / "cli.py").write_text(body, encoding="utf-8")
    if requirements is not None:
        (folder / "requirements.txt").write_text(requirements, encoding="utf-8")
    return folder


def test_the_tools_imports_are_read_not_run(tmp_path, monkeypatch):
    tool = _tool(tmp_path, "import os, json\nimport helpers\nfrom helpers import x\nimport numpy.linalg\n"
                           "from aerialist.px4.drone_test import DroneTest\nimport bagpy\n"
                           "def f():\n    import surely_not_installed_xyz\n")
    assert tool_imports(tool) == {"numpy": "cli.py", "surely_not_installed_xyz": "cli.py"}
    choice = choose_env(tool, "auto", tmp_path / "cache")
    assert choice.kind == "own" and choice.cache == tmp_path / "cache"
    assert choice.reason == "it imports surely_not_installed_xyz (cli.py), not installed here"
    assert choose_env(tool, "own", tmp_path / "cache").reason == "--tool-env own"
    monkeypatch.chdir(tmp_path)
    assert choose_env(tool, "own", "envs").cache == tmp_path / "envs"  # absolute: the tool runs in another folder
    with pytest.raises(DependencyNotInstalled, match=r"its cli.py imports surely_not_installed_xyz, which is not "
                                                     r"installed here \(--tool-env ours\)"):
        choose_env(tool, "ours")
    (tool / "requirements.txt").unlink()
    with pytest.raises(SurrealistError, match="no requirements.txt to build its own environment from"):
        choose_env(tool, "auto")
    with pytest.raises(SurrealistError, match="--tool-env: expected one of auto, own, ours, got 'theirs'"):
        choose_env(tool, "theirs")
    assert choose_env(_tool(tmp_path / "b", "import numpy\n"), "auto").kind == "ours"


def test_requirements_and_cache_key(tmp_path, monkeypatch):
    """CAMBA's pins are given to pip as they are, less Aerialist (from a folder, never installed); what Aerialist's
    modules import is added by name where the requirements do not name it; the cache key follows the text."""
    text = (CAMBA / "requirements.txt").read_text()
    lines, notes = requirement_lines(text + "# a comment\n-e git+https://example.org/x.git\n")
    assert "Shapely==1.8.4" in lines and not any(line.lower().startswith("aerialist") for line in lines)
    assert notes[0] == "aerialist==0.2.2: not installed (Aerialist comes from $SURREALIST_AERIALIST or --aerialist)"
    assert notes[1].startswith("-e git+https://example.org/x.git: not installed")
    assert "webdav4" in lines and "shapely" not in lines  # named by the requirements already (as Shapely)
    assert set(toolenv.AERIALIST_NEEDS) - {"shapely"} <= {line.split("==")[0].lower() for line in lines} | set(lines)
    key = env_key(text)
    assert key == env_key(text) and key != env_key(text + "numpy\n")
    assert key.startswith(f"{sys.implementation.name}-{sys.version_info.major}.{sys.version_info.minor}-")
    monkeypatch.setenv(toolenv.CACHE_ENV, str(tmp_path / "envs"))
    assert toolenv.default_cache() == tmp_path / "envs"
    monkeypatch.delenv(toolenv.CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert toolenv.default_cache() == tmp_path / "xdg" / "surrealist-gym" / "tool-envs"


def test_one_line_errors_of_the_tool_environment(tmp_path, capsys, monkeypatch):
    """--tool-env ours for a tool importing what is not here, and a cache that cannot be a folder: one line, exit
    code 2, nothing written."""
    monkeypatch.setenv("SURREALIST_AERIALIST", str(THIRD_PARTY / "aerialist-master"))
    tool = _tool(tmp_path, "import surely_not_installed_xyz\n")
    out = tmp_path / "out"
    assert main(["compete", str(tool), "mission1", "1", "--out", str(out), "--tool-env", "ours"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    line = err.strip().splitlines()[-1]
    assert line.startswith(f"error: tool {tool}: its cli.py imports surely_not_installed_xyz, which is not installed")
    assert not out.exists()
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    assert main(["compete", str(tool), "mission1", "1", "--out", str(out), "--tool-env-cache", str(blocker)]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == f"error: --tool-env-cache {blocker}: exists and is " \
                                                               f"not a folder"
    assert not out.exists()


def test_a_cached_environment_is_reused(tmp_path):
    """An environment in the cache whose build finished (its marker written last) is used as it is: no pip."""
    tool = _tool(tmp_path, "import surely_not_installed_xyz\n")
    choice = choose_env(tool, "auto", tmp_path / "cache")
    folder = choice.cache / env_key((tool / "requirements.txt").read_text())
    (folder / "bin").mkdir(parents=True)
    os.symlink(sys.executable, folder / "bin" / "python")
    (folder / "surrealist-tool-env.json").write_text(json.dumps({"substitutions": ["x==1: took x"]}))
    env = own_env(choice, tmp_path / "log.txt")
    assert env.kind == "own" and env.python == folder / "bin" / "python" and env.build_s is None
    assert env.substitutions == ("x==1: took x",) and not (tmp_path / "log.txt").exists()
    assert "reused" in env.describe()


@pytest.mark.slow
@pytest.mark.skipif(not os.environ.get("SURREALIST_TEST_OWN_ENV"),
                    reason="set SURREALIST_TEST_OWN_ENV=1: builds CAMBA's own environment from the package index "
                           "(5-6 min on 2 cores the first time; kept in $SURREALIST_TOOL_ENVS or ~/.cache)")
def test_camba_in_its_own_environment(tmp_path, monkeypatch):
    """CAMBA with --tool-env own: its pins where this Python can install them (numpy 1.23.2, matplotlib 3.6.1), the
    rest substituted and recorded; Aerialist 0.2.1 from its folder; the tool runs there unchanged."""
    import subprocess

    from surrealist_gym.competition.compete import prepare, run

    monkeypatch.setenv("SURREALIST_AERIALIST", str(THIRD_PARTY / "aerialist-0.2.1"))
    monkeypatch.delenv("AGENT", raising=False)
    result = run(prepare(CAMBA, "mission1", 10, tmp_path / "out", tool_env="own"))
    assert result.problem is None and result.tool_env.kind == "own", result.problem
    versions = subprocess.run([str(result.tool_env.python), "-c", "import numpy, matplotlib; "
                               "print(numpy.__version__, matplotlib.__version__)"], capture_output=True, text=True)
    assert versions.stdout.split() == ["1.23.2", "3.6.1"]  # CAMBA's pins, not ours
    notes = result.tool_env.substitutions
    assert any(n.startswith("aerialist==0.2.2: not installed") for n in notes)
    assert any(n.startswith("Shapely") and "does not import on this Python" in n for n in notes)
    assert result.spent == 10 and all(t.ulg is not None and t.png is not None for t in result.tests)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["tool_env"]["substitutions"] == list(notes)
