"""The simulation server of ``surrealist compete``: flies the tests that a tool's Aerialist agents send, within budget.

A tool's process (with the shim, ``shim/surrealist_compete_shim.py``) connects to a
:class:`multiprocessing.connection.Listener` on a local socket, authenticated by a key only the two processes know,
and sends one message per ``agent.run()``::

    {"op": "fly", "agent": "DockerAgent", "api": "AerialistTest", "cwd": TOOL_FOLDER, "test": TO_DICT, "runs": N,
     "compat": [NOTES]}

The server writes the test as our YAML (``sim-NNNN.yaml`` in its folder: the test as flown), flies its ``N`` runs
and writes each as a ULog (``sim-NNNN-runI.ulg``), and answers ``{"ok": True, "logs": [PATHS]}``; or
``{"ok": False, "error": ONE_LINE}`` for a test that cannot be flown, a failed simulation or a request over the
budget, which is refused unflown. The budget counts runs flown (one PX4 simulation each). Run ``k`` of the whole
session (k = 0, 1, ... in request order) draws its noise from (test, seed, k), so a tool that asks for the same
tests in the same order gets the same flights.

Example::

    >>> from surrealist_gym.sim.profiles import resolve_uav                        # doctest: +SKIP
    >>> with SimulationServer(folder, budget=10, config=resolve_uav("px4-v1.12-sitl-iris").sim_config()) as s:
    ...     run_the_tool(s.address, s.authkey)                                    # doctest: +SKIP
    >>> s.spent, [f.statuses for f in s.flights]                                  # doctest: +SKIP
"""
from __future__ import annotations

import secrets
import threading
import time
from dataclasses import dataclass
from multiprocessing.connection import Client, Listener
from pathlib import Path
from typing import Callable

from ...errors import SurrealistError, one_line


@dataclass(frozen=True, slots=True)
class Flight:
    """One ``agent.run()`` of the tool.

    Attributes:
        number: 1, 2, ... in request order.
        agent: the Aerialist agent class that asked (``DockerAgent``, ...). api: ``DroneTest`` or ``AerialistTest``.
        test_file: our YAML of the test ("" when it could not be read).
        logs: one ULog per run flown. statuses: each run's status. distances: each run's competition distance [m]
            (box footprint to the 0.5 s trajectory polyline, unbuffered; inf without obstacles).
        wall_s: time to answer the request [s] (reading the test, flying, writing the ULogs).
        refused: True when the request was over the budget (nothing flown).
        error: why the tool got no result ("" when it got one).
    """

    number: int
    agent: str
    api: str
    test_file: str = ""
    logs: tuple[str, ...] = ()
    statuses: tuple[str, ...] = ()
    distances: tuple[float, ...] = ()
    wall_s: float = 0.0
    refused: bool = False
    error: str = ""


def default_runaway_after(budget: int) -> int:
    """Refused requests after which a tool counts as never stopping: ``max(100, 10 x budget)``. Tools overspend
    honestly by up to a first population (DeepHyperion-UAV evaluates 30 whatever its budget, AmbieGen a generation);
    a tool in a loop reaches this many refusals in a second or so, since a refusal costs nothing."""
    return max(100, 10 * budget)


