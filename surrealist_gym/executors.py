"""Where simulations run: in this process, on a local process pool (default), or on a Dask cluster.

Every executor answers ``run(test, seeds, config) -> list of RunResult`` (one per seed, in order). A simulation
that raises is retried once on its own; if it fails again it becomes a run with status ``error`` and the search
goes on.
"""
from __future__ import annotations

import math
import os
from concurrent.futures import ProcessPoolExecutor
from typing import Sequence

from .errors import DependencyNotInstalled


def fly(test, seeds: Sequence[int], config) -> list:
    """Simulate the runs of ``test`` with the given seeds in one batch (the function the workers call)."""
    from .sim import simulate_seeds

    return list(simulate_seeds(test, seeds, config))


def _fly_with_retry(submit, test, seeds, config) -> list:
    """Run chunks via ``submit(test, seeds, config) -> future``; retry a failed chunk run by run, once."""
    from .sim import failed_run

    try:
        return submit(test, seeds, config).result()
    except Exception:  # noqa: BLE001 - any worker failure costs a retry, not the search
        results = []
        for seed in seeds:
            try:
                results.extend(submit(test, [seed], config).result())
            except Exception as err:  # noqa: BLE001
                results.append(failed_run(seed, f"{type(err).__name__}: {err}"))
        return results


def _chunks(seeds: Sequence[int], parts: int) -> list[list[int]]:
    size = max(1, math.ceil(len(seeds) / max(parts, 1)))
    return [list(seeds[i:i + size]) for i in range(0, len(seeds), size)]


class _Done:
    """A finished 'future' for in-process runs."""

    def __init__(self, fn, *args):
        self._fn, self._args = fn, args

    def result(self):
        return self._fn(*self._args)


class InlineExecutor:
    """Simulate in this process, the n runs of a test together in one world."""

    workers = 1

    def run(self, test, seeds, config) -> list:
        return _fly_with_retry(lambda *a: _Done(fly, *a), test, list(seeds), config)

    def close(self) -> None:
        pass


class LocalPoolExecutor:
    """A pool of local processes; the runs of one test are split evenly over the workers."""

    def __init__(self, workers: int | None = None):
        self.workers = workers or max(1, min(os.cpu_count() or 1, 8))
        self._pool: ProcessPoolExecutor | None = None

    def _submit(self, test, seeds, config):
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self.workers)
        return self._pool.submit(fly, test, seeds, config)

    def run(self, test, seeds, config) -> list:
        futures = [(chunk, self._submit(test, chunk, config)) for chunk in _chunks(list(seeds), self.workers)]
        results = []
        for chunk, future in futures:
            results.extend(_fly_with_retry(lambda *a, f=future: _Once(f, self._submit, a), test, chunk, config))
        return results

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None


class _Once:
    """The first call returns an already-submitted future; later calls (retries) submit anew."""

    def __init__(self, future, submit, args):
        self._future, self._submit, self._args = future, submit, args

    def result(self):
        if self._future is not None:
            future, self._future = self._future, None
            return future.result()
        return self._submit(*self._args).result()


class DaskExecutor:
    """Runs on a Dask cluster: a scheduler address (``tcp://host:port``) or a ``distributed.Client``."""

    def __init__(self, scheduler):
        try:
            from distributed import Client
        except ImportError as err:
            raise DependencyNotInstalled("Dask executor needs distributed: pip install 'surrealist-gym[dask]'") from err
        self.client = scheduler if isinstance(scheduler, Client) else Client(scheduler)
        self._own = not isinstance(scheduler, Client)
        self.workers = max(1, len(self.client.scheduler_info().get("workers", {})))

    def run(self, test, seeds, config) -> list:
        futures = [(chunk, self.client.submit(fly, test, chunk, config, pure=False))
                   for chunk in _chunks(list(seeds), self.workers)]
        results = []
        for chunk, future in futures:
            submit = (lambda t, s, c: self.client.submit(fly, t, s, c, pure=False))
            results.extend(_fly_with_retry(lambda *a, f=future: _Once(f, submit, a), test, chunk, config))
        return results

    def close(self) -> None:
        if self._own:
            self.client.close()


def make_executor(spec=None, workers: int | None = None):
    """An executor from a spec: None/"process" (local pool), "inline", a Dask address or Client, or an executor."""
    if spec is None or spec == "process":
        return LocalPoolExecutor(workers)
    if spec == "inline":
        return InlineExecutor()
    if isinstance(spec, str):
        return DaskExecutor(spec)
    if hasattr(spec, "run"):
        return spec
    return DaskExecutor(spec)
