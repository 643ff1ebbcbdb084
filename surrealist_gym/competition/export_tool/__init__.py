"""``surrealist export-tool DIR``: a UAV Testing Competition tool folder that chooses its tests with surrealist-gym.

The tool follows the competition's submission rules (``python3 cli.py generate CASE_STUDY BUDGET``, the snippet's
``TestCase`` interface, a Dockerfile on the competition's image, ``output folder: PATH``). Its ``cli.py`` runs
``surrealist generate --case-study`` in a Python of its own (``$SURREALIST_PYTHON``, else the tool's), executes the
ranked failures through Aerialist's agents, best first, within the real budget, and writes the real failures
(``templates/cli.py`` says how). :func:`write_tool` writes::

    cli.py, testcase.py        the tool (templates/)
    surrealist-tool.json       its settings (ToolSettings), which cli.py reads
    Dockerfile, requirements.txt, README.md
    case_studies/              mission1-mission3 and the files they name, as a competition tool folder holds them
    surrealist_gym-VERSION.tar.gz   this surrealist-gym's source, which the Dockerfile installs in a venv of its own
    constraints.txt            the versions of surrealist-gym's dependencies installed here

Example::

    >>> write_tool("tmp/tool", ToolSettings(sim_budget_factor=10))   # doctest: +SKIP
"""
from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import re
import shutil
import sys
import tarfile
import tempfile
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from ...errors import SurrealistError

TEMPLATES = Path(__file__).resolve().parent / "templates"
TOOL_FILES = ("cli.py", "testcase.py", "Dockerfile", "requirements.txt", "README.md")
SETTINGS_FILE = "surrealist-tool.json"
CASE_STUDIES = ("mission1", "mission2", "mission3")
AGENTS = ("suite", "cmaes", "random", "greedy")  # the searches generate --case-study runs
#: What the source archive holds: what pyproject.toml builds the package from.
SOURCE_ITEMS = ("pyproject.toml", "README.md", "surrealist_gym", "search", "surrogates")


@dataclass(frozen=True)
class ToolSettings:
    """How the tool searches before it spends the real budget (written to ``surrealist-tool.json``)."""

    sim_budget_factor: int = 10  # the simulator's evaluations per real simulation of BUDGET
    obstacles: int = 1  # boxes per test (generate --obstacles)
    confirm: int = 5  # re-runs of each failure in the simulator, which rank them (generate --confirm)
    buffer: float = 0.125  # generate --buffer: Aerialist master's competition distance (the platform's since 2024)
    seed: int = 0  # generate --random-seed: the search's choices and the simulator's noise
    workers: int = 1  # simulator processes (the competition gives a tool 1.5 vCPU)
    agent: str = "suite"  # generate --agent: the search (suite, the default; cmaes, random, greedy to compare)
    px4_verdict: bool = False  # generate --px4-verdict: rank the failures by the model of PX4's verdict first

    def check(self) -> "ToolSettings":
        """Check every setting (one-line errors naming export-tool's flag); returns self."""
        from ...geometry import check_buffer

        lowest = {"sim_budget_factor": 1, "obstacles": 1, "confirm": 0, "seed": 0, "workers": 1}
        for name, low in lowest.items():
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                flag = "--random-seed" if name == "seed" else f"--{name.replace('_', '-')}"  # export-tool's flags
                raise SurrealistError(f"{flag}: expected a whole number >= {low}, got {value!r}")
        check_buffer(self.buffer)
        if self.agent not in AGENTS:
            raise SurrealistError(f"--agent: expected one of {', '.join(AGENTS)}, got {self.agent!r}")
        if not isinstance(self.px4_verdict, bool):
            raise SurrealistError(f"--px4-verdict: expected true or false, got {self.px4_verdict!r}")
        if self.obstacles > 3:
            raise SurrealistError(f"--obstacles: the competition allows 1 to 3 boxes, got {self.obstacles}")
        return self


