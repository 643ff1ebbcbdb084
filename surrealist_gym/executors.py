"""Where simulations run: in this process, on a local process pool (default), or on a Dask cluster.

Every executor answers ``run(test, indices, seed, config) -> list of RunResult`` (one per run index, in order;
run i of a test draws its noise from (test, seed, i)). A simulation that raises is retried once on its own; if it
fails again it becomes a run with status ``error`` and the search goes on.
"""
from __future__ import annotations

import logging
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .errors import DependencyNotInstalled, InfrastructureError, SurrealistError, one_line
from .trajectory import Trajectory


def fly(test, indices: Sequence[int], seed: int, config) -> list:
    """Simulate the runs of ``test`` with the given indices together (the function the workers call)."""
    from .sim import simulate_runs

    return simulate_runs(test, list(indices), seed, config)


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
    """Pool worker initializer: on Linux, end this worker when the process that started it dies (even kill -9)."""
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            import signal

            ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
        except (OSError, AttributeError):
            pass


def _fly_with_retry(submit, test, indices, seed, config, renew=lambda: None) -> list:
    """Run a chunk via ``submit(test, indices, seed, config) -> future``.

    A failure of the test itself (a :class:`SurrealistError` raised by the simulation, e.g. a mission that cannot be
    flown) is retried run by run, once, and a run that fails again becomes an ``error`` run: a result. Any other
    failure is the infrastructure's (a dead worker or pool, a lost scheduler): ``renew()`` replaces it and the chunk
    is flown again; a second such failure raises :class:`InfrastructureError`, so nothing of it is stored."""
    for attempt in (1, 2):
        try:
            return submit(test, indices, seed, config).result()
        except SurrealistError:
            break
        except Exception as err:  # noqa: BLE001 - anything else is the machinery's failure
            if attempt == 2:
                raise InfrastructureError(f"the simulations failed twice outside the simulator ({type(err).__name__}: "
                                          f"{one_line(err)})") from None
            renew()
    results = []
    for index in indices:
        try:
            results.extend(submit(test, [index], seed, config).result())
        except SurrealistError as err:
            results.append(FailedRun(seed, index, f"{type(err).__name__}: {err}"))
    return results


def _chunks(indices: Sequence[int], parts: int) -> list[list[int]]:
    size = max(1, math.ceil(len(indices) / max(parts, 1)))
    return [list(indices[i:i + size]) for i in range(0, len(indices), size)]


class _Done:
    """A finished 'future' for in-process runs."""

    def __init__(self, fn, *args):
        self._fn, self._args = fn, args

    def result(self):
        return self._fn(*self._args)


class InlineExecutor:
    """Simulate in this process, the n runs of a test together in one world."""

    workers = 1

    def run(self, test, indices, seed, config) -> list:
        return _fly_with_retry(lambda *a: _Done(fly, *a), test, list(indices), seed, config)

    def close(self) -> None:
        pass


class _ChunkedExecutor:
    """Splits the runs of a test evenly over ``self.workers``; subclasses submit one chunk with ``_submit``."""

    workers = 1

    def _submit(self, test, indices, seed, config):
        raise NotImplementedError

    def run(self, test, indices, seed, config) -> list:
        futures = [(chunk, self._submit(test, chunk, seed, config)) for chunk in _chunks(list(indices), self.workers)]
        results = []
        for chunk, future in futures:
            results.extend(_fly_with_retry(_Once(future, self._submit).submit, test, chunk, seed, config,
                                           self._renew))
        return results

    def _renew(self) -> None:
        """Replace what failed before flying a chunk again (a local pool whose worker died is broken for good)."""


class LocalPoolExecutor(_ChunkedExecutor):
    """A pool of local processes; the runs of one test are split evenly over the workers."""

    def __init__(self, workers: int | None = None):
        self.workers = workers or max(1, min(os.cpu_count() or 1, 8))
        self._pool: ProcessPoolExecutor | None = None

    def _submit(self, test, indices, seed, config):
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.workers, initializer=_die_with_parent)
        return self._pool.submit(fly, test, indices, seed, config)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None

    def _renew(self) -> None:
        self.close()


class _Once:
    """A chunk's submission: the first ``submit`` returns its already-submitted future, later ones (retries) submit
    anew."""

    def __init__(self, future, submit):
        self._future, self._submit = future, submit

    def submit(self, *args):
        if self._future is not None:
            future, self._future = self._future, None
            return future
        return self._submit(*args)


LOST_SCHEDULER_S = 25.0  # a chunk is given up on after its client has been cut off from the scheduler this long


class _Watched:
    """A Dask future whose result is given up on (ConnectionError) once its client has lost the scheduler for
    ``patience`` seconds, so a lost scheduler stops a search (two attempts) within a minute instead of hanging."""

    def __init__(self, future, client, patience: float):
        self._future, self._client, self._patience = future, client, patience

    def result(self):
        lost_since = None
        while True:
            try:
                return self._future.result(timeout=1.0)
            except TimeoutError:
                if self._client.status == "running":
                    lost_since = None
                    continue
                lost_since = lost_since or time.monotonic()
                if time.monotonic() - lost_since > self._patience:
                    # the search reports the lost scheduler in one line; the client's reconnect traceback goes
                    logging.getLogger("distributed.client").setLevel(logging.CRITICAL)
                    raise ConnectionError(f"the Dask scheduler has been unreachable for {self._patience:.0f} s "
                                          f"(client {self._client.status})") from None


class DaskExecutor(_ChunkedExecutor):
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
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))
        self.patience = patience

    def _submit(self, test, indices, seed, config):
        return _Watched(self.client.submit(fly, test, indices, seed, config, pure=False), self.client, self.patience)

    def close(self) -> None:
        if self._own:
            self.client.close()


def make_executor(spec=None, workers: int | None = None):
    """An executor from a spec: None/"process" (local pool), "inline", a Dask address or Client, or an executor."""
    if spec is None or spec == "process":
        return LocalPoolExecutor(workers)
    if spec == "inline":
        return InlineExecutor()
    if isinstance(spec, str) or type(spec).__module__.startswith("distributed"):
        return DaskExecutor(spec)
    return spec  # an executor object: run(test, indices, seed, config) and close()
