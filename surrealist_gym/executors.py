"""Where simulations run: in this process (on one thread or several), on a local process pool (default), or on a Dask
cluster (whose workers' threads fly in parallel: the compiled loop releases the GIL); and the one way to fly many
tests on any of them (:func:`fly_many`).

Every executor answers ``submit(task, test, indices, seed, config) -> future`` (``task`` a module-level function
such as :func:`fly`, run where the executor runs it; the future's ``done()`` and ``result()`` answer) and, built on
it, ``run(test, indices, seed, config) -> list of RunResult`` (one per run index, in order; run i of a test draws its
noise from (test, seed, i)), the evaluator's and the search agents' call. One retry policy (:func:`_fly_with_retry`)
holds for both: a simulation that raises a :class:`SurrealistError` is retried run by run, and a run that fails again
becomes a run with status ``error`` (the search goes on); any other failure is the infrastructure's (a dead worker,
a lost scheduler): the chunk is flown again, and a second such failure raises :class:`InfrastructureError`.

:func:`fly_many` flies every test's runs at once over an executor (the re-evaluation's and the fidelity measure's
call, and calibration's): whole tests first, the last ones run by run, each chunk reduced to
:class:`~surrealist_gym.outcomes.RunRecord` where it was flown, handed to ``done`` as it completes (to store it), and
runs already held (``have``) not flown again.
"""
from __future__ import annotations

import logging
import math
import os
import sys
import time
from concurrent.futures import BrokenExecutor, ProcessPoolExecutor, ThreadPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from .errors import DependencyNotInstalled, InfrastructureError, SurrealistError, one_line
from .outcomes import RunRecord
from .trajectory import Trajectory


def fly(test, indices: Sequence[int], seed: int, config) -> list:
    """Simulate the runs of ``test`` with the given indices together (the function the workers call)."""
    from .sim import simulate_runs

    return simulate_runs(test, list(indices), seed, config)


def fly_records(test, indices: Sequence[int], seed: int, config) -> list[RunRecord]:
    """:func:`fly`, each run reduced to its :class:`RunRecord` where it was flown (:func:`fly_many`'s task: only the
    records travel back, not the runs' true positions)."""
    return [RunRecord.of(r) for r in fly(test, indices, seed, config)]


@dataclass(frozen=True, slots=True)
class FailedRun:
    """A run whose simulation raised twice: status ``error``, no trajectory."""

    seed: int
    index: int
    message: str
    status: str = "error"
    min_distance: float = float("inf")
    min_distance_2d: float = float("inf")
    competition_distance: float = float("inf")
    duration: float = 0.0
    trajectory: Trajectory = field(default_factory=lambda: Trajectory(np.zeros(0), np.zeros((0, 3))))


