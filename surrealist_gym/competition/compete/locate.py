"""Where ``surrealist compete`` finds Aerialist, and which of Aerialist's two APIs a competition tool uses.

Two generations are in use (COMPETITION.md section 1): the tools of 2024 import ``aerialist.px4.drone_test``
(``DroneTest``, Aerialist 0.2.x) and the 2025 snippet ``aerialist.px4.aerialist_test`` (``AerialistTest``,
master). No Aerialist holds both, so each tool runs with the first Aerialist that holds what it imports, taken from
``--aerialist DIR``, else from the folders in ``$SURREALIST_AERIALIST`` (separated by ``:``), else the one
installed in this environment. A folder is the one holding the ``aerialist`` package (or the package itself).

Example::

    >>> find_aerialist(("DroneTest",), "../shared/third_party/aerialist-0.2.1").version    # doctest: +SKIP
    '0.2.1'
"""
from __future__ import annotations

import importlib.util
import os
import re
from dataclasses import dataclass
from pathlib import Path

from ...errors import DependencyNotInstalled, SurrealistError

AERIALIST_ENV = "SURREALIST_AERIALIST"
#: Aerialist's test API -> its module in aerialist.px4.
API_MODULES = {"DroneTest": "drone_test", "AerialistTest": "aerialist_test"}


@dataclass(frozen=True, slots=True)
class AerialistSource:
    """One Aerialist: ``path`` goes first on the tool's PYTHONPATH (None: the installed package is imported)."""

    package: Path
    version: str
    apis: tuple[str, ...]
    path: Path | None = None

    def describe(self) -> str:
        """One line for the user: the Aerialist version, its test APIs and where it was found."""
        where = self.path if self.path is not None else f"{self.package} (installed)"
        return f"Aerialist {self.version} ({', '.join(self.apis) or 'no test API'}) from {where}"


def tool_apis(tool) -> tuple[str, ...]:
    """The Aerialist test APIs the tool's Python files import (``DroneTest``, ``AerialistTest``)."""
    found = set()
    for path in sorted(Path(tool).rglob("*.py")):
        if any(part.startswith(".") or part == "__pycache__" for part in path.relative_to(tool).parts):
            continue
        try:
            text = path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        found |= {api for api, module in API_MODULES.items() if f"aerialist.px4.{module}" in text}
    return tuple(api for api in API_MODULES if api in found)


def source_of(folder) -> AerialistSource | None:
    """The Aerialist in ``folder`` (the folder holding the ``aerialist`` package, or the package), else None."""
    folder = Path(folder).expanduser()
    if (folder / "aerialist" / "px4").is_dir():
        root = folder
    elif folder.name == "aerialist" and (folder / "px4").is_dir():
        root = folder.parent
    else:
        return None
    package = (root / "aerialist").resolve()
    return AerialistSource(package, _version(root), _apis(package), root.resolve())


def installed() -> AerialistSource | None:
    """The Aerialist installed in this environment, if any (found without importing it)."""
    try:
        spec = importlib.util.find_spec("aerialist")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    package = Path(list(spec.submodule_search_locations)[0]).resolve()
    try:
        from importlib.metadata import PackageNotFoundError, version

        number = version("aerialist")
    except PackageNotFoundError:
        number = "?"
    return AerialistSource(package, number, _apis(package))


def find_aerialist(needed, given=None) -> AerialistSource:
    """The first Aerialist that holds every API in ``needed``: ``given`` (a folder), else the folders of
    ``$SURREALIST_AERIALIST``, else the installed one; a one-line error naming what was looked at otherwise."""
    needed = tuple(needed)
    if given is not None:
        named = [("--aerialist", given)]
    else:
        named = [(f"${AERIALIST_ENV}", p) for p in os.environ.get(AERIALIST_ENV, "").split(os.pathsep) if p]
    candidates = []
    for origin, folder in named:
        source = source_of(folder)
        if source is None:
            raise SurrealistError(f"{origin} {folder}: not an Aerialist folder (no aerialist/px4 in it)")
        candidates.append(source)
    if given is None and installed() is not None:
        candidates.append(installed())
    for source in candidates:
        if set(needed) <= set(source.apis):
            return source
    want = " and ".join(f"{api} (aerialist/px4/{API_MODULES[api]}.py)" for api in needed) or "Aerialist"
    seen = "; ".join(s.describe() for s in candidates) or "none"
    raise DependencyNotInstalled(f"the tool imports Aerialist's {want}: give --aerialist DIR or set {AERIALIST_ENV} "
                                 f"to folders holding the aerialist package (looked at: {seen})")


def _apis(package: Path) -> tuple[str, ...]:
    return tuple(api for api, module in API_MODULES.items() if (package / "px4" / f"{module}.py").is_file())


def _version(root: Path) -> str:
    """From PKG-INFO or setup.py beside the package (an sdist or a clone), else '?'."""
    for name, pattern in (("PKG-INFO", r"^Version:\s*(\S+)"), ("setup.py", r"version\s*=\s*[\"']([^\"']+)")):
        try:
            match = re.search(pattern, (root / name).read_text(encoding="utf-8", errors="replace"), re.MULTILINE)
        except OSError:
            continue
        if match:
            return match.group(1)
    return "?"
