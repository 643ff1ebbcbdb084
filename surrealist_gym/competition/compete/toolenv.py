"""Which Python runs a competition tool's ``cli.py``: ours, or an environment of its own built from its requirements.

The rule (``--tool-env``):

- ``auto`` (default): every module the tool's Python files import (read, not run: the ``import`` statements, less
  the standard library, the tool's own modules, Aerialist and the shim's stand-ins) is installed here -> the tool runs
  with this interpreter, as it always did; else it gets an environment of its own.
- ``ours``: this interpreter; a module the tool imports that is not installed here is a one-line error before
  anything starts.
- ``own``: an environment of its own, always.

An environment of its own is a virtual environment of this Python made from the tool's ``requirements.txt`` and
what Aerialist's modules import (:data:`AERIALIST_NEEDS`, by name, where the requirements do not name them).
Aerialist itself is never installed there (it comes from ``$SURREALIST_AERIALIST`` or ``--aerialist``). The
requirements are first installed as pinned; when pip cannot, each pin the index does not have for this Python is
replaced by the package's name (the version the index offers), and when the pins still cannot go together, every pin
is dropped. Each replacement is recorded. The environment is kept in a cache (``--tool-env-cache DIR``, else
``$SURREALIST_TOOL_ENVS``, else ``~/.cache/surrealist-gym/tool-envs``), in a folder named by a hash of the
requirements, this Python's version and :data:`AERIALIST_NEEDS`, and reused by every later run with the same ones.

Example::

    >>> choice = choose_env("../shared/third_party/peers/camba/snippets", "auto")          # doctest: +SKIP
    >>> choice.kind, choice.reason                                                          # doctest: +SKIP
    ('ours', 'every module its files import is installed here')
"""
from __future__ import annotations

import ast
import hashlib
import importlib.util
import json
import os
import re
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from ...errors import DependencyNotInstalled, SurrealistError, one_line

TOOL_ENV_MODES = ("auto", "own", "ours")
CACHE_ENV = "SURREALIST_TOOL_ENVS"
#: What Aerialist's test-case, obstacle, trajectory, plot and agent modules import (0.2.x and master), as pip names.
AERIALIST_NEEDS = ("munch", "python-decouple", "pyyaml", "shapely", "matplotlib", "numpy", "pandas",
                   "similaritymeasures", "ruptures", "tslearn", "pyulog", "requests", "webdav4", "webdavclient3")
#: The modules Aerialist's modules import, tried in a new environment before it is kept (with the tool's imports).
AERIALIST_MODULES = ("munch", "decouple", "yaml", "numpy", "pandas", "scipy.spatial", "shapely.geometry",
                     "shapely.affinity", "matplotlib.pyplot", "matplotlib.patches", "similaritymeasures", "ruptures",
                     "tslearn.barycenters", "pyulog", "requests", "webdav3.client", "webdav4.client")
#: Never installed in a tool's environment: Aerialist comes from a folder; bagpy is the shim's stand-in.
NOT_INSTALLED = ("aerialist", "bagpy")
_SKIPPED_FOLDERS = {"__pycache__", "venv", ".venv", "node_modules"}
_MARKER = "surrealist-tool-env.json"


@dataclass(frozen=True, slots=True)
class EnvChoice:
    """Which environment runs the tool (``kind``: ``ours`` or ``own``) and why; ``cache`` is where an own one lives."""

    kind: str
    reason: str
    requirements: Path | None = None
    cache: Path | None = None
    imports: tuple[str, ...] = ()  # the tool's imports, tried in its own environment before it is kept


@dataclass(frozen=True, slots=True)
class ToolEnv:
    """The interpreter that runs the tool, and for an own environment its folder, what was substituted for the tool's
    pins, and the time it took to build (None: reused from the cache)."""

    kind: str
    python: Path
    reason: str
    folder: Path | None = None
    substitutions: tuple[str, ...] = ()
    build_s: float | None = None

    def describe(self) -> str:
        """One line for the user."""
        if self.kind == "ours":
            return f"tool environment: this one ({self.reason})"
        how = "reused" if self.build_s is None else f"built in {self.build_s:.0f} s"
        return f"tool environment: its own, {self.folder} ({how}; {self.reason})"

    def to_dict(self) -> dict:
        """As JSON values."""
        return {"kind": self.kind, "python": str(self.python), "reason": self.reason,
                "folder": None if self.folder is None else str(self.folder),
                "substitutions": list(self.substitutions), "build_s": self.build_s}


