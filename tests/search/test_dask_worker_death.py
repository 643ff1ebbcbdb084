"""A Dask worker killed in the middle of an evaluation costs a retry, not the search (real LocalCluster)."""
import os
import signal
import threading
import time
import warnings

import gymnasium as gym
import pytest

import surrealist_gym  # noqa: F401 - registers the envs

distributed = pytest.importorskip("distributed")


def _busy_worker(client, timeout: float = 60.0):
    """The address of a worker with a task in progress (polls the scheduler)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        busy = [w for w, keys in client.processing().items() if keys]
        if busy:
            return busy[0]
        time.sleep(0.02)
    return None


def test_killed_worker_costs_a_retry_not_the_search():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                      dashboard_address=None) as cluster, distributed.Client(cluster) as client:
            env = gym.make("Surrealist-Generate-v0", budget=3, runs=2, executor=client).unwrapped
            outcome = {}

            def evaluate():
                try:
                    outcome["reset"] = env.reset(seed=0)
                except Exception as err:  # noqa: BLE001 - reported below
                    outcome["error"] = err

            thread = threading.Thread(target=evaluate)
            thread.start()
            victim = _busy_worker(client)
            assert victim is not None, "no task ever started on the cluster"
            pid = client.run(os.getpid, workers=[victim])[victim]
            os.kill(pid, signal.SIGKILL)  # the worker process dies mid-evaluation; its nanny starts a new one
            thread.join(180)
            assert not thread.is_alive() and "error" not in outcome, outcome.get("error")
            _, info = outcome["reset"]
            assert len(info["statuses"]) == 2 and "error" not in info["statuses"]
            # the search goes on after the death
            _, _, _, _, step_info = env.step(env.action_for([1.0, -1.0]))
            assert step_info["evaluations"] == 2 and "error" not in step_info["statuses"]
            env.close()
