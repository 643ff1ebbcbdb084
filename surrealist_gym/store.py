"""The evaluation store: every evaluation of a search is written to SQLite as it completes.

One row per evaluated test case, keyed by ``TestCase.key()``: the test (Aerialist-like dict as JSON), the seeds of
its runs, the per-run summaries (status, minimum distances, duration), the fitness and timings. A search that is
interrupted resumes from the store and loses nothing; surrogate models train on it.
"""
from __future__ import annotations

import contextlib
import json
import os
import sqlite3
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

from .errors import SurrealistError, one_line, regular_file

_SCHEMA = """
CREATE TABLE IF NOT EXISTS evaluations (
    id          INTEGER PRIMARY KEY AUTOINCREMENT,
    search      TEXT NOT NULL DEFAULT '',
    test_key    TEXT NOT NULL,
    test        TEXT NOT NULL,
    seeds       TEXT NOT NULL,
    runs        TEXT NOT NULL,
    fitness     REAL,
    info        TEXT NOT NULL DEFAULT '{}',
    sim_seconds REAL NOT NULL DEFAULT 0,
    wall_seconds REAL NOT NULL DEFAULT 0,
    created     REAL NOT NULL
);
CREATE INDEX IF NOT EXISTS evaluations_key ON evaluations (search, test_key);
CREATE TABLE IF NOT EXISTS meta (
    key         TEXT PRIMARY KEY,
    value       TEXT NOT NULL
);
"""
SCHEMA_VERSION = 2  # 1: evaluations only; 2: a meta table with the schema version and the search's identity


@dataclass(frozen=True, slots=True)
class StoredEvaluation:
    """One stored evaluation (``runs`` is a tuple of per-run summary dicts)."""

    test_key: str
    test: dict
    seeds: tuple[int, ...]
    runs: tuple[dict, ...]
    fitness: float | None
    info: dict = field(default_factory=dict)
    sim_seconds: float = 0.0
    wall_seconds: float = 0.0
    search: str = ""
    id: int | None = None
    created: float | None = None


