"""``surrealist compete`` inside a competition tool's process: Aerialist's agents fly surrealist-gym's simulator.

As Aerialist's agent modules import (``aerialist.px4.local_agent``, ``docker_agent``, ``k8s_agent``), their
``LocalAgent``, ``DockerAgent`` and ``K8sAgent`` are replaced by subclasses that start no PX4, container or job:
``run()`` sends the test (Aerialist's own ``to_dict()``) to the ``surrealist compete`` process over a local socket
(``SURREALIST_COMPETE_ADDRESS``; length-prefixed JSON, ``surrealist_compete_wire``), which flies it and writes each
run as a ULog, and returns what Aerialist's agent returns: a list with one result per run, ``DroneTestResult``
(Aerialist 0.2.x) or ``AerialistTestResult`` (master), built by Aerialist's own code from the ULog at its
``log_file`` (so ``record`` is Aerialist's ``Trajectory``). A test whose ``agent:`` section gives a count flies that
many runs, any other ``SURREALIST_COMPETE_RUNS`` (default 1). A refused or failed flight raises ``RuntimeError`` in
the tool, as a failed PX4 run raises there.

Each ``run()`` gets a folder of its own, where Aerialist master's ``DockerAgent.import_config`` puts a run: the
test's ``agent.path``, else the agent's ``LOGS_COPY_DIR`` (``results/logs/``), then ``<id>/``, the id being the
test's ``agent.id`` and ``-`` (if it has one) before ``file_helper.time_filename()`` (a ``-2``, ``-3`` ... is added
when that folder exists already), relative to the tool's working folder. The shim copies each run's ULog there from
the server's record as ``<id>_sim-NNNN-runI.ulg`` (Aerialist's ``<id>_<container>.ulg``) beside the test as flown,
``<id>.yaml``, and the results name those copies: the tool may read, move or delete them, and the folder, without
touching what ``surrealist compete`` keeps.

Where the Aerialist in use lacks what a competition tool calls, it is added, each time with a note that the
summary lists (see docs/compete.md): ``AerialistTest.plot`` (the 2025 snippet calls it; master moved it to
``Plot.plot_test``), ``Trajectory.min_distance_to_obstacles`` (2024 tools call it; 0.2.1 lacks it), a
``DroneTest.plot`` that returns its file (0.2.1 returns None), a ``file_helper.time_filename`` that never gives
one name twice in a process (PX4 flights take minutes, ours under a second) and, in the obstacle module, a
matplotlib ``Rectangle`` that takes its angle positionally (Aerialist pins matplotlib 3.6; 3.10 made it
keyword-only).

Standard library only: the tool may run in another Python environment than surrealist-gym's.
"""
from __future__ import annotations

import importlib.abc
import os
import sys
import threading

import surrealist_compete_wire

ADDRESS_ENV = "SURREALIST_COMPETE_ADDRESS"
AUTHKEY_ENV = "SURREALIST_COMPETE_AUTHKEY"
RUNS_ENV = "SURREALIST_COMPETE_RUNS"
SEED_ENV = "SURREALIST_COMPETE_SEED"
LOCAL_AGENT_MODULE = "aerialist.px4.local_agent"

_notes: list = []  # what was added to or changed in Aerialist in this process, sent with every flight
_lock = threading.Lock()
_link = None  # (pid, connection): a forked child opens its own


# --- the link to the surrealist compete process ---------------------------------------------------------------------
def _ask(message: dict) -> dict:
    global _link
    with _lock:
        if _link is None or _link[0] != os.getpid():
            import socket

            address = os.environ.get(ADDRESS_ENV)
            if not address:
                raise RuntimeError(f"surrealist compete: no simulation server ({ADDRESS_ENV} is not set)")
            conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            conn.connect(address)
            surrealist_compete_wire.send(conn, {"op": "hello", "key": os.environ.get(AUTHKEY_ENV, "")})
            if not surrealist_compete_wire.receive(conn).get("ok"):
                raise RuntimeError("surrealist compete: the simulation server refused the connection")
            _link = (os.getpid(), conn)
        surrealist_compete_wire.send(_link[1], message)
        return surrealist_compete_wire.receive(_link[1])


