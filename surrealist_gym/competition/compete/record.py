"""What a ``surrealist compete`` run has flown, stored as each simulation completes: ``flights.sqlite`` in its folder.

One row per ``agent.run()`` that was flown, keyed by what decides its flights: the test as flown (the bytes of our
YAML of it), the index of its first run in the session, its number of runs and the noise seed (run ``k`` of the
session draws its noise from the test, the seed and ``k``). When a killed run is started again on the same folder,
the tool (seeded alike) asks for the same tests in the same order, and each request whose key is stored is answered
from the row (its statuses, distances and the ULogs already in ``flights/``) instead of flown: the resumed run ends
with the flights, records and scores of an uninterrupted one.

Example::

    >>> record = FlightRecord(out / "flights.sqlite")                                    # doctest: +SKIP
    >>> key = flight_key(yaml_bytes, first=0, runs=1, seed=0)                           # doctest: +SKIP
    >>> record.get(key) or record.put(key, fly(...))                                    # doctest: +SKIP
"""
from __future__ import annotations

import hashlib
import json
import sqlite3
import threading
from pathlib import Path

#: The file and table of the record (``ResultsFolder.stores`` of a compete folder).
FLIGHTS = ("flights.sqlite", "flights")

_SCHEMA = """
CREATE TABLE IF NOT EXISTS flights (
    key       TEXT PRIMARY KEY,
    number    INTEGER NOT NULL,
    logs      TEXT NOT NULL,
    statuses  TEXT NOT NULL,
    distances TEXT NOT NULL,
    wall_s    REAL NOT NULL,
    error     TEXT NOT NULL
)
"""


def flight_key(test: bytes, first: int, runs: int, seed: int) -> str:
    """The key of a request: the test as flown, its first run's index in the session, its runs, the seed."""
    digest = hashlib.sha256(test)
    digest.update(f"|{first}|{runs}|{seed}".encode())
    return digest.hexdigest()


class FlightRecord:
    """The SQLite record of a compete folder's flights; each :meth:`put` is committed at once. Thread-safe."""

    def __init__(self, path) -> None:
        self.path = Path(path)
        self._db = sqlite3.connect(self.path, check_same_thread=False, isolation_level=None)
        self._db.execute(_SCHEMA)
        self._lock = threading.Lock()

    def get(self, key: str) -> dict | None:
        """The stored flight of ``key`` (logs, statuses, distances, wall_s, error), None when it is not stored or a
        ULog it names is gone."""
        with self._lock:
            row = self._db.execute("SELECT number, logs, statuses, distances, wall_s, error FROM flights "
                                   "WHERE key = ?", (key,)).fetchone()
        if row is None:
            return None
        logs = tuple(json.loads(row[1]))
        if not all(Path(log).is_file() for log in logs):
            return None
        return {"number": row[0], "logs": logs, "statuses": tuple(json.loads(row[2])),
                "distances": tuple(float(d) for d in json.loads(row[3])), "wall_s": float(row[4]), "error": row[5]}

    def put(self, key: str, number: int, logs, statuses, distances, wall_s: float, error: str) -> None:
        """Store a flight (its ULogs written already)."""
        with self._lock:
            self._db.execute("INSERT OR REPLACE INTO flights VALUES (?, ?, ?, ?, ?, ?, ?)",
                             (key, number, json.dumps(list(logs)), json.dumps(list(statuses)),
                              json.dumps([float(d) for d in distances]), float(wall_s), error))

    def __len__(self) -> int:
        with self._lock:
            return int(self._db.execute("SELECT COUNT(*) FROM flights").fetchone()[0])

    def close(self) -> None:
        """Close the file (every flight is committed already)."""
        with self._lock:
            self._db.close()