def write_tool(folder, settings: ToolSettings = ToolSettings()) -> Path:
    """Write the tool into ``folder`` (new or empty; one-line SurrealistError otherwise); returns the folder."""
    from ... import __version__

    settings.check()
    folder = Path(folder)
    if folder.is_symlink():
        raise SurrealistError(f"DIR {folder}: a link (to {os.readlink(folder)}); give a new or empty folder")
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise SurrealistError(f"DIR {folder}: exists and is not an empty folder; give a new or empty folder")
    root = _source_root()
    studies = [_case_study_files(name) for name in CASE_STUDIES]  # a missing one fails before anything is written
    archive = f"surrealist_gym-{__version__}.tar.gz"
    made = [p for p in folder.parents if not p.exists()]  # the folders to remove should writing fail
    staging = None
    try:
        folder.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}.partial-", dir=folder.parent))
        _write_files(staging, settings, studies, root, archive)
        staging.chmod(0o755)
        os.replace(staging, folder)  # the whole tool or nothing (onto an empty folder too)
    except OSError as err:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
        for parent in made:
            with contextlib.suppress(OSError):
                parent.rmdir()
        raise SurrealistError(f"DIR {folder}: cannot write the tool ({err.strerror or err}); nothing is left "
                              f"there") from None
    return folder


def _write_files(folder: Path, settings: ToolSettings, studies: list, root: Path, archive: str) -> None:
    for name in TOOL_FILES:
        text = (TEMPLATES / name).read_text(encoding="utf-8")
        text = text.replace("@ARCHIVE@", archive).replace("@PYTHON_VERSION@", "%d.%d" % sys.version_info[:2])
        (folder / name).write_text(text, encoding="utf-8")
    (folder / SETTINGS_FILE).write_text(json.dumps(dataclasses.asdict(settings), indent=2) + "\n", encoding="utf-8")
    (folder / "case_studies").mkdir()
    for files in studies:
        for file in files:
            shutil.copyfile(file, folder / "case_studies" / file.name)
    _source_archive(root, folder / archive, archive[:-len(".tar.gz")])
    (folder / "constraints.txt").write_text("".join(f"{name}=={version}\n" for name, version in _dependencies()),
                                           encoding="utf-8")


def _source_root() -> Path:
    """The folder holding surrealist-gym's pyproject.toml and packages (a source checkout, installed with -e)."""
    root = Path(__file__).resolve().parents[3]
    if not all((root / item).exists() for item in SOURCE_ITEMS):
        raise SurrealistError(f"surrealist-gym's source is not beside its package in {root} (export-tool puts it in "
                              f"the tool for its Dockerfile): run it from a source checkout installed with pip -e")
    return root


def _case_study_files(name: str) -> list[Path]:
    """The case study's YAML and the mission, parameter and command files it names."""
    from ...aerialist import load_test
    from ..rules import case_study_path

    path = case_study_path(name)
    test = load_test(path)
    return [path] + [Path(f) for f in (test.mission_file, test.params_file, test.commands_file) if f]


def _source_archive(root: Path, target: Path, top: str) -> None:
    """The source as an sdist-like archive (``top/`` holding pyproject.toml and the packages), without caches."""
    def keep(info: tarfile.TarInfo):
        parts = Path(info.name).parts
        if "__pycache__" in parts or info.name.endswith(".pyc"):
            return None
        info.uid = info.gid = 0
        info.uname = info.gname = ""
        return info

    with tarfile.open(target, "w:gz") as tar:
        for item in SOURCE_ITEMS:
            tar.add(root / item, arcname=f"{top}/{item}", filter=keep)


def _dependencies() -> list[tuple[str, str]]:
    """surrealist-gym's own dependencies (not its extras) and the versions installed here."""
    found = []
    for requirement in metadata.requires("surrealist-gym") or []:
        if "extra ==" in requirement:
            continue
        name = re.match(r"[A-Za-z0-9._-]+", requirement).group(0)
        found.append((name, metadata.version(name)))
    return found


__all__ = ["ToolSettings", "write_tool"]
