"""A command's results folder: made, locked against a second writer, resumed, kept on failure, and written.

Every command that writes a folder (the searches, ``evaluate``, ``compare``, ``compete``, ``leaderboard``,
``fidelity``, ``calibrate``) claims it through :meth:`ResultsFolder.claim`:

* **made** when new; a folder that holds something else (files, but no record of this command) is refused in one line
  naming what it holds;
* **locked** (``.lock``, an exclusive ``flock`` with the writer's process id in it): a second writer is refused in
  one line; the lock of a process that no longer runs (killed with ``kill -9``, its pool's workers still holding the
  file) is taken over;
* **resumed**: the folder records the run's settings (``run.json``, or the command's own file); claiming it again with
  the same settings resumes, with other settings it is refused in one line naming the first setting that differs;
* **kept on failure** (:meth:`ResultsFolder.keeping`): a folder that holds a stored result (a row of one of its
  SQLite stores) is never deleted; a folder made by this claim that stores nothing is removed again.

:meth:`write_json` writes a report or summary whole or not at all (a temporary file renamed over it), and
:meth:`read_json` reads it back.

Example::

    >>> folder = ResultsFolder.claim("results/ev", "evaluate", {"runs": 5, "tests": ["a.yaml"]})  # doctest: +SKIP
    >>> with folder.keeping("the same command resumes it"):                                      # doctest: +SKIP
    ...     fly(folder.path / "evaluations.sqlite")
    ...     folder.write_json("summary.json", summary)
    >>> folder.release()                                                                          # doctest: +SKIP
"""
from __future__ import annotations

import contextlib
import json
import os
import shutil
import sqlite3
from contextlib import closing
from pathlib import Path
from typing import Callable, Iterable

from ..errors import InfrastructureError, SurrealistError, one_line

LOCK_FILE = ".lock"
RUN_FILE = "run.json"
#: The store of every search and evaluation (``store.EvaluationStore``): file and table.
EVALUATIONS = ("evaluations.sqlite", "evaluations")


