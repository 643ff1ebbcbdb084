"""The simulation server of ``surrealist compete``: flies the tests that a tool's Aerialist agents send, within budget.

A tool's process (with the shim, ``shim/surrealist_compete_shim.py``) connects to an ``AF_UNIX`` socket in a folder
only this user may enter, says hello with a key only the two processes know, and sends one JSON message per
``agent.run()`` (``shim/surrealist_compete_wire.py``: length-prefixed JSON, never pickle)::

    {"op": "fly", "agent": "DockerAgent", "api": "AerialistTest", "cwd": TOOL_FOLDER, "test": TO_DICT, "runs": N,
     "compat": [NOTES]}

Every field is checked (``request.py``: ``runs`` a whole number from 1 to the budget, ...), and every file the test
names must lie in one of the server's ``roots`` (the tool's working folder, the case study's folder, the files the
case study names), links resolved. The server writes the test as our YAML (``sim-NNNN.yaml`` in its folder: the test
as flown), flies its ``N`` runs and writes each as a ULog (``sim-NNNN-runI.ulg``), and answers ``{"ok": True,
"logs": [PATHS]}``; or ``{"ok": False, "error": ONE_LINE}`` for a bad request, a test that cannot be flown, a failed
simulation or a request over the budget, which is refused unflown. Its folder is ``compete``'s record (made again
when it is gone): the shim hands the tool copies of the ULogs in a folder of the run's own. The error line is short
and never quotes a file or an exception's text (a test naming ``/etc/shadow`` must not get a line of it back, nor
leave one in ``flights.csv``): a test our loader refuses is named by its YAML and the field the loader stopped at
(:func:`cannot_fly`).
The budget counts runs flown (one PX4 simulation each). Run ``k`` of the whole session (k = 0, 1, ... in request
order) draws its noise from (test, seed, k), so a tool that asks for the same tests in the same order gets the same
flights.

Example::

    >>> from surrealist_gym.sim.uav import decide_uav                             # doctest: +SKIP
    >>> with SimulationServer(folder, budget=10, config=decide_uav(uav="px4-v1.12-sitl-iris").config) as s:
    ...     run_the_tool(s.address, s.authkey)                                    # doctest: +SKIP
    >>> s.spent, [f.statuses for f in s.flights]                                  # doctest: +SKIP
"""
from __future__ import annotations

import hmac
import os
import re
import secrets
import shutil
import socket
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from ...aerialist import FILE_FIELDS
from ...errors import SurrealistError
from .request import AGENTS, APIS, BadRequest, check
from .shim.surrealist_compete_wire import WireError, receive, send

#: Connections a tool may hold open at once (a process of its each); more are closed unanswered.
MAX_CONNECTIONS = 64


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


#: Where the loader says a test is wrong, at the start of its message after the file: ``field 'wind'``, ``section
#: 'robot'``, ``unknown section 'x'`` (a field of the tool's, up to 60 characters), or a path to a field:
#: ``obstacles[0].size``, ``robot.port``, ``commands[2]``.
_FIELD = re.compile(r"(?:unknown section|section|field) '([^'\n]{1,60})'((?:\.\w{1,40}|\[\d{1,6}\]){0,4})"
                    r"|([A-Za-z_]\w{0,40}(?:\.\w{1,40}|\[\d{1,6}\]){1,4})(?=[: ]|$)")
_FILE_FIELDS = frozenset(key for keys in FILE_FIELDS.values() for key in keys)


def cannot_fly(err: Exception, test_file: Path, written: bool, test, cwd) -> str:
    """The one-line refusal of a test that cannot be flown. It names the file (our YAML of the test, ``test_file``,
    which the folder keeps; ``written``: whether it was written) and the field the loader stopped at, with the file
    that field names and the line of it where the loader gives one; of the error itself only its class, never its
    words, which may quote a file."""
    from .translate import aerialist_doc

    kind = type(err).__name__
    if isinstance(err, OSError):
        where = err.filename if isinstance(err.filename, str) and err.filename else test_file
        return f"the test cannot be flown: {where}: could not be written or read ({kind})"
    text = str(err)
    prefix = f"{test_file}: "
    read = written and text.startswith(prefix)  # the loader's own line, naming our YAML first
    match = _FIELD.match(text[len(prefix):] if read else text)
    if match is not None and match.group(1) is None and not read:  # a path to a field only in the loader's line
        match = None
    file = f"{test_file}" if written else f"the test (not written as {test_file})"
    why = f"{kind}; surrealist simulate {test_file} says why" if written else kind
    if match is None:
        return f"the test cannot be flown: {file}: not a test our loader reads ({why})"
    field = match.group(1) + match.group(2) if match.group(1) is not None else match.group(3)
    named = ""
    if field in _FILE_FIELDS:
        try:
            doc = aerialist_doc(test, cwd)
        except SurrealistError:
            doc = {}
        value = next((part[field] for part in (doc.get(section) for section in FILE_FIELDS)
                      if isinstance(part, dict) and isinstance(part.get(field), str)), None)
        line = re.search(r": line (\d{1,9}):", text)
        if value is not None:
            named = f" (it names {value[:300]}{f', line {line.group(1)}' if line else ''})"
    return f"the test cannot be flown: {file}: field {field!r}{named} is not what our loader reads ({why})"


