"""The copy of a tool's folder that ``surrealist compete`` runs it in, made without following a link out of it.

A tool folder is untrusted input. :func:`check_folder` walks it (links not followed) and refuses, in one line naming
the entry, a link whose target (resolved) is outside the folder, a link to a folder that holds it (a loop), a
broken link or a loop of links, and anything that is neither a file, a folder nor a link (FIFOs, sockets, devices).
:func:`copy_folder` copies it, checking each entry again as it goes (the folder may change in between): files and
folders as they are, a link inside the folder as a relative link to the same place in the copy. ``.git``,
``__pycache__``, ``.venv``, ``venv`` and ``.pytest_cache`` are left out of both (a tool's own virtual environment
links to its Python outside the folder).

Example::

    >>> check_folder("../shared/third_party/peers/camba/snippets")   # doctest: +SKIP
    >>> copy_folder("../shared/third_party/peers/camba/snippets", "out/tool")   # doctest: +SKIP
"""
from __future__ import annotations

import os
import shutil
import stat
from pathlib import Path
from typing import Iterator

from ...errors import SurrealistError

#: Entries of a tool's folder that are neither checked nor copied.
IGNORED = frozenset((".git", "__pycache__", ".venv", "venv", ".pytest_cache"))


def check_folder(tool) -> None:
    """Refuse (SurrealistError, one line) a tool folder holding a link out of it, a loop or a special file."""
    for _ in _entries(Path(tool)):
        pass


def copy_folder(tool, work) -> None:
    """Copy the tool's folder to ``work`` (new), as checked by :func:`check_folder`, never following a link."""
    work = Path(work)
    work.mkdir(parents=True)
    for relative, kind, target in _entries(Path(tool)):
        destination = work / relative
        if kind == "dir":
            destination.mkdir()
        elif kind == "file":
            shutil.copy2(Path(tool) / relative, destination, follow_symlinks=False)
        else:
            os.symlink(target, destination)


def _entries(tool: Path) -> Iterator[tuple[Path, str, str]]:
    """(path relative to the folder, "dir" | "file" | "link", a link's relative target) for every entry, parents
    first; SurrealistError at the first one refused."""
    root = Path(os.path.realpath(tool))
    for folder, dirs, files in os.walk(root, followlinks=False, onerror=_walk_error):
        dirs[:] = sorted(d for d in dirs if d not in IGNORED)
        here = Path(folder)
        for name in dirs + sorted(files):
            path = here / name
            relative = path.relative_to(root)
            mode = os.lstat(path).st_mode
            if stat.S_ISLNK(mode):
                yield relative, "link", _link_target(tool, root, path, relative)
                if name in dirs:
                    dirs.remove(name)  # os.walk lists a link to a folder among the folders: never entered
            elif stat.S_ISDIR(mode):
                yield relative, "dir", ""
            elif stat.S_ISREG(mode):
                yield relative, "file", ""
            else:
                raise SurrealistError(f"tool {tool}: {relative} is not a file, folder or link (a FIFO, socket or "
                                      f"device); compete copies none")


def _link_target(tool: Path, root: Path, path: Path, relative: Path) -> str:
    """A link's target relative to its own folder, when it lies inside the tool's folder and is no loop."""
    given = os.readlink(path)
    try:
        target = Path(os.path.realpath(path, strict=True))
    except (OSError, RuntimeError):
        raise SurrealistError(f"tool {tool}: {relative} is a broken link or a loop of links (-> {given}); compete "
                              f"follows no link out of a tool folder, remove it") from None
    if not target.is_relative_to(root):
        raise SurrealistError(f"tool {tool}: {relative} is a link to {target}, outside the tool's folder; compete "
                              f"follows no link out of a tool folder (copy what it needs into the folder)")
    if target.is_dir() and path.parent.is_relative_to(target):
        raise SurrealistError(f"tool {tool}: {relative} is a link to {given}, a folder that holds it (a loop); "
                              f"compete copies no loop, remove it")
    return os.path.relpath(target, path.parent)


def _walk_error(err: OSError) -> None:
    raise SurrealistError(f"{err.filename}: cannot read ({err.strerror})")
