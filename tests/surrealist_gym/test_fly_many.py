"""One way to fly many tests (``executors.fly_many``) and one run record (``outcomes.RunRecord``): chunks handed to
``done`` as they complete and a resume from ``have``; a simulation error becomes an ``error`` run; ``surrealist
evaluate`` and ``surrealist fidelity`` on a Dask LocalCluster give the runs local workers give. Real flights (short
CAMBA tests, a few rows of the RILAST labelled set), real processes, a real cluster."""
import csv
import dataclasses
import math
import warnings

import numpy as np
import pytest

from surrealist_gym.cli import main
from surrealist_gym.executors import InlineExecutor, LocalPoolExecutor, _jobs, fly_many
from surrealist_gym.outcomes import RunRecord, status_counts, statuses_text
from surrealist_gym.sim.profiles import SITL_IRIS
from tests.conftest import CAMBA_FAST, SHARED_DATA

COMPETITION = SHARED_DATA / "competition"
RILAST = COMPETITION / "rilast-mission1" / "tests.csv"


@pytest.fixture(scope="module")
def tests(camba_fast_folder):
    from surrealist_gym.competition.tool_output import load_tests

    return [test for _, test in load_tests([camba_fast_folder])][:2]


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as local:
            yield local


def _same(a, b) -> bool:
    """Two runs alike: index, status, distance and duration exactly, and the flight."""
    return ((a.index, a.status, a.distance, a.duration, a.airborne) == (b.index, b.status, b.distance, b.duration,
                                                                          b.airborne)
            and np.array_equal(a.trajectory.xyz, b.trajectory.xyz))


def _rows(path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


# --- the record ----------------------------------------------------------------------------------------------------
def test_a_record_is_what_evaluate_and_fidelity_keep_and_reads_old_stores():
    crash = RunRecord(0, "collision", 3.0, 40.0, np.zeros((3, 3)), airborne=35.0)
    close, error = RunRecord(1, "success", 0.9, 50.0), RunRecord(2, "error", math.nan, 0.0, message="flipped")
    assert (crash.failed, crash.points, close.failed, close.points) == (True, 5, True, 2)
    assert (error.flown, error.failed, error.points) == (False, False, 0)
    assert crash.trajectory.t.tolist() == [0.0, 0.5, 1.0]  # an array is a trajectory of 0.5 s means
    with pytest.raises(dataclasses.FrozenInstanceError):
        crash.status = "success"
    assert statuses_text([crash, close, close, error]) == "collision:1 success:2 error:1"
    assert status_counts([close, {"status": "stuck"}]) == {"success": 1, "stuck": 1}
    back = RunRecord.from_dict(crash.to_dict(), crash.trajectory.xyz.tolist())
    assert _same(back, crash) and back.message == crash.message
    # a run as `surrealist evaluate` stored it before records kept the airborne time
    old = {"index": 3, "status": "success", "distance": 2.5, "duration": 61.0, "message": ""}
    assert RunRecord.from_dict(old, [[0, 0, 0], [1, 0, 5]]).airborne == 0.0


# --- fly_many ------------------------------------------------------------------------------------------------------
def test_jobs_fly_whole_tests_first_and_the_last_ones_run_by_run():
    assert _jobs(5, 3, 2) == [(0, [0, 1, 2])] + [(i, [k]) for i in range(1, 5) for k in range(3)]
    assert _jobs(2, 3, 1) == [(0, [0, 1, 2]), (1, [0, 1, 2])]  # one worker: whole tests


def test_chunks_are_stored_as_they_complete_and_a_resume_flies_only_the_rest(tests):
    config = SITL_IRIS.sim_config()
    inline = fly_many(tests, 2, 7, config, InlineExecutor())
    stored, seen = [], []

    def store(i, records):
        if len(stored) == 2:  # the store fails on the third chunk (a full disk): the evaluation stops there
            raise OSError("disk full")
        stored.append((i, records))

    pool = LocalPoolExecutor(2)
    try:
        with pytest.raises(OSError, match="disk full"):
            fly_many(tests, 2, 7, [config, config], pool, done=store)
        have = [{} for _ in tests]
        for i, records in stored:
            have[i].update((r.index, r) for r in records)
        flown = []
        resumed = fly_many(tests, 2, 7, config, pool, have=have, progress=lambda n, total: seen.append((n, total)),
                           done=lambda i, records: flown.extend((i, r.index) for r in records))
    finally:
        pool.close()
    held = {(i, k) for i, h in enumerate(have) for k in h}
    assert len(held) == 2 and sorted(flown) == sorted({(i, k) for i in range(2) for k in range(2)} - held)
    assert seen[0] == (2, 4) and seen[-1] == (4, 4)
    assert all(_same(a, b) for got, want in zip(resumed, inline) for a, b in zip(got, want))
    assert [[r.index for r in runs] for runs in resumed] == [[0, 1], [0, 1]]
    assert all(r.airborne > 0 and len(r.trajectory) for runs in resumed for r in runs)


def test_a_test_that_cannot_be_flown_becomes_error_runs(tests):
    no_mission = dataclasses.replace(tests[0], mission=None)
    (bad, good) = fly_many([no_mission, tests[1]], 2, 0, SITL_IRIS.sim_config(), InlineExecutor())
    assert [r.status for r in bad] == ["error", "error"] and "no item with a position" in bad[0].message
    assert not any(r.flown for r in bad) and all(r.flown for r in good)


# --- evaluate and fidelity on a Dask cluster -----------------------------------------------------------------------
def test_evaluate_on_a_dask_cluster_equals_local_workers(camba_fast_folder, cluster, tmp_path, capsys):
    local, remote = tmp_path / "local", tmp_path / "dask"
    assert main(["evaluate", str(camba_fast_folder), "--runs", "2", "--workers", "2", "--out", str(local)]) == 0
    assert main(["evaluate", str(camba_fast_folder), "--runs", "2", "--dask-scheduler", cluster.scheduler_address,
                 "--out", str(remote)]) == 0
    assert "on 2 worker(s)" in capsys.readouterr().out
    assert _rows(local / "runs.csv") == _rows(remote / "runs.csv")  # statuses, distances, durations: exactly
    assert _rows(local / "evaluation.csv") == _rows(remote / "evaluation.csv")
    assert len(_rows(remote / "runs.csv")) == 6


def test_fidelity_on_a_dask_cluster_equals_local_workers(cluster, tmp_path, shared_data):
    local, remote = tmp_path / "local", tmp_path / "dask"
    args = ["fidelity", str(RILAST), "--limit", "2", "--every", "300", "--runs", "2"]
    assert main([*args, "--workers", "2", "--out", str(local)]) == 0
    assert main([*args, "--dask-scheduler", cluster.scheduler_address, "--out", str(remote)]) == 0
    rows = _rows(remote / "fidelity.csv")
    assert _rows(local / "fidelity.csv") == rows and [r["runs"] for r in rows] == ["2", "2"]


@pytest.mark.parametrize("command", ["evaluate", "fidelity"])
def test_a_scheduler_that_cannot_be_reached_is_one_line(command, camba_fast_folder, tmp_path, capsys, shared_data):
    import dask

    first = str(camba_fast_folder / f"{CAMBA_FAST[0]}.yaml")
    given = [first] if command == "evaluate" else [str(RILAST), "--limit", "1"]
    with dask.config.set({"distributed.comm.timeouts.connect": "2s"}), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main([command, *given, "--dask-scheduler", "tcp://127.0.0.1:1", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "Traceback" not in err
    assert err.startswith("error: --dask-scheduler tcp://127.0.0.1:1: cannot connect")