# --- the rule --------------------------------------------------------------------------------------------------------
def top_level_imports(nodes):
    """The top-level module of each absolute ``import`` among ``nodes`` (Python AST nodes), in order."""
    for node in nodes:
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
            [node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module else []
        yield from (name.split(".")[0] for name in names)


def tool_imports(tool) -> dict[str, str]:
    """Top-level modules the tool's Python files import (not the standard library, the tool's own modules, Aerialist
    or the shim's stand-ins) -> the first file importing each, relative to the tool's folder."""
    tool = Path(tool)
    files = [p for p in sorted(tool.rglob("*.py"))
             if not any(part.startswith(".") or part in _SKIPPED_FOLDERS for part in p.relative_to(tool).parts)]
    own = {p.stem for p in files} | {p.parent.name for p in files if p.name == "__init__.py"}
    found: dict[str, str] = {}
    for path in files:
        try:
            tree = ast.parse(path.read_text(encoding="utf-8", errors="replace"))
        except SyntaxError:
            continue
        for top in top_level_imports(ast.walk(tree)):
            if top not in own and top not in NOT_INSTALLED and top not in sys.stdlib_module_names \
                    and top != "__future__":
                found.setdefault(top, path.relative_to(tool).as_posix())
    return found


def missing_here(tool) -> dict[str, str]:
    """The modules the tool imports that this environment does not have -> the file importing each."""
    missing = {}
    for module, file in tool_imports(tool).items():
        try:
            spec = importlib.util.find_spec(module)
        except (ImportError, ValueError):
            spec = None
        if spec is None:
            missing[module] = file
    return missing


def default_cache() -> Path:
    """Where own environments are kept unless told: ``$SURREALIST_TOOL_ENVS``, else the user's cache folder."""
    given = os.environ.get(CACHE_ENV)
    if given:
        return Path(given).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "surrealist-gym" / "tool-envs"


def choose_env(tool, mode: str = "auto", cache=None) -> EnvChoice:
    """Apply the rule (module docstring) to the tool's folder; a one-line SurrealistError for a bad mode, ``ours``
    with an import not installed here, or an own environment without ``requirements.txt`` to build it from."""
    if mode not in TOOL_ENV_MODES:
        raise SurrealistError(f"--tool-env: expected one of {', '.join(TOOL_ENV_MODES)}, got {mode!r}")
    tool = Path(tool)
    missing = missing_here(tool) if mode != "own" else {}
    if mode == "ours" or (mode == "auto" and not missing):
        if missing:
            module, file = next(iter(missing.items()))
            raise DependencyNotInstalled(f"tool {tool}: its {file} imports {module}, which is not installed here "
                                         f"(--tool-env ours); install it, or give --tool-env own or auto")
        return EnvChoice("ours", "every module its files import is installed here")
    requirements = tool / "requirements.txt"
    if not requirements.is_file():
        raise SurrealistError(f"tool {tool}: no requirements.txt to build its own environment from "
                              f"({'--tool-env own' if mode == 'own' else 'it imports ' + ', '.join(missing)}, "
                              f"not installed here)")
    reason = "--tool-env own" if mode == "own" else \
        "it imports " + ", ".join(f"{m} ({f})" for m, f in missing.items()) + ", not installed here"
    cache = (Path(cache).expanduser() if cache else default_cache()).absolute()  # the tool runs in another folder
    return EnvChoice("own", reason, requirements.resolve(), cache, tuple(tool_imports(tool)))


# --- an environment of its own ---------------------------------------------------------------------------------------
def requirement_lines(text: str) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The requirements pip is given (comments, options and VCS or URL lines left out, as is Aerialist), and a note
    for each line left out."""
    kept, left = [], []
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        name = _name(line)
        if name is None or line.startswith("-") or "://" in line:
            left.append(f"{line}: not installed (not a package requirement pip is given here)")
        elif name in NOT_INSTALLED:
            left.append(f"{line}: not installed (Aerialist comes from $SURREALIST_AERIALIST or --aerialist)")
        else:
            kept.append(line)
    named = {_name(line) for line in kept}
    kept.extend(need for need in AERIALIST_NEEDS if _name(need) not in named)
    return tuple(kept), tuple(left)


def env_key(requirements_text: str) -> str:
    """The cache folder's name: a hash of the requirements, this Python's version and what Aerialist needs."""
    python = f"{sys.implementation.name}-{sys.version_info.major}.{sys.version_info.minor}"
    text = "\n".join((requirements_text, python, " ".join(AERIALIST_NEEDS)))
    return f"{python}-{hashlib.sha256(text.encode()).hexdigest()[:16]}"


def own_env(choice: EnvChoice, log=None) -> ToolEnv:
    """The tool's own environment from the cache, or built there (pip's output appended to ``log``)."""
    text = choice.requirements.read_text(encoding="utf-8", errors="replace")
    folder = choice.cache / env_key(text)
    python = folder / "bin" / "python"
    marker = folder / _MARKER
    if marker.is_file() and python.exists():
        record = json.loads(marker.read_text(encoding="utf-8"))
        return ToolEnv("own", python, choice.reason, folder, tuple(record.get("substitutions", ())))
    start = time.perf_counter()
    shutil.rmtree(folder, ignore_errors=True)  # a build that did not finish (no marker)
    folder.parent.mkdir(parents=True, exist_ok=True)
    _call([sys.executable, "-m", "venv", str(folder)], log, "could not make a virtual environment")
    substitutions = _install(python, text, log)
    substitutions += _repair(python, (*AERIALIST_MODULES, *choice.imports), log)
    marker.write_text(json.dumps({"requirements": str(choice.requirements), "substitutions": list(substitutions)},
                                 indent=2) + "\n", encoding="utf-8")  # last: the environment is complete
    return ToolEnv("own", python, choice.reason, folder, substitutions, round(time.perf_counter() - start, 1))


def _install(python: Path, text: str, log) -> tuple[str, ...]:
    """Install the requirements into the environment of ``python``; what was substituted, one line each."""
    lines, notes = requirement_lines(text)
    pip = [str(python), "-m", "pip", "install", "--disable-pip-version-check", "-q"]
    if _ok(pip + list(lines), log):
        return notes
    kept, notes = [], list(notes)
    for line in lines:
        if _name(line) == line.strip() or _ok(pip + ["--dry-run", "--no-deps", "--ignore-installed", line], log):
            kept.append(line)
        else:
            kept.append(_name(line))
            notes.append(f"{line}: not installable on this Python from the index; took the index's {_name(line)}")
    if _ok(pip + kept, log):
        return tuple(notes)
    names = [_name(line) for line in kept]
    notes.append("the remaining pins (" + ", ".join(line for line in kept if line not in names) + ") cannot be "
                 "installed together; took the versions the index offers for all")
    _call(pip + names, log, "pip could not install the tool's requirements, even unpinned")
    return tuple(notes)


_TRY_IMPORTS = """
import importlib, json, sys
from importlib.metadata import packages_distributions
dists, bad = packages_distributions(), {}
for module in sys.argv[1:]:
    try:
        importlib.import_module(module)
    except Exception as err:
        bad[module] = [dists.get(module.split(".")[0], []), f"{type(err).__name__}: {err}"[:160]]