def _plain(value):
    """Aerialist's ``to_dict()`` as plain Python values (tools build obstacles of numpy numbers)."""
    if value is None or isinstance(value, (bool, str)):
        return value
    if isinstance(value, int):
        return int(value)
    if isinstance(value, float):
        return float(value) if value == value and abs(value) != float("inf") else str(value)  # JSON has no nan
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    item = getattr(value, "item", None)  # a numpy scalar
    if callable(item):
        try:
            return _plain(item())
        except (TypeError, ValueError):
            pass
    return str(value)


def _runs(config) -> int:
    count = getattr(getattr(config, "agent", None), "count", None)
    if isinstance(count, int) and not isinstance(count, bool) and count >= 1:
        return count
    return max(1, int(os.environ.get(RUNS_ENV, "1")))


def _result(config, agent: str, log: str):
    """What Aerialist's ``agent`` appends for one run of ``config`` logged at ``log``."""
    current = sys.modules.get("aerialist.px4.aerialist_test")
    if current is not None and isinstance(config, current.AerialistTest):
        result = current.AerialistTestResult
        if agent == "LocalAgent":
            return result(log, current.AssertionConfig.TRAJECTORY)
        if agent == "DockerAgent":
            return result(log, status=result.Status.UNKNOWN)
        return result(log)
    legacy = sys.modules.get("aerialist.px4.drone_test")
    if legacy is not None and isinstance(config, legacy.DroneTest):
        if agent == "LocalAgent":
            return legacy.DroneTestResult(log, legacy.AssertionConfig.TRAJECTORY)
        return legacy.DroneTestResult(log)
    raise TypeError(f"surrealist compete: {agent} was given a {type(config).__name__}, not Aerialist's DroneTest "
                    f"or AerialistTest")


def fly(config, agent: str) -> list:
    """Fly an Aerialist test as ``agent`` would: one result per run."""
    doc = config.to_dict()
    doc.pop("assertion", None)  # no reference flight: a competition test flies the competition's UAV
    doc.pop("agent", None)
    plain = _plain(doc)
    reply = _ask({"op": "fly", "agent": agent, "api": type(config).__name__, "cwd": os.getcwd(),
                  "test": plain, "runs": _runs(config), "compat": list(_notes)})
    if not reply.get("ok"):
        raise RuntimeError(f"surrealist compete: {reply.get('error')}")
    return [_result(config, agent, log) for log in hand_over(config, plain, reply["logs"])]


DEFAULT_COPY_DIR = "results/logs/"  # Aerialist's LOGS_COPY_DIR default


def run_folder(config) -> tuple:
    """A new folder of this run's own, as Aerialist master's ``DockerAgent.import_config`` names it (see the module
    docstring), made here; returns (the folder, ending in ``/``, and the run's id)."""
    settings = getattr(config, "agent", None)
    base = getattr(settings, "path", None)
    if not isinstance(base, str) or not base:
        base = _copy_dir()
    if not base.endswith("/"):
        base += "/"
    helper = sys.modules.get("aerialist.px4.file_helper")
    if helper is not None and callable(getattr(helper, "time_filename", None)):
        stamp = helper.time_filename()
    else:
        import datetime

        stamp = datetime.datetime.now().strftime("%d-%m-%H-%M-%S")
    given = getattr(settings, "id", None)
    name = f"{given}-{stamp}" if isinstance(given, str) and given else stamp
    os.makedirs(base, exist_ok=True)
    run_id, count = name, 1
    while True:
        try:
            os.mkdir(base + run_id)
            return base + run_id + "/", run_id
        except FileExistsError:  # a run of another process in the same second
            count += 1
            run_id = f"{name}-{count}"


def _copy_dir() -> str:
    """Aerialist's ``LOGS_COPY_DIR`` (its DockerAgent's ``COPY_DIR``: the setting, else ``results/logs/``)."""
    docker = getattr(sys.modules.get("aerialist.px4.docker_agent"), "DockerAgent", None)
    value = getattr(docker, "COPY_DIR", None)
    if value is None:
        try:
            from decouple import config as setting

            value = setting("LOGS_COPY_DIR", default=DEFAULT_COPY_DIR)
        except Exception:  # noqa: BLE001 - decouple missing or its .env unreadable: Aerialist's default
            value = DEFAULT_COPY_DIR
    return value if isinstance(value, str) and value else DEFAULT_COPY_DIR