class SimulationServer:
    """Flies the tool's tests (see the module docstring); a context manager that starts and stops the server.

    Args:
        folder: where the tests and ULogs are written (created).
        budget: the simulations (runs) the tool may fly; a request beyond it is refused.
        config: the simulator configuration (the UAV profile's ``sim_config()``).
        seed: base seed of the runs' noise.
        workers: processes that fly the runs of one request (1: in this process).
        on_flight: called with each :class:`Flight` as it is recorded (from the server's thread).
        runaway_after: refused requests after which :attr:`runaway` is set (a tool that keeps asking; default
            :func:`default_runaway_after`).
    """

    def __init__(self, folder, budget: int, config, seed: int = 0, workers: int = 1,
                 on_flight: Callable[[Flight], None] | None = None, runaway_after: int | None = None) -> None:
        from ...executors import InlineExecutor, LocalPoolExecutor

        self.folder = Path(folder)
        self.budget, self.config, self.seed = budget, config, seed
        self._executor = InlineExecutor() if workers <= 1 else LocalPoolExecutor(workers)
        self._on_flight = on_flight
        self._runaway_after = default_runaway_after(budget) if runaway_after is None else runaway_after
        self.runaway = threading.Event()
        self.authkey = secrets.token_bytes(32)
        self._lock = threading.RLock()  # on_flight may read the server's properties
        self._flights: list[Flight] = []
        self._notes: dict[str, None] = {}
        self._spent = 0
        self._refused_counts: list[int] = []
        self._closing = False
        self._listener: Listener | None = None
        self._thread: threading.Thread | None = None

    # --- lifecycle -----------------------------------------------------------------------------------------------
    @property
    def address(self) -> str:
        """The socket a tool's shim connects to."""
        return self._listener.address

    def start(self) -> "SimulationServer":
        """Listen on a new socket in a background thread; returns self."""
        self.folder.mkdir(parents=True, exist_ok=True)
        self._listener = Listener(family="AF_UNIX", authkey=self.authkey)
        self._thread = threading.Thread(target=self._accept, name="surrealist-compete-server", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop listening and wake the accepting thread (once; later calls do nothing)."""
        if self._listener is None or self._closing:
            return
        self._closing = True
        try:  # wake the accepting thread
            Client(self.address, authkey=self.authkey).close()
        except OSError:
            pass
        self._thread.join(timeout=10)
        self._listener.close()
        self._executor.close()

    def __enter__(self) -> "SimulationServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # --- what it has done ----------------------------------------------------------------------------------------
    @property
    def flights(self) -> tuple[Flight, ...]:
        """The flights served so far, in order."""
        with self._lock:
            return tuple(self._flights)

    @property
    def spent(self) -> int:
        """Runs flown so far."""
        return self._spent

    @property
    def refused(self) -> int:
        """Runs asked for beyond the budget (refused unflown)."""
        with self._lock:
            return sum(self._refused_counts)

    @property
    def notes(self) -> tuple[str, ...]:
        """What the tool's shim added to or changed in Aerialist (each once)."""
        with self._lock:
            return tuple(self._notes)

    # --- serving -------------------------------------------------------------------------------------------------
    def _accept(self) -> None:
        while not self._closing:
            try:
                conn = self._listener.accept()
            except (OSError, EOFError):
                if self._closing:
                    return
                continue
            except Exception:  # noqa: BLE001 - a client with a wrong key (AuthenticationError): ignore it
                continue
            if self._closing:
                conn.close()
                return
            threading.Thread(target=self._serve, args=(conn,), daemon=True).start()

    def _serve(self, conn) -> None:
        with conn:
            while True:
                try:
                    message = conn.recv()
                except (EOFError, OSError):
                    return
                try:
                    reply = self._handle(message)
                except Exception as err:  # noqa: BLE001 - the tool gets one line; the server goes on
                    reply = {"ok": False, "error": f"internal error of surrealist compete ({type(err).__name__}: "
                                                   f"{one_line(err)})"}
                try:
                    conn.send(reply)
                except OSError:
                    return

    def _handle(self, message) -> dict:
        if not isinstance(message, dict) or message.get("op") != "fly":
            return {"ok": False, "error": f"unknown request {message!r:.60}"}
        with self._lock:
            for note in message.get("compat") or ():
                self._notes.setdefault(str(note))
            return self._fly(message)

    def _fly(self, message: dict) -> dict:
        from ..rules import load_competition_test
        from .translate import write_test

        number = len(self._flights) + 1
        agent, api = str(message.get("agent", "?")), str(message.get("api", "?"))
        runs = int(message.get("runs") or 1)
        if self._spent + runs > self.budget:
            error = (f"the budget of {self.budget} simulations is spent ({self._spent} flown, this test asks for "
                     f"{runs} more)")
            self._refused_counts.append(runs)
            if len(self._refused_counts) >= self._runaway_after:
                self.runaway.set()
            return self._record(Flight(number, agent, api, refused=True, error=error))
        start = time.perf_counter()
        stem = self.folder / f"sim-{number:04d}"
        try:
            test_file = write_test(message.get("test"), message.get("cwd") or ".", stem.with_suffix(".yaml"))
            test = load_competition_test(test_file)
        except SurrealistError as err:
            return self._record(Flight(number, agent, api, error=f"the test cannot be flown: {err}"))
        first = self._spent
        self._spent += runs  # a run that fails counts as flown, as a PX4 run does
        results = self._executor.run(test, range(first, first + runs), self.seed, self.config)
        logs, statuses, distances, failures = [], [], [], []
        for i, run in enumerate(results):
            statuses.append(str(getattr(run.status, "value", run.status)))
            if not hasattr(run, "save_ulog"):  # executors.FailedRun: its simulation raised twice
                failures.append(run.message)
                continue
            log = f"{stem}-run{i}.ulg"
            run.save_ulog(log, mission=test.mission)
            logs.append(log)
            distances.append(float(run.competition_distance))
        error = "" if logs else f"the simulation failed: {failures[0] if failures else 'no run'}"
        return self._record(Flight(number, agent, api, str(test_file), tuple(logs), tuple(statuses),
                                   tuple(distances), time.perf_counter() - start, error=error))

    def _record(self, flight: Flight) -> dict:
        self._flights.append(flight)
        if self._on_flight is not None:
            self._on_flight(flight)
        if flight.error:
            return {"ok": False, "error": flight.error}
        return {"ok": True, "logs": list(flight.logs)}