def _alive(pid: int) -> bool:
    """Whether a process of this id runs (a zombie counts as ended)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # a zombie (killed, not yet reaped) holds no lock of its own
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as f:
            return f.read().rsplit(")", 1)[-1].split()[0] != "Z"
    except OSError:
        return True


def count_rows(path: Path, table: str) -> int:
    """Rows of ``table`` in the SQLite file ``path`` (0 when there is none; an unreadable file that is not empty
    counts as 1, so that it is never deleted)."""
    if not path.is_file():
        return 0
    try:
        with closing(sqlite3.connect(f"file:{path}?mode=ro", uri=True)) as db:
            return int(db.execute(f"SELECT COUNT(*) FROM {table}").fetchone()[0])
    except sqlite3.Error:
        return 1 if path.stat().st_size else 0


class ResultsFolder:
    """One command's results folder (see the module docstring). Make one with :meth:`claim`.

    Attributes:
        path: the folder. command: the command that writes it (``replicate``, ``evaluate``, ``compete``, ...).
        resumed: True when the folder held this command's run already (the claim resumes it).
        fresh: True when the claim made the folder (it did not exist).
        settings: what the folder records of the run's settings (None for a command that records its own).
    """

    def __init__(self, path, command: str, *, settings_file: str = RUN_FILE, flag: str = "--out",
                 stores: Iterable[tuple[str, str]] = (EVALUATIONS,)) -> None:
        self.path = Path(path)
        self.command = command
        self.settings_file = settings_file
        self.flag = flag
        self.stores = tuple(stores)
        self.resumed = False
        self.fresh = False
        self.settings: dict | None = None
        self._lock = None

    # --- claiming --------------------------------------------------------------------------------------------------
    @classmethod
    def claim(cls, path, command: str, settings: dict | None = None, *, free: Iterable[str] = (),
              resume_only: bool = False, **kwargs) -> "ResultsFolder":
        """Make or resume the folder and lock it (one-line SurrealistError otherwise).

        Args:
            path: the folder.
            command: the command writing it; a folder recording another command's run is refused.
            settings: the run's settings (JSON values), recorded in ``settings_file`` as ``{"command": ..., ...}``
                when the folder is new, compared with the record when it is resumed (each key but those in
                ``free``, which may change: where it runs). None: the command checks and records its own
                settings in ``settings_file``; the folder only needs that file to count as this command's.
            free: settings a resume may change.
            resume_only: refuse a folder that holds no run to resume (``--resume DIR``).
            kwargs: ``settings_file``, ``flag`` (the option named in errors), ``stores`` (SQLite files, or glob
                patterns of them, and their tables: a folder whose stores hold a row is kept on failure).
        """
        folder = cls(path, command, **kwargs)
        folder._claim(settings, frozenset(free), resume_only)
        return folder

    @classmethod
    def check(cls, path, command: str, **kwargs) -> None:
        """What :meth:`claim` refuses of the folder as it is (not a folder; holding something else), checked
        before any work and without writing anything (the settings are compared when it is claimed)."""
        folder = cls(path, command, **kwargs)
        folder._check_kind()
        if folder.path.is_dir() and not (folder.path / folder.settings_file).is_file():
            folder._check_empty()

    def _check_kind(self) -> None:
        if self.path.is_symlink() or (self.path.exists() and not self.path.is_dir()):
            raise SurrealistError(f"{self.flag} {self.path}: exists and is not a folder; choose a folder")

    def _check_empty(self) -> None:
        held = sorted(p.name for p in self.path.iterdir() if p.name != LOCK_FILE)
        if held:
            more = f" and {len(held) - 1} more" if len(held) > 1 else ""
            raise SurrealistError(f"{self.flag} {self.path}: holds something else ({held[0]}{more}), not a run of "
                                  f"{self.command}; choose a new or empty folder")

    def _claim(self, settings: dict | None, free: frozenset, resume_only: bool) -> None:
        path, flag = self.path, self.flag
        self._check_kind()
        if resume_only and not (path / self.settings_file).is_file():
            raise SurrealistError(f"{flag} {path}: not a results folder to resume (no {self.settings_file})")
        if path.is_dir() and not (path / self.settings_file).is_file():
            self._check_empty()  # refused before anything is written in it (checked again once locked)
        self.fresh = not path.exists()
        lock_made = not (path / LOCK_FILE).exists()
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise SurrealistError(f"{flag} {path}: cannot make this folder ({err.strerror or one_line(err)})") from None
        try:
            self.lock()
            self._check(settings, free)
        except BaseException:
            held = self._lock is not None
            self.release(remove=self.fresh)
            if held and lock_made and not self.fresh:  # a folder refused is left as it was
                with contextlib.suppress(OSError):
                    (path / LOCK_FILE).unlink()
            raise

    def _check(self, settings: dict | None, free: frozenset) -> None:
        path, flag, record = self.path, self.flag, self.path / self.settings_file
        if not record.is_file():
            self._check_empty()
            if settings is not None:
                self.settings = dict(settings)
                self.write_json(self.settings_file, {"command": self.command, **settings})
            return
        if settings is None:  # the command's own record: it checks it
            self.resumed = True
            return
        before = self.read_json(self.settings_file)
        if isinstance(before, dict) and self.settings_file != RUN_FILE:  # a file of the command's own name
            before = {"command": self.command, **before}  # (written before it recorded the command: still its)
        if not isinstance(before, dict) or before.get("command") != self.command:
            other = before.get("command") if isinstance(before, dict) else None
            raise SurrealistError(f"{flag} {path}: holds {repr(other) + ' run' if other else 'another run'}, not "
                                  f"a run of {self.command}; choose another folder")
        now = json.loads(json.dumps(settings, default=str))
        for key in sorted(set(now) | set(before) - {"command"}, key=lambda k: (k not in now, k)):
            if key in free or key == "command":
                continue
            if before.get(key) != now.get(key):
                raise SurrealistError(f"{flag} {path}: holds a {self.command} run with other settings ({key}: "
                                      f"{before.get(key)!r} there, {now.get(key)!r} here); resume it with the same "
                                      f"settings, or choose another folder")
        self.settings = {k: v for k, v in before.items() if k != "command"}
        self.resumed = True

    # --- the lock --------------------------------------------------------------------------------------------------
    def lock(self) -> None:
        """Hold ``.lock`` (an exclusive ``flock``, with this process's id in it) until :meth:`release`; take over the
        lock of a process that no longer runs; one line if another writer holds it."""
        try:
            import fcntl
        except ImportError:  # no advisory locks on this platform
            return
        if self._lock is not None:
            return
        lock_path = self.path / LOCK_FILE
        for attempt in range(2):
            try:
                handle = open(lock_path, "a+", encoding="ascii")
            except OSError as err:
                raise SurrealistError(f"{self.flag} {self.path}: cannot write in this folder "
                                      f"({err.strerror or one_line(err)})") from None
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                handle.seek(0)
                text = handle.read().strip()
                handle.close()
                holder = int(text) if text.isdigit() else 0
                if attempt == 0 and holder and not _alive(holder):
                    # its writer was killed; what still holds the file (workers it forked) is ending: a new file
                    with contextlib.suppress(OSError):
                        lock_path.unlink()
                    continue
                who = f" (process {holder})" if holder else ""
                raise SurrealistError(f"{self.flag} {self.path}: another process{who} is writing to this "
                                      f"folder") from None
            handle.seek(0)
            handle.truncate()
            handle.write(f"{os.getpid()}\n")
            handle.flush()
            self._lock = handle
            return

    def unlock(self) -> None:
        """Let the lock go (the file stays)."""
        handle, self._lock = self._lock, None
        if handle is not None:
            handle.close()

    def release(self, remove: bool = False) -> None:
        """Unlock; with ``remove``, delete the folder unless it stores a result."""
        self.unlock()
        if remove and not self.stored():
            shutil.rmtree(self.path, ignore_errors=True)

    # --- keeping ---------------------------------------------------------------------------------------------------
    def stored(self) -> int:
        """How many results the folder's stores hold (rows of its SQLite stores)."""
        return sum(count_rows(path, table) for pattern, table in self.stores
                   for path in (sorted(self.path.glob(pattern)) if "*" in pattern else [self.path / pattern]))

    @contextlib.contextmanager
    def keeping(self, resume: str = "the same command resumes it", what: str = "result(s)", said: bool = False):
        """Inside, a failure keeps the folder when it stores a result and says so in one line with ``resume`` (how
        to finish the run); a folder this claim made that stores nothing is removed again (bad input leaves
        nothing behind). Ctrl-C passes through (the folder kept or removed the same way). ``said``: an input
        error's own line already says what is kept (it passes as it is). The lock is released on leaving."""
        try:
            yield self
        except KeyboardInterrupt:
            self.release(remove=self.fresh)
            raise
        except (SurrealistError, OSError, sqlite3.Error) as err:
            stored = self.stored()
            self.release(remove=self.fresh)
            plain = isinstance(err, SurrealistError) and not isinstance(err, InfrastructureError)
            if plain and said:
                raise
            if not stored:
                if plain:
                    raise  # bad input: its own line says it all
                gone = f"{self.path} is removed" if self.fresh else f"{self.path} is left as it was"
                raise SurrealistError(f"{self._what_failed(err)}; nothing was stored, so {gone}") from None
            raise SurrealistError(f"{self._what_failed(err)}; {stored} {what} are stored in {self.path}: "
                                  f"{resume}") from None
        finally:
            self.unlock()

    def _what_failed(self, err: BaseException) -> str:
        if isinstance(err, SurrealistError):
            return str(err)
        if isinstance(err, OSError):
            return f"{err.filename or self.path}: cannot write ({err.strerror or one_line(err)})"
        return f"{self.path}: cannot store a result ({one_line(err)})"

    # --- writing ---------------------------------------------------------------------------------------------------
    def write_json(self, name: str, value, default: Callable | None = str) -> Path:
        """Write ``value`` as JSON to ``name`` in the folder, whole or not at all; returns its path."""
        target = self.path / name
        partial = target.with_name(f".{target.name}.partial")
        partial.write_text(json.dumps(value, indent=2, default=default) + "\n", encoding="utf-8")
        os.replace(partial, target)
        return target

    def read_json(self, name: str):
        """A JSON file of the folder (one-line SurrealistError when it cannot be read)."""
        return read_json(self.path / name)

    def __repr__(self) -> str:
        return f"ResultsFolder({str(self.path)!r}, {self.command!r}, resumed={self.resumed})"


def read_json(path) -> object:
    """A results folder's JSON file (its summary, its settings), or a one-line SurrealistError naming it."""
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise SurrealistError(f"{path}: not readable ({getattr(err, 'strerror', None) or type(err).__name__})") \
            from None


def read_summary(folder, name: str = "summary.json") -> dict | None:
    """A finished run's summary in ``folder`` (None when it has none yet: the run is not finished)."""
    path = Path(folder) / name
    if not path.is_file():
        return None
    summary = read_json(path)
    if not isinstance(summary, dict):
        raise SurrealistError(f"{path}: not a summary (a JSON object)")
    return summary