print(json.dumps(bad))
"""


def _repair(python: Path, modules, log, rounds: int = 3) -> tuple[str, ...]:
    """Import each module in the new environment; a package that installed but does not import on this Python (e.g.
    Shapely 1.8 without its GEOS library) is replaced by the newest version the index offers that goes with every
    other package as installed (so numpy stays as pinned), else by its newest. What was replaced, one line each; a
    one-line error when a module still does not import."""
    notes = []
    for _ in range(rounds):
        done = subprocess.run([str(python), "-c", _TRY_IMPORTS, *modules], capture_output=True, text=True,
                              stdin=subprocess.DEVNULL, env={**os.environ, "MPLBACKEND": "Agg"})
        bad = json.loads(done.stdout.strip().splitlines()[-1]) if done.returncode == 0 and done.stdout.strip() else \
            {"?": [[], one_line(done.stderr or "the import check did not run", 160)]}
        if not bad:
            return tuple(notes)
        fixable = {d for dists, _ in bad.values() for d in dists}
        if not fixable:
            break
        pip = [str(python), "-m", "pip", "install", "--disable-pip-version-check", "-q", "--upgrade"]
        constraints = python.parent.parent / "surrealist-constraints.txt"
        frozen = subprocess.run([str(python), "-m", "pip", "freeze"], capture_output=True, text=True).stdout
        keep = {_name(d) for d in fixable}
        constraints.write_text("\n".join(line for line in frozen.splitlines()
                                         if "==" in line and _name(line) not in keep) + "\n", encoding="utf-8")
        if _ok(pip + ["-c", str(constraints)] + sorted(fixable), log):
            took = "the index's newest that goes with the other packages as installed"
        elif _ok(pip + sorted(fixable), log):
            took = "the index's newest"
        else:
            break
        notes.extend(f"{', '.join(dists) or module}: installed but does not import on this Python ({why}); took "
                     f"{took}" for module, (dists, why) in bad.items() if dists)
    module, (_, why) = next(iter(bad.items()))
    raise SurrealistError(f"the tool's own environment {python.parent.parent}: {module} does not import ({why}); "
                          f"see {log}")


def _name(line: str) -> str | None:
    match = re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)", line)
    return match.group(1).lower().replace("_", "-") if match else None


def _ok(command, log) -> bool:
    done = subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          stdin=subprocess.DEVNULL)
    if log is not None:
        with open(log, "a", encoding="utf-8") as f:
            f.write(f"$ {' '.join(command)}\n{done.stdout}\n(exit code {done.returncode})\n")
    return done.returncode == 0


def _call(command, log, what: str) -> None:
    if not _ok(command, log):
        raise SurrealistError(f"{what} ({' '.join(command[:4])} ...; see {log})")


__all__ = ["AERIALIST_MODULES", "AERIALIST_NEEDS", "CACHE_ENV", "TOOL_ENV_MODES", "EnvChoice", "ToolEnv", "choose_env",
           "default_cache", "env_key", "missing_here", "own_env", "requirement_lines", "tool_imports",
           "top_level_imports"]