def hand_over(config, plain: dict, records: list) -> list:
    """The run's ULogs as the tool gets them: copies of the server's records (``records``) in a folder of the run's
    own, beside the test as flown (``<id>.yaml``); their paths, in order."""
    import shutil

    import yaml  # Aerialist's own import: there wherever Aerialist runs

    folder, run_id = run_folder(config)
    logs = []
    for record in records:
        log = f"{folder}{run_id}_{os.path.basename(record)}"
        try:
            shutil.copyfile(record, log)
        except OSError as err:
            raise RuntimeError(f"surrealist compete: the log of this run could not be handed over to {log} "
                               f"({type(err).__name__}: {err.strerror or 'no such file'})") from None
        logs.append(log)
    with open(f"{folder}{run_id}.yaml", "w", encoding="utf-8") as f:
        yaml.safe_dump(plain, f, sort_keys=False)
    return logs


def _agent_class(base: type, name: str, module: str) -> type:
    def __init__(self, config) -> None:  # no container, job or PX4 to set up
        self.config = config
        self.results = []

    def run(self):
        self.results.extend(fly(self.config, name))
        return self.results

    async def run_async(self):
        self.run()

    return type(name, (base,), {"__init__": __init__, "run": run, "run_async": run_async, "__module__": module,
                                "__doc__": f"Aerialist's {name}, flying surrealist-gym's simulator (surrealist "
                                           f"compete)."})


# --- what happens as Aerialist's modules import ---------------------------------------------------------------------
def _agent_patch(name: str):
    def patch(module) -> None:
        setattr(module, name, _agent_class(getattr(module, name), name, module.__name__))
    return patch


def _local_stand_in(module, err: Exception) -> None:
    """Aerialist's local_agent imports PX4's and ROS's Python modules (mavsdk, ...) and, through its simulator module,
    reads PX4's settings (``PX4_HOME``, ...) as it imports: without them, its module holds our LocalAgent on
    Aerialist's TestAgent."""
    from aerialist.px4.test_agent import TestAgent

    module.LocalAgent = _agent_class(TestAgent, "LocalAgent", module.__name__)
    why = str(err) if isinstance(err, ImportError) else f"{type(err).__name__}: {err}"
    _notes.append(f"LocalAgent: Aerialist's local_agent module needs what is not installed ({why}); a stand-in "
                  f"module holds the LocalAgent that flies our simulator")


def _unique_time_filename(module) -> None:
    original = module.time_filename
    given: dict = {}  # name -> how many times it was given (names of one second: a plot's, a run folder's)

    def time_filename(add_host=False):
        name = original(add_host)
        given[name] = given.get(name, 0) + 1
        return name if given[name] == 1 else f"{name}-{given[name]}"

    module.time_filename = time_filename
    _notes.append("file_helper.time_filename never gives one name twice in a process (names are to the second; our "
                  "flights take under one, so two plots would share a file)")


def _min_distance_if_missing(module) -> None:
    trajectory = module.Trajectory
    if hasattr(trajectory, "min_distance_to_obstacles"):
        return

    def min_distance_to_obstacles(self, obstacles):
        line = self.to_line()
        return min(obstacle.distance(line) for obstacle in obstacles)

    trajectory.min_distance_to_obstacles = min_distance_to_obstacles
    _notes.append("Trajectory.min_distance_to_obstacles added (this Aerialist lacks it; the 2024 tools call it): "
                  "the least Obstacle.distance from a footprint to the flight's polyline, as Aerialist had it before "
                  "its 0.125 m buffer")


def _rectangle_angle_positional(module) -> None:
    """Aerialist's Obstacle.plt_patch gives matplotlib's Rectangle its angle as the 4th positional argument, which
    matplotlib 3.10 and later take by keyword only: the obstacle module gets a Rectangle that takes both."""
    import inspect
    import types

    patches = module.mpatches
    angle = inspect.signature(patches.Rectangle.__init__).parameters.get("angle")
    if angle is None or angle.kind is not inspect.Parameter.KEYWORD_ONLY:
        return

    def Rectangle(xy, width, height, angle=0.0, **kwargs):  # noqa: N802 - matplotlib's name
        return patches.Rectangle(xy, width, height, angle=angle, **kwargs)

    proxy = types.ModuleType(patches.__name__)
    proxy.__dict__.update(vars(patches))
    proxy.Rectangle = Rectangle
    module.mpatches = proxy
    _notes.append("Obstacle.plt_patch: its matplotlib.patches.Rectangle takes the angle as a positional argument "
                  "again (matplotlib 3.10 made it keyword-only; Aerialist pins 3.6)")


