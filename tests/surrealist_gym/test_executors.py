"""Executors on real simulations: in process, a local process pool, a Dask LocalCluster; failures become runs."""
import dataclasses
import warnings

import pytest

import surrealist_gym as sg
from surrealist_gym.executors import DaskExecutor, InlineExecutor, LocalPoolExecutor, make_executor
from surrealist_gym.sim import SimConfig


@pytest.fixture(scope="module")
def test_case():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return sg.load_test(sg.data_path("rq2-seed.yaml"))


def _summary(runs):
    return [(str(getattr(r.status, "value", r.status)), round(r.min_distance, 9), r.index) for r in runs]


def test_pool_equals_inline(test_case):
    inline = InlineExecutor().run(test_case, [0, 1, 2], 5, SimConfig())
    pool = LocalPoolExecutor(workers=2)
    try:
        pooled = pool.run(test_case, [0, 1, 2], 5, SimConfig())
    finally:
        pool.close()
    assert _summary(inline) == _summary(pooled) and len(inline) == 3


@pytest.mark.parametrize("processes, threads, uav", [(2, 1, None), (1, 2, "px4-v1.12-sitl-iris")])
def test_dask_local_cluster_equals_inline(test_case, processes, threads, uav):
    """Two worker processes, or one with two threads (``dask worker --nthreads 2``: the executor splits the runs over
    every worker thread, which fly at once, PX4-Avoidance's tree too): the runs are the inline ones."""
    from surrealist_gym.sim.profiles import load_profile

    distributed = pytest.importorskip("distributed")
    config = SimConfig() if uav is None else load_profile(uav).sim_config()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with distributed.LocalCluster(n_workers=processes, threads_per_worker=threads, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            executor = make_executor(client)
            assert executor.workers == processes * threads
            remote = executor.run(test_case, [0, 1], 5, config)
    assert _summary(remote) == _summary(InlineExecutor().run(test_case, [0, 1], 5, config))


def test_a_failing_simulation_is_retried_then_recorded(test_case):
    no_mission = dataclasses.replace(test_case, mission=None)
    runs = InlineExecutor().run(no_mission, [0, 1], 0, SimConfig())
    assert [r.status for r in runs] == ["error", "error"]
    assert "no item with a position" in runs[0].message


def test_a_seed_whose_simulations_fail_is_reported_not_searched(test_case):
    from surrealist_gym.envs.generate import GenerateEnv
    from surrealist_gym.errors import SimulationError

    env = GenerateEnv(seed_test=dataclasses.replace(test_case, mission=None), runs=1, budget=2,
                                       executor="inline")
    with pytest.raises(SimulationError, match=r"none of its runs could be judged \(1 error\)"):
        env.reset(seed=0)


def test_a_dead_pool_worker_is_replaced_and_costs_nothing(test_case):
    """A worker killed mid-chunk breaks a local pool: the pool is replaced and the chunk flown again, so the runs
    are the simulator's own, equal to the inline ones (never an 'error' run)."""
    import os
    import signal

    pool = LocalPoolExecutor(workers=1)
    try:
        pool.run(test_case, [0], 5, SimConfig())  # start the pool
        pid = next(iter(pool._pool._processes))
        os.kill(pid, signal.SIGKILL)
        runs = pool.run(test_case, [0, 1], 5, SimConfig())
    finally:
        pool.close()
    assert _summary(runs) == _summary(InlineExecutor().run(test_case, [0, 1], 5, SimConfig()))


def test_infrastructure_that_fails_twice_stops_with_one_line(test_case):
    from surrealist_gym.errors import InfrastructureError
    from surrealist_gym.executors import _fly_with_retry

    class Lost:
        def result(self):
            raise ConnectionError("scheduler lost")

    with pytest.raises(InfrastructureError, match="failed twice outside the simulator \\(ConnectionError"):
        _fly_with_retry(lambda *a: Lost(), test_case, [0, 1], 5, SimConfig())


def test_a_lost_dask_scheduler_stops_the_search_with_one_line(test_case):
    """A scheduler process killed under a connected executor: nothing becomes an error run; the executor gives up
    with an InfrastructureError once the client has been cut off for its patience (25 s by default, 3 s here) on
    each of two attempts, or its reconnection window closes (distributed.comm.timeouts.connect), instead of
    waiting on the lost cluster."""
    import socket
    import subprocess
    import sys
    import time

    pytest.importorskip("distributed")
    import dask

    from surrealist_gym.errors import InfrastructureError

    with socket.socket() as free:
        free.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{free.getsockname()[1]}"
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", address.rsplit(":", 1)[1], "--no-dashboard"], **quiet)
    worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                               "--no-dashboard"], **quiet)
    try:
        with dask.config.set({"distributed.comm.timeouts.connect": "5s"}), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            executor = DaskExecutor(address, patience=3.0)
            executor.client.wait_for_workers(1, timeout=60)
            assert [r.status for r in executor.run(test_case, [0], 5, SimConfig())] != ["error"]
            scheduler.kill()
            scheduler.wait()
            time.sleep(0.5)
            with pytest.raises(InfrastructureError, match="failed twice outside the simulator"):
                executor.run(test_case, [0, 1], 5, SimConfig())
            executor.close()
    finally:
        for process in (worker, scheduler):
            process.kill()
            process.wait()


@pytest.fixture(scope="module")
def sitl_config():
    from surrealist_gym.sim.profiles import load_profile

    return load_profile("px4-v1.12-sitl-iris").sim_config()


def test_threads_equal_inline_run_for_run(test_case, sitl_config):
    """This process's threads fly the chunks of a test (PX4-Avoidance's tree and the simple planner alike) and give
    the inline runs exactly: each run's noise is its own, whichever thread flies it."""
    from surrealist_gym.executors import ThreadExecutor
    from surrealist_gym.sim.compiled.loop import fly_span

    assert fly_span.targetoptions.get("nogil") is True  # else the threads would take turns
    for config in (sitl_config, SimConfig()):
        executor = make_executor("threads", 2)
        assert isinstance(executor, ThreadExecutor) and executor.workers == 2
        try:
            threaded = executor.run(test_case, [0, 1, 2, 3], 5, config)
        finally:
            executor.close()
        inline = InlineExecutor().run(test_case, [0, 1, 2, 3], 5, config)
        assert _summary(threaded) == _summary(inline)
        assert [r.duration for r in threaded] == [r.duration for r in inline]


def test_an_env_given_threads_flies_its_runs_on_that_many_threads(test_case):
    from surrealist_gym.envs.generate import GenerateEnv
    from surrealist_gym.executors import ThreadExecutor

    env = GenerateEnv(seed_test=test_case, runs=2, budget=2, executor="threads", workers=2)
    try:
        executor = env.unwrapped.evaluator.executor
        assert isinstance(executor, ThreadExecutor) and executor.workers == 2
        _, info = env.reset(seed=0)
        assert info["fitness"] is not None
    finally:
        env.close()