class SimulationServer:
    """Flies the tool's tests (see the module docstring); a context manager that starts and stops the server.

    Args:
        folder: where the tests and ULogs are written (created, and made again whenever it is gone).
        budget: the simulations (runs) the tool may fly; a request beyond it is refused.
        config: the simulator configuration (the UAV profile's ``sim_config()``).
        seed: base seed of the runs' noise.
        workers: processes that fly the runs of one request (1: in this process).
        on_flight: called with each :class:`Flight` as it is recorded (from the server's thread).
        runaway_after: refused requests after which :attr:`runaway` is set (a tool that keeps asking; default
            :func:`default_runaway_after`).
        executor: a Dask scheduler's address (or an executor): the runs fly there instead of on ``workers``.
        record: a :class:`~surrealist_gym.competition.compete.record.FlightRecord`: every flight is stored in it as
            it completes, and a request it holds (the same test, first run index, runs and seed) is answered from it
            unflown (:attr:`replayed` counts those runs).
    """

    def __init__(self, folder, budget: int, config, seed: int = 0, workers: int = 1,
                 on_flight: Callable[[Flight], None] | None = None, runaway_after: int | None = None,
                 roots: tuple = (), executor=None, record=None) -> None:
        from ...executors import InlineExecutor, LocalPoolExecutor, make_executor

        self.folder = Path(folder)
        self.budget, self.config, self.seed = budget, config, seed
        self.roots = tuple(Path(os.path.realpath(r)) for r in roots)
        self._executor = (make_executor(executor) if executor is not None
                          else InlineExecutor() if workers <= 1 else LocalPoolExecutor(workers))
        self._on_flight = on_flight
        self._runaway_after = default_runaway_after(budget) if runaway_after is None else runaway_after
        self.runaway = threading.Event()
        self.authkey = secrets.token_bytes(32)
        self._lock = threading.RLock()  # on_flight may read the server's properties
        self._flights: list[Flight] = []
        self._notes: dict[str, None] = {}
        self._spent = 0
        self._store = record
        self.replayed = 0
        self._refused_counts: list[int] = []
        self._closing = False
        self._socket: socket.socket | None = None
        self._home: str | None = None
        self._slots = threading.BoundedSemaphore(MAX_CONNECTIONS)
        self._thread: threading.Thread | None = None

    # --- lifecycle -----------------------------------------------------------------------------------------------
    @property
    def address(self) -> str:
        """The socket a tool's shim connects to."""
        return os.path.join(self._home, "server.sock")

    def start(self) -> "SimulationServer":
        """Listen on a new socket (in a new folder of mode 0700) in a background thread; returns self."""
        self.folder.mkdir(parents=True, exist_ok=True)
        self._home = tempfile.mkdtemp(prefix="surrealist-compete-")
        self._socket = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._socket.bind(self.address)
        self._socket.listen(16)
        self._thread = threading.Thread(target=self._accept, name="surrealist-compete-server", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop listening and wake the accepting thread (once; later calls do nothing)."""
        if self._socket is None or self._closing:
            return
        self._closing = True
        try:  # wake the accepting thread
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as wake:
                wake.connect(self.address)
        except OSError:
            pass
        self._thread.join(timeout=10)
        self._socket.close()
        shutil.rmtree(self._home, ignore_errors=True)
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
                conn, _ = self._socket.accept()
            except OSError:
                if self._closing:
                    return
                continue
            if self._closing or not self._slots.acquire(blocking=False):
                conn.close()
                continue
            threading.Thread(target=self._serve, args=(conn,), daemon=True).start()

    def _serve(self, conn: socket.socket) -> None:
        try:
            with conn:
                conn.settimeout(30)  # the hello comes at once
                if not self._hello(conn):
                    return
                conn.settimeout(None)
                while True:
                    message = receive(conn)
                    try:
                        reply = self._handle(message)
                    except Exception as err:  # noqa: BLE001 - the tool gets one line; the server goes on
                        reply = {"ok": False, "error": f"internal error of surrealist compete ({type(err).__name__})"}
                    send(conn, reply)
        except (EOFError, OSError, WireError):  # the tool closed, or sent what is not a message: drop it
            return
        finally:
            self._slots.release()

    def _hello(self, conn: socket.socket) -> bool:
        message = receive(conn)
        key = message.get("key") if message.get("op") == "hello" else None
        if not isinstance(key, str) or not hmac.compare_digest(key, self.authkey.hex()):
            return False
        send(conn, {"ok": True})
        return True

    def _handle(self, message: dict) -> dict:
        with self._lock:
            try:
                request = check(message, self.budget)
            except BadRequest as err:
                agent, api = message.get("agent"), message.get("api")
                self._count_refusal(0)
                return self._record(Flight(len(self._flights) + 1, agent if agent in AGENTS else "?",
                                           api if api in APIS else "?", error=str(err)))
            for note in request.compat:
                if len(self._notes) < 64:
                    self._notes.setdefault(note)
            return self._fly(request)

    def _count_refusal(self, runs: int) -> None:
        self._refused_counts.append(runs)
        if len(self._refused_counts) >= self._runaway_after:
            self.runaway.set()

    def _fly(self, request) -> dict:
        from ...aerialist import load_test
        from .translate import outside, write_test

        number = len(self._flights) + 1
        agent, api, runs = request.agent, request.api, request.runs
        if self._spent + runs > self.budget:
            error = (f"the budget of {self.budget} simulations is spent ({self._spent} flown, this test asks for "
                     f"{runs} more)")
            self._count_refusal(runs)
            return self._record(Flight(number, agent, api, refused=True, error=error))
        start = time.perf_counter()
        stem = self.folder / f"sim-{number:04d}"
        written = False
        try:
            field = outside(request.test, request.cwd, self.roots)
            if field is not None:
                return self._record(Flight(number, agent, api, error=f"the test cannot be flown: its field {field!r} "
                                                                     f"names a file outside the tool's folder"))
            self.folder.mkdir(parents=True, exist_ok=True)  # made again if something removed it
            test_file = write_test(request.test, request.cwd, stem.with_suffix(".yaml"))
            written = True
            test = load_test(test_file)
        except (SurrealistError, ValueError, TypeError, OSError) as err:  # its words may quote a file: not sent
            return self._record(Flight(number, agent, api, str(stem.with_suffix(".yaml")) if written else "",
                                       error=cannot_fly(err, stem.with_suffix(".yaml"), written, request.test,
                                                        request.cwd)))
        first = self._spent
        self._spent += runs  # a run that fails counts as flown, as a PX4 run does
        key = None
        if self._store is not None:
            from .record import flight_key

            key = flight_key(Path(test_file).read_bytes(), first, runs, self.seed)
            stored = self._store.get(key)
            if stored is not None:  # flown before this run was interrupted: answered as it was then
                self.replayed += runs
                return self._record(Flight(number, agent, api, str(test_file), stored["logs"], stored["statuses"],
                                           stored["distances"], stored["wall_s"], error=stored["error"]))
        results = self._executor.run(test, range(first, first + runs), self.seed, self.config)
        from ...logs.ulog_writer import write_run_ulog

        logs, statuses, distances, failures = [], [], [], 0
        for i, run in enumerate(results):
            statuses.append(str(getattr(run.status, "value", run.status)))
            if not hasattr(run, "local_position"):  # executors.FailedRun: its simulation raised twice
                failures += 1
                continue
            log = f"{stem}-run{i}.ulg"
            write_run_ulog(log, run, mission=test.mission)
            logs.append(log)
            distances.append(float(run.competition_distance))
        error = "" if logs else f"the simulation failed ({failures} of {runs} runs raised)"
        wall_s = time.perf_counter() - start
        if key is not None:
            self._store.put(key, number, logs, statuses, distances, wall_s, error)
        return self._record(Flight(number, agent, api, str(test_file), tuple(logs), tuple(statuses),
                                   tuple(distances), wall_s, error=error))

    def _record(self, flight: Flight) -> dict:
        self._flights.append(flight)
        if self._on_flight is not None:
            self._on_flight(flight)
        if flight.error:
            return {"ok": False, "error": flight.error}
        return {"ok": True, "logs": list(flight.logs)}
