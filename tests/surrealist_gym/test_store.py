import sqlite3

import pytest

import surrealist_gym as sg
from surrealist_gym.store import EvaluationStore, StoredEvaluation
from tests.conftest import EXPERIMENTS


def _evaluation(test, fitness):
    runs = ({"status": "success", "min_distance": 2.5, "duration": 43.0},)
    return StoredEvaluation(test.key(), {"obstacles": [o.to_list() for o in test.obstacles]}, (11,), runs, fitness)


def test_each_evaluation_is_durable_at_once(tmp_path):
    test = sg.load_test(EXPERIMENTS / "rq1-seed1.yaml")
    path = tmp_path / "evals.sqlite"
    store = EvaluationStore(path, search="rq1")
    store.add(_evaluation(test, -383.5))
    # a second connection (another process after a crash) sees it without close()
    other = EvaluationStore(path, search="rq1")
    got = other.get(test.key())
    assert got.fitness == -383.5 and got.runs[0]["status"] == "success" and got.seeds == (11,)
    assert len(other) == 1 and other.searches() == ["rq1"]
    assert EvaluationStore(path, search="other").get(test.key()) is None


def test_iteration_order_and_resume(tmp_path):
    test = sg.load_test(EXPERIMENTS / "rq1-seed1.yaml")
    with EvaluationStore(tmp_path / "e.sqlite") as store:
        for i in range(3):
            moved = test.with_obstacles([test.obstacles[0].__class__(*test.obstacles[0].to_list()[:3],
                                                                     i, 0, 0, 0)])
            store.add(_evaluation(moved, -float(i)))
    with EvaluationStore(tmp_path / "e.sqlite") as store:
        assert [e.fitness for e in store] == [0.0, -1.0, -2.0]


def test_not_a_database(tmp_path):
    bad = tmp_path / "bad.sqlite"
    bad.write_bytes(b"this is not sqlite" * 100)
    with pytest.raises(sg.SurrealistError, match="not an evaluation store"):
        EvaluationStore(bad)
    assert sqlite3.sqlite_version


def test_a_store_records_one_search_and_reading_changes_nothing(tmp_path):
    import shutil
    from pathlib import Path

    from surrealist_gym.errors import SurrealistError
    from surrealist_gym.store import SCHEMA_VERSION, EvaluationStore

    with EvaluationStore(tmp_path / "new.sqlite") as store:
        assert store.identity is None
        store.claim({"runs": 5, "seed": 0, "version": "0.1.0"})
        store.claim({"runs": 5, "seed": 0, "version": "0.2.0"})  # the version is recorded, not compared
        with pytest.raises(SurrealistError, match=r"another search \(runs: 5 there, 2 here\)"):
            store.claim({"runs": 2, "seed": 0, "version": "0.1.0"})
        assert store.identity["runs"] == 5
        version = store._db.execute("SELECT value FROM meta WHERE key = 'schema_version'").fetchone()[0]
        assert int(version) == SCHEMA_VERSION
    old = tmp_path / "old.sqlite"  # a store written before the meta table existed
    shutil.copy(Path(__file__).resolve().parents[1] / "data" / "stores" / "rq2-rep0.sqlite", old)
    before = old.read_bytes()
    with EvaluationStore(old) as store:
        assert store.identity is None and len(store) > 0 and next(iter(store)).fitness is not None
    assert old.read_bytes() == before
    with EvaluationStore(old) as store, pytest.warns(UserWarning, match="written before stores recorded their search"):
        store.claim({"runs": 10, "seed": 0, "version": "0.1.0"})  # resuming it: repaired, in one line
    with EvaluationStore(old) as store:
        assert store.identity["runs"] == 10