def _png_files(folder: str) -> set:
    return {folder + f for f in os.listdir(folder) if f.endswith(".png")} if os.path.isdir(folder) else set()


def _drone_test_plot_returns_file(module) -> None:
    original = module.DroneTest.__dict__["plot"].__func__

    def plot(cls, test, results, *args, **kwargs):
        folder = getattr(sys.modules["aerialist.px4.trajectory"].Trajectory, "DIR", "results/")
        before = _png_files(folder)
        made = original(cls, test, results, *args, **kwargs)
        if made is None:
            new = sorted(_png_files(folder) - before, key=os.path.getmtime)
            made = new[-1] if new else None
        return made

    module.DroneTest.plot = classmethod(plot)
    _notes.append("DroneTest.plot returns the file it wrote (Aerialist 0.2.1's returns None; the 2024 tools copy "
                  "its file)")


def _aerialist_test_plot_if_missing(module) -> None:
    if hasattr(module.AerialistTest, "plot"):
        return

    def plot(cls, test, results, *args, **kwargs):
        from aerialist.px4.plot import Plot

        return Plot.plot_test(test, results, *args, **kwargs)

    module.AerialistTest.plot = classmethod(plot)
    _notes.append("AerialistTest.plot added (the 2025 snippet calls it; this Aerialist moved it to "
                  "Plot.plot_test, which it calls)")


_PATCHES = {
    "aerialist.px4.file_helper": _unique_time_filename,
    "aerialist.px4.obstacle": _rectangle_angle_positional,
    "aerialist.px4.trajectory": _min_distance_if_missing,
    "aerialist.px4.drone_test": _drone_test_plot_returns_file,
    "aerialist.px4.aerialist_test": _aerialist_test_plot_if_missing,
    LOCAL_AGENT_MODULE: _agent_patch("LocalAgent"),
    "aerialist.px4.docker_agent": _agent_patch("DockerAgent"),
    "aerialist.px4.k8s_agent": _agent_patch("K8sAgent"),
}


class _PatchingLoader(importlib.abc.Loader):
    """Runs a module's own loader, then its patch."""

    def __init__(self, inner, name: str) -> None:
        self._inner, self._name = inner, name

    def create_module(self, spec):
        return self._inner.create_module(spec)

    def exec_module(self, module) -> None:
        try:
            self._inner.exec_module(module)
        except Exception as err:  # the local agent: mavsdk or ROS missing, PX4's settings (PX4_HOME, ...) not set
            if self._name != LOCAL_AGENT_MODULE:
                raise
            _local_stand_in(module, err)
            return
        _PATCHES[self._name](module)

    def __getattr__(self, attr):  # get_source, get_filename, ... for tracebacks and inspect
        return getattr(self._inner, attr)


class _Finder(importlib.abc.MetaPathFinder):
    """Finds the patched modules with the other finders and wraps their loader."""

    def find_spec(self, name, path=None, target=None):
        if name not in _PATCHES:
            return None
        for finder in sys.meta_path:
            if finder is self or not hasattr(finder, "find_spec"):
                continue
            spec = finder.find_spec(name, path, target)
            if spec is not None:
                if spec.loader is None:
                    return None
                spec.loader = _PatchingLoader(spec.loader, name)
                return spec
        return None


def seed_generators() -> None:
    """Seed the tool's global random generators (Python's ``random``, and ``numpy.random`` where numpy is installed)
    from ``SURREALIST_COMPETE_SEED``: a tool that draws from them unseeded (the reference generator's
    ``random.uniform``) writes the same tests for the same seed. A tool that seeds them itself (from the clock) still
    does."""
    value = os.environ.get(SEED_ENV)
    if value is None:
        return
    import random

    random.seed(int(value))
    try:
        import numpy
    except ImportError:
        return
    numpy.random.seed(int(value) % 2 ** 32)


def install() -> None:
    """Patch Aerialist's modules as they import (idempotent)."""
    if not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