def _die_with_parent() -> None:
    """Pool worker initializer: on Linux, end this worker when the process that started it dies (even kill -9).
    Ctrl-C is the parent's to answer (one message; it stops the workers): a worker ignores SIGINT, which the terminal
    sends to the whole process group, instead of printing its traceback."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        try:
            import ctypes

            ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass


def _fly_with_retry(submit, test, indices, seed, config, first=None) -> list:
    """Run a chunk via ``submit(test, indices, seed, config) -> future`` (``first``: its future, submitted already).

    A failure of the test itself (a :class:`SurrealistError` raised by the simulation, e.g. a mission that cannot be
    flown) is retried run by run, once, and a run that fails again becomes an ``error`` run (:class:`FailedRun`): a
    result. Any other failure is the infrastructure's (a dead worker or pool, a lost scheduler): the chunk is flown
    again (an executor replaces a broken pool when it is next given work); a second such failure raises
    :class:`InfrastructureError`, so nothing of it is stored."""
    for attempt in (1, 2):
        try:
            return (first if attempt == 1 and first is not None else submit(test, indices, seed, config)).result()
        except SurrealistError:
            break
        except Exception as err:  # noqa: BLE001 - anything else is the machinery's failure
            if attempt == 2:
                raise InfrastructureError(f"the simulations failed twice outside the simulator ({type(err).__name__}: "
                                          f"{one_line(err)})") from None
    results = []
    for index in indices:
        try:
            results.extend(submit(test, [index], seed, config).result())
        except SurrealistError as err:
            results.append(FailedRun(seed, index, f"{type(err).__name__}: {one_line(err)}"))
    return results


def _chunks(indices: Sequence[int], parts: int) -> list[list[int]]:
    size = max(1, math.ceil(len(indices) / max(parts, 1)))
    return [list(indices[i:i + size]) for i in range(0, len(indices), size)]


class _Done:
    """A 'future' for in-process runs: flown when its result is asked for."""

    def __init__(self, fn, *args):
        self._fn, self._args = fn, args

    def done(self) -> bool:
        return True

    def cancel(self) -> bool:
        return True

    def result(self):
        return self._fn(*self._args)


class _Executor:
    """``run`` built on ``submit``: the runs of a test split evenly over ``self.workers``, each chunk under the
    retry policy."""

    workers = 1

    def submit(self, task, test, indices, seed, config):
        raise NotImplementedError

    def run(self, test, indices, seed, config) -> list:
        chunks = _chunks(list(indices), self.workers)
        futures = [self.submit(fly, test, chunk, seed, config) for chunk in chunks]
        submit = self.submitter(fly)
        return [r for chunk, future in zip(chunks, futures)
                for r in _fly_with_retry(submit, test, chunk, seed, config, first=future)]

    def submitter(self, task) -> Callable:
        """``submit(test, indices, seed, config) -> future`` for ``task`` (what :func:`_fly_with_retry` calls)."""
        return lambda test, indices, seed, config: self.submit(task, test, indices, seed, config)

    def abandon(self) -> None:
        """Stop what runs now (Ctrl-C, a store that cannot be written): its results are not wanted."""

    def close(self) -> None:
        pass


class InlineExecutor(_Executor):
    """Simulate in this process, the n runs of a test together in one world."""

    def submit(self, task, test, indices, seed, config):
        """Fly the runs now, in this process, when the result is asked for."""
        return _Done(task, test, list(indices), seed, config)


#: Local worker processes when none are asked for: all cores, but no more than this (each worker holds a simulator and
#: its compiled loop; ``--workers`` asks for more).
DEFAULT_MAX_WORKERS = 8


def default_workers() -> int:
    """The local worker processes used when none are asked for: all cores, at most :data:`DEFAULT_MAX_WORKERS`."""
    return max(1, min(os.cpu_count() or 1, DEFAULT_MAX_WORKERS))


class LocalPoolExecutor(_Executor):
    """A pool of local processes (default :func:`default_workers`); the runs of one test are split evenly over the
    workers. A pool broken by a dead worker is replaced when next given work."""

    def __init__(self, workers: int | None = None):
        self.workers = workers or default_workers()
        self._pool = None

    def _new_pool(self):
        return ProcessPoolExecutor(max_workers=self.workers, initializer=_die_with_parent)

    def submit(self, task, test, indices, seed, config):
        """Submit the runs to the pool (a new pool, once, if the pool is broken); a future."""
        for attempt in (1, 2):
            if self._pool is None:
                self._pool = self._new_pool()
            try:
                return self._pool.submit(task, test, list(indices), seed, config)
            except BrokenExecutor:
                if attempt == 2:
                    raise
                self._pool.shutdown(wait=False, cancel_futures=True)
                self._pool = None

    def abandon(self) -> None:
        """End the workers now, not after their jobs (Python 3.14: ``terminate_workers``)."""
        if self._pool is not None:
            processes = list((getattr(self._pool, "_processes", None) or {}).values())
            self._pool.shutdown(wait=False, cancel_futures=True)
            for process in processes:
                process.terminate()
            self._pool = None

    def close(self) -> None:
        """Shut the pool down, cancelling what has not started."""
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None


class ThreadExecutor(LocalPoolExecutor):
    """The pool as threads of this process (default :func:`default_workers`). The compiled loop releases the GIL
    while it flies (``fly_span`` is ``nogil``), so the threads fly in parallel, as the processes do, without starting
    processes or pickling tests; results are those of :class:`InlineExecutor`, run for run. PyBullet's physics
    (``$SURREALIST_PHYSICS=pybullet``) holds the GIL: its runs take turns. A thread cannot be stopped: ``abandon``
    cancels what has not started and leaves the chunks in flight to end unwaited."""

    def _new_pool(self):
        return ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix="fly")


LOST_SCHEDULER_S = 25.0  # a chunk is given up on after its client has been cut off from the scheduler this long


class _Watched:
    """A Dask future whose result is given up on (ConnectionError) once its client has lost the scheduler for
    ``patience`` seconds, so a lost scheduler stops a search (two attempts) within a minute instead of hanging."""

    def __init__(self, future, client, patience: float):
        self._future, self._client, self._patience = future, client, patience
        self._lost_since: float | None = None

    def done(self) -> bool:
        """Whether ``result()`` answers now: the future finished, or its client has lost the scheduler for longer
        than the patience (then ``result()`` gives up)."""
        if self._future.done():
            return True
        if self._client.status == "running":
            self._lost_since = None
            return False
        self._lost_since = self._lost_since or time.monotonic()
        return time.monotonic() - self._lost_since > self._patience

    def cancel(self) -> bool:
        return self._future.cancel()

    def result(self):
        while True:
            try:
                return self._future.result(timeout=1.0)
            except TimeoutError:
                if self.done() and not self._future.done():  # the scheduler lost for longer than the patience
                    # the search reports the lost scheduler in one line; the client's reconnect traceback goes
                    logging.getLogger("distributed.client").setLevel(logging.CRITICAL)
                    raise ConnectionError(f"the Dask scheduler has been unreachable for {self._patience:.0f} s "
                                          f"(client {self._client.status})") from None


class DaskExecutor(_Executor):
    """Runs on a Dask cluster: a scheduler address (``tcp://host:port``) or a ``distributed.Client``."""

    def __init__(self, scheduler, patience: float = LOST_SCHEDULER_S):
        try:
            from distributed import Client
        except ImportError as err:
            raise DependencyNotInstalled("Dask executor needs distributed: pip install 'surrealist-gym[dask]'") from err
        try:
            self.client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
        except (OSError, TimeoutError, ValueError) as err:
            raise SurrealistError(f"--dask-scheduler {scheduler}: cannot connect ({one_line(err)})") from None
        self._own = not isinstance(scheduler, Client)
        # every worker thread flies a chunk at once (the compiled loop releases the GIL): chunks are split over them
        self.workers = max(1, sum(int(w.get("nthreads", 1))
                                  for w in self.client.scheduler_info().get("workers", {}).values()))
        self.patience = patience

    def submit(self, task, test, indices, seed, config):
        """Submit the runs to the Dask cluster; a future given up on after ``patience`` cut off from the scheduler."""
        return _Watched(self.client.submit(task, test, list(indices), seed, config, pure=False), self.client,
                        self.patience)

    def close(self) -> None:
        """Close the Dask client if this executor made it."""
        if self._own:
            self.client.close()


def make_executor(spec=None, workers: int | None = None):
    """An executor from a spec: None/"process" (local pool), "inline", "threads" (this process's threads), a Dask
    address or Client, or an executor."""
    if spec is None or spec == "process":
        return LocalPoolExecutor(workers)
    if spec == "inline":
        return InlineExecutor()
    if spec == "threads":
        return ThreadExecutor(workers)
    if isinstance(spec, str) or type(spec).__module__.startswith("distributed"):
        return DaskExecutor(spec)
    return spec  # an executor object: submit, run(test, indices, seed, config) and close()


class SharedExecutor:
    """An executor lent to several envs: each env's ``close()`` leaves it open; its owner closes ``executor``."""

    def __init__(self, executor):
        self.executor, self.workers = executor, getattr(executor, "workers", 1)

    def run(self, *args):
        """Fly on the shared executor."""
        return self.executor.run(*args)

    def close(self) -> None:
        """Nothing: the owner closes the shared executor."""


@contextmanager
def executor_for(spec=None, workers: int | None = None):
    """:func:`make_executor` for the length of a ``with``, closed after it unless ``spec`` was an executor already;
    without a spec, one worker flies in this process (:class:`InlineExecutor`)."""
    executor = make_executor("inline" if spec is None and workers == 1 else spec, workers)
    try:
        yield executor
    finally:
        if executor is not spec:
            executor.close()


def _jobs(tests: int, runs: int, workers: int) -> list[tuple[int, list[int]]]:
    """(test, run indices) to submit: whole tests first (flying runs in one world is cheaper), then the last
    ``2 * workers`` tests run by run, so the last round of the workers is made of short jobs."""
    tail = min(tests, 2 * workers) if workers > 1 else 0
    return ([(i, list(range(runs))) for i in range(tests - tail)]
            + [(i, [k]) for i in range(tests - tail, tests) for k in range(runs)])


def _first_done(pending: dict, poll_s: float = 0.02):
    """The first of the ``pending`` futures that is done (in submission order when several are)."""
    while True:
        for future in pending:
            if future.done():
                return future
        time.sleep(poll_s)


def fly_many(tests: Sequence, runs: int, seed: int, configs, executor, *,
             progress: Callable[[int, int], None] | None = None, have: Sequence[dict] | None = None,
             done: Callable[[int, list[RunRecord]], None] | None = None) -> list[tuple[RunRecord, ...]]:
    """Fly runs 0..``runs``-1 of every test on ``executor`` (any of this module's) and return each test's
    :class:`RunRecord` values, in run order.

    Args:
        tests: the test cases; configs: one SimConfig for every test, or a sequence with one per test.
        runs, seed: runs per test and the base seed (run i of a test draws its noise from (test, seed, i)).
        progress: called with (runs held, runs) as each chunk completes (and first with the runs of ``have``).
        have: per test, the runs flown before ({index: RunRecord}): not flown again.
        done: called with (test index, records) as each chunk completes, before anything else of it (to store it).

    Every job is submitted at once: whole tests first, the last ``2 * executor.workers`` tests run by run (so the
    last round is short). Each job keeps the module's retry policy: a simulation error becomes an ``error`` run, an
    infrastructure failure flies it again, twice is an :class:`InfrastructureError`. On any exception (Ctrl-C, a
    store that cannot be written) the jobs still pending are cancelled and the executor's workers stopped
    (``abandon``)."""
    configs = list(configs) if isinstance(configs, (list, tuple)) else [configs] * len(tests)
    if len(configs) != len(tests):
        raise ValueError(f"configs: expected one per test ({len(tests)}), got {len(configs)}")
    got: list[dict] = [dict(h) for h in have] if have is not None else [{} for _ in tests]
    total = len(tests) * runs
    if progress and any(got):
        progress(sum(map(len, got)), total)
    submit = executor.submitter(fly_records)
    pending: dict = {}
    try:
        for i, chunk in _jobs(len(tests), runs, max(1, int(getattr(executor, "workers", 1)))):
            if todo := [k for k in chunk if k not in got[i]]:
                pending[submit(tests[i], todo, seed, configs[i])] = (i, todo)
        while pending:
            future = _first_done(pending)
            i, chunk = pending.pop(future)
            records = [r if isinstance(r, RunRecord) else RunRecord.of(r)  # a FailedRun of the retry policy
                       for r in _fly_with_retry(submit, tests[i], chunk, seed, configs[i], first=future)]
            if done:
                done(i, records)
            got[i].update((r.index, r) for r in records)
            if progress:
                progress(sum(map(len, got)), total)
    except BaseException:
        for future in pending:
            future.cancel()
        executor.abandon()
        raise
    return [tuple(g[k] for k in range(runs)) for g in got]