class EvaluationStore:
    """A SQLite file of evaluations; ``search`` names separate several searches in one file.

    ``readonly``: an input store (surrogate training and evaluation) is opened read-only (SQLite ``mode=ro``): it
    must be an existing, non-empty regular file holding an evaluations table, and nothing is ever written to it (a
    writable open would turn an empty or missing file into a new database)."""

    def __init__(self, path, search: str = "", readonly: bool = False):
        self.path = os.fspath(path)
        self.search = search
        if readonly:
            regular_file(self.path, "evaluation store", SurrealistError, empty_ok=False)
        try:
            self._db = (sqlite3.connect(Path(self.path).resolve().as_uri() + "?mode=ro", uri=True) if readonly
                        else sqlite3.connect(self.path))
            tables = {r[0] for r in self._db.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            if "evaluations" not in tables:  # a new store; an existing one is not changed by reading it
                if readonly:
                    self._db.close()
                    raise SurrealistError(f"{self.path}: not an evaluation store (no evaluations table)")
                self._upgrade()
        except sqlite3.DatabaseError as err:
            raise SurrealistError(f"{self.path}: not an evaluation store ({one_line(err)})") from None

    def _upgrade(self) -> None:
        """Create the tables (or add the meta table to a store written before it existed)."""
        self._db.executescript(_SCHEMA)
        self._db.execute("INSERT OR IGNORE INTO meta (key, value) VALUES ('schema_version', ?)", (str(SCHEMA_VERSION),))
        self._db.commit()

    @property
    def identity(self) -> dict | None:
        """What the stored fitness values depend on (:meth:`claim`), or None for a store that never recorded it."""
        with self._readable():
            try:
                row = self._db.execute("SELECT value FROM meta WHERE key = ?",
                                       (f"identity:{self.search}",)).fetchone()
            except sqlite3.OperationalError as err:
                if "no such table" in str(err):  # no meta table: a store of schema version 1
                    return None
                raise
            return None if row is None else json.loads(row[0])

    def claim(self, identity: dict) -> None:
        """Record the identity of the search that writes here, or check it against the one recorded: a store holds
        the evaluations of one search (a mismatch is a one-line error naming the first difference; ``version`` is
        recorded, not compared)."""
        held = self.identity
        if held is None:
            if len(self):
                warnings.warn(f"{self.path}: written before stores recorded their search; its evaluations are taken "
                              f"as this search's, and its identity is recorded now", stacklevel=2)
            self._upgrade()
            self._db.execute("INSERT INTO meta (key, value) VALUES (?, ?)",
                             (f"identity:{self.search}", json.dumps(identity, sort_keys=True)))
            self._db.commit()
            return
        for key in sorted(set(held) | set(identity)):
            if key != "version" and held.get(key) != identity.get(key):
                if key == "physics":  # named only when not PyBullet (evaluation.named_physics)
                    there, here = (str(d.get(key) or "pybullet") for d in (held, identity))
                    raise SurrealistError(f"{self.path}: holds the evaluations of a search flown on another physics "
                                          f"({there} there, {here} here); set $SURREALIST_PHYSICS={there} to resume "
                                          f"it, or use another results folder")
                if key == "tree_reuse":  # named only where it acts (evaluation.named_tree_reuse)
                    there = str(held.get(key) or "none").split(" m")[0].replace("none", "0")
                    raise SurrealistError(f"{self.path}: holds the evaluations of a search flown with another reuse "
                                          f"of the planner's tree ({held.get(key) or 'none'} there, "
                                          f"{identity.get(key) or 'none'} here); set $SURREALIST_TREE_REUSE={there} "
                                          f"to resume it, or use another results folder")
                raise SurrealistError(f"{self.path}: holds the evaluations of another search ({key}: "
                                      f"{_short(held.get(key))} there, {_short(identity.get(key))} here); use "
                                      f"--resume with that search's options, or another results folder")

    def add(self, evaluation: StoredEvaluation, simulations: int = 0) -> int:
        """Write one evaluation and commit at once, with ``simulations`` added to the search's count of them
        (:meth:`count_simulations`) in the same transaction; returns its id."""
        if simulations:
            self.count_simulations(simulations, commit=False)
        cur = self._db.execute(
            "INSERT INTO evaluations (search, test_key, test, seeds, runs, fitness, info, sim_seconds, wall_seconds,"
            " created) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (evaluation.search or self.search, evaluation.test_key, json.dumps(evaluation.test),
             json.dumps(list(evaluation.seeds)), json.dumps(list(evaluation.runs)), evaluation.fitness,
             json.dumps(evaluation.info), evaluation.sim_seconds, evaluation.wall_seconds, time.time()))
        self._db.commit()
        return int(cur.lastrowid)

    def get(self, test_key: str) -> StoredEvaluation | None:
        """The first stored evaluation of this test in this search, or None."""
        with self._readable():
            row = self._db.execute(
                "SELECT * FROM evaluations WHERE search = ? AND test_key = ? ORDER BY id LIMIT 1",
                (self.search, test_key)).fetchone()
            return None if row is None else self._from_row(row)

    def __iter__(self) -> Iterator[StoredEvaluation]:
        with self._readable():
            cur = self._db.execute("SELECT * FROM evaluations WHERE search = ? ORDER BY id", (self.search,))
            for row in cur:
                yield self._from_row(row)

    def __len__(self) -> int:
        with self._readable():
            return self._db.execute("SELECT COUNT(*) FROM evaluations WHERE search = ?",
                                    (self.search,)).fetchone()[0]

    @contextlib.contextmanager
    def _readable(self):
        """A damaged file (corrupt pages, bytes that are not the JSON written) is one SurrealistError line."""
        try:
            yield
        except (sqlite3.DatabaseError, ValueError, TypeError, KeyError) as err:
            raise SurrealistError(f"{self.path}: a damaged evaluation store ({type(err).__name__}: "
                                  f"{one_line(err)}); move it aside or use another results folder") from None

    def count_simulations(self, n: int, commit: bool = True) -> None:
        """Add ``n`` to the simulations this search has flown (kept as evaluations or not: racing drops some), so
        a resumed search reports all of them (the meta table exists: a new store is made with it, an older one
        gains it when a search claims it)."""
        self._db.execute("INSERT INTO meta (key, value) VALUES (?, ?) ON CONFLICT(key) DO UPDATE SET "
                         "value = CAST(value AS INTEGER) + excluded.value", (f"simulations:{self.search}", int(n)))
        if commit:
            self._db.commit()

    @property
    def simulations(self) -> int:
        """The simulations this search has flown (:meth:`count_simulations`; for a store written before it was
        counted, the runs of its evaluations)."""
        with self._readable():
            try:
                row = self._db.execute("SELECT value FROM meta WHERE key = ?",
                                       (f"simulations:{self.search}",)).fetchone()
            except sqlite3.OperationalError as err:
                if "no such table" not in str(err):
                    raise
                row = None
            return int(row[0]) if row is not None else sum(len(e.runs) for e in self)

    def searches(self) -> list[str]:
        """The names of the searches the store holds, sorted."""
        return [r[0] for r in self._db.execute("SELECT DISTINCT search FROM evaluations ORDER BY search")]

    def close(self) -> None:
        """Close the database."""
        self._db.close()

    def __enter__(self) -> "EvaluationStore":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @staticmethod
    def _from_row(row) -> StoredEvaluation:
        (id_, search, key, test, seeds, runs, fitness, info, sim_s, wall_s, created) = row
        return StoredEvaluation(key, json.loads(test), tuple(json.loads(seeds)), tuple(json.loads(runs)), fitness,
                                json.loads(info), sim_s, wall_s, search, id_, created)


def _short(value) -> str:
    text = json.dumps(value, sort_keys=True)
    return text if len(text) <= 60 else text[:57] + "..."
