"""The tool's process: its own session and process group, resource limits, a time limit, and an end with ours.

:func:`start` runs the tool's command through a few lines of Python (``python -S -E -c``) that set the limits of
:class:`ToolLimits` with :mod:`resource`, ask Linux to kill the tool if ``compete`` dies (``PR_SET_PDEATHSIG``),
fork a watchdog into the tool's process group that kills the whole group (the processes the tool started too) once
``compete`` has ended, however it ended (``kill -9`` included), then ``exec`` the command: the limits hold from its
first instruction and for every process it starts, and no ``preexec_fn`` runs in ``compete``'s threaded process.
The tool leads a new session (``start_new_session``), so :func:`stop` ends it and every process it started (that
stayed in its group) with one signal; :func:`ending_with_us` turns SIGTERM and SIGHUP to ``compete`` into an
exception, so the ``finally`` that stops the tool runs (Ctrl-C already raises one); :func:`end_with_parent` sends
``compete`` that SIGTERM when the process named in ``$SURREALIST_COMPETE_PARENT`` (a leaderboard running it as a
cell) has ended. See docs/compete.md, "What a tool sees of the machine".

Example::

    >>> process = start(["python", "cli.py", "generate", "mission1", "10"], ToolLimits(), cwd="t")  # doctest: +SKIP
    >>> stop(process)                                                                       # doctest: +SKIP
"""
from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import threading
import time
from dataclasses import dataclass

_LAUNCHER = """
import os, resource, signal, sys, time
for pair in sys.argv[1].split(","):
    name, soft, hard = pair.split(":")
    which = getattr(resource, name)
    top = resource.getrlimit(which)[1]
    cap = lambda v: int(v) if top == resource.RLIM_INFINITY else min(int(v), top)
    resource.setrlimit(which, (cap(soft), cap(hard)))
try:
    import ctypes
    ctypes.CDLL(None).prctl(1, 9)  # PR_SET_PDEATHSIG, SIGKILL: end with the process that started us
except Exception:
    pass
def born(pid):  # when the process started (None once it has ended): a process id reused is not it
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return None if fields[0] in ("Z", "X") else fields[19]
compete = os.getppid()
birth = born(compete)
if birth is not None and os.fork() == 0:  # the watchdog, in the tool's process group
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        devnull = os.open(os.devnull, os.O_RDWR)
        for fd in (0, 1, 2):
            os.dup2(devnull, fd)
        while born(compete) == birth:
            time.sleep(0.25)
        os.killpg(0, signal.SIGKILL)  # compete is gone (kill -9): the tool's whole group goes with it
    finally:
        os._exit(0)
os.execv(sys.argv[2], sys.argv[2:])
"""
#: The watchdog's name for a process that compete started and that must end with it (a leaderboard's cell).
PARENT_ENV = "SURREALIST_COMPETE_PARENT"


@dataclass(frozen=True, slots=True)
class ToolLimits:
    """What a tool may use. ``timeout_s``: wall time before it is stopped; ``memory_gb``: its address space
    (RLIMIT_AS, per process); ``file_gb``: the largest file it may write (RLIMIT_FSIZE); ``cpus``: the CPU time it
    may use per second of ``timeout_s`` (RLIMIT_CPU = cpus x timeout_s, per process; the competition gives a tool
    1.5 vCPU)."""

    timeout_s: float = 7200.0
    memory_gb: float = 8.0
    file_gb: float = 1.0
    cpus: float = 1.5

    def rlimits(self) -> tuple[tuple[str, int, int], ...]:
        """(resource name, soft, hard) as the launcher sets them."""
        cpu = max(1, int(self.cpus * self.timeout_s))
        return (("RLIMIT_AS", int(self.memory_gb * 2 ** 30), int(self.memory_gb * 2 ** 30)),
                ("RLIMIT_FSIZE", int(self.file_gb * 2 ** 30), int(self.file_gb * 2 ** 30)),
                ("RLIMIT_CPU", cpu, cpu + 10),  # past the soft limit SIGXCPU, past the hard one SIGKILL
                ("RLIMIT_CORE", 0, 0))

    def describe(self) -> str:
        """One line for the user."""
        return (f"tool limits: {self.timeout_s:g} s wall, {self.cpus:g} x that in CPU time, {self.memory_gb:g} GB "
                f"address space, files up to {self.file_gb:g} GB, no core dumps")


def start(command: list[str], limits: ToolLimits, **popen) -> subprocess.Popen:
    """Start ``command`` (its first item the Python that runs it) under ``limits``, leading a new session."""
    spec = ",".join(f"{name}:{soft}:{hard}" for name, soft, hard in limits.rlimits())
    return subprocess.Popen([command[0], "-S", "-E", "-c", _LAUNCHER, spec, *command], start_new_session=True,
                            **popen)


def wait(process: subprocess.Popen, limits: ToolLimits, runaway: threading.Event) -> tuple[int, str | None]:
    """The tool's exit code and why it was stopped: None (it ended), "runaway" (``runaway`` was set: it asked on and
    on past its budget) or "timeout" (past ``limits.timeout_s``)."""
    deadline = time.monotonic() + limits.timeout_s
    while True:
        try:
            return process.wait(timeout=0.2), None
        except subprocess.TimeoutExpired:
            why = "runaway" if runaway.is_set() else "timeout" if time.monotonic() > deadline else None
            if why is not None:
                stop(process)
                return process.returncode, why


def stop(process: subprocess.Popen, grace_s: float = 5.0) -> None:
    """End the tool's process group: SIGTERM, then SIGKILL to what is left after ``grace_s``; reaps the tool. Also
    after the tool ended by itself, for the processes it left behind."""
    _signal_group(process.pid, signal.SIGTERM)
    try:
        process.wait(timeout=grace_s)
    except subprocess.TimeoutExpired:
        pass
    _signal_group(process.pid, signal.SIGKILL)
    process.wait()


def _signal_group(pgid: int, signum: int) -> None:
    with contextlib.suppress(ProcessLookupError, PermissionError):
        os.killpg(pgid, signum)


@contextlib.contextmanager
def ending_with_us():
    """Inside, SIGTERM and SIGHUP to this process raise SystemExit (128 + the signal), so ``finally`` blocks run and
    the tool is stopped. Only in the main thread (elsewhere signals cannot be handled); the old handlers come back
    after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def raise_exit(signum, frame):
        raise SystemExit(128 + signum)

    old = {s: signal.signal(s, raise_exit) for s in (signal.SIGTERM, signal.SIGHUP)}
    try:
        yield
    finally:
        for s, handler in old.items():
            signal.signal(s, handler)



def end_with_parent() -> None:
    """When ``$SURREALIST_COMPETE_PARENT`` names this process's parent (a leaderboard running a cell), watch it from
    a daemon thread and send this process SIGTERM once it has ended (however: ``kill -9`` too), so that the cell
    stops its tool and its folder's lock is free for the leaderboard's resume."""
    try:
        parent = int(os.environ.get(PARENT_ENV, ""))
    except ValueError:
        return
    if parent != os.getppid():  # not the one that started us (or already gone)
        if not _born(parent):
            os.kill(os.getpid(), signal.SIGTERM)
        return
    birth = _born(parent)

    def watch() -> None:
        while _born(parent) == birth:
            time.sleep(0.25)
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, name="surrealist-compete-parent", daemon=True).start()


def _born(pid: int) -> str | None:
    """When process ``pid`` started (None once it has ended, a zombie included)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as f:
            fields = f.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return None if fields[0] in ("Z", "X") else fields[19]
