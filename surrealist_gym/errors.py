"""Errors for bad input: each message is one line naming the file or field, the bad value and what was expected; and
the safe reading of input files from anywhere (:func:`input_file`, :func:`read_text`, :func:`safe_yaml`).

The command line turns any :class:`SurrealistError` into exit code 2 with its message on stderr.
"""
from __future__ import annotations

import functools


class SurrealistError(Exception):
    """Base class of every error caused by bad input or a missing optional dependency."""


class LogFormatError(SurrealistError):
    """A flight log cannot be read, or lacks the data asked for (e.g. no valid local position)."""


class MissionError(SurrealistError):
    """A mission file (.plan, QGC WPL) is invalid or holds items that cannot be flown."""


class InvalidTestCase(SurrealistError):
    """A test case (or its YAML) is invalid: wrong field, non-positive size, overlapping obstacles, missing file."""


class InvalidProfile(SurrealistError):
    """A UAV profile (preset name or YAML) is unknown or holds an unknown key or an out-of-range value."""


class InvalidLabels(SurrealistError):
    """A labelled set for ``surrealist fidelity`` is invalid: missing column, unknown test, non-numeric value."""


class SimulationError(SurrealistError):
    """A simulation could not be set up from the given test case."""


class UnknownAgent(SurrealistError):
    """An agent name that is not registered."""


class DependencyNotInstalled(SurrealistError):
    """An optional dependency is missing; the message names the pip command that installs it."""


def one_line(err: Exception, limit: int = 80) -> str:
    """A foreign exception's text for a SurrealistError message: on one line (SQLite and pymavlink quote text with
    its line breaks), at most ``limit`` characters."""
    return " ".join(str(err).split())[:limit]


class InfrastructureError(SurrealistError):
    """The machinery that runs simulations failed (a worker or pool died, a scheduler was lost), not the simulation:
    never stored as a result; the search stops and ``--resume`` re-flies what is missing."""


def regular_file(path, what: str, error: type[SurrealistError] = SurrealistError, empty_ok: bool = True,
                 max_bytes: int | None = None) -> str:
    """``path`` (as a string) if it names an existing regular file, else a one-line ``error``: missing, or what it is
    instead (a folder, a FIFO, a device, a socket), or empty when ``empty_ok`` is False. Checked with ``stat``, which
    does not open the file, so an input that is a FIFO or a device is refused instead of blocking its reader. Every
    reader of an input file calls it before opening it. ``what`` names the input ("log file", "test case"). A file
    of the kernel's (under /proc or /sys: regular to ``stat``, but endless, blocking or secret) is refused, and so is
    one larger than ``max_bytes``."""
    import os
    import stat

    name = os.fspath(path)
    try:
        info = os.stat(name)
    except OSError as err:
        raise error(f"{name}: cannot read {what} ({err.strerror or err})") from None
    if not stat.S_ISREG(info.st_mode):
        kind = ("a folder" if stat.S_ISDIR(info.st_mode) else "a FIFO (named pipe)" if stat.S_ISFIFO(info.st_mode)
                else "a socket" if stat.S_ISSOCK(info.st_mode)
                else "a device" if stat.S_ISCHR(info.st_mode) or stat.S_ISBLK(info.st_mode) else "a special file")
        raise error(f"{name}: {kind}, not a regular file ({what} expected)")
    real = os.path.realpath(name)
    kernel = next((root for root in KERNEL_FOLDERS if real == root or real.startswith(root + "/")), None)
    if kernel:
        raise error(f"{name}: a file of the kernel's ({kernel}), not a regular file ({what} expected)")
    if max_bytes is not None and info.st_size > max_bytes:
        raise error(f"{name}: {info.st_size} bytes, more than the {max_bytes} a {what} may hold")
    if not empty_ok and info.st_size == 0:
        raise error(f"{name}: an empty file, no {what} in it")
    return name


#: Folders of the kernel's files: never an input (/proc/kmsg blocks, /proc/self/environ is the environment).
KERNEL_FOLDERS = ("/proc", "/sys")
#: The most bytes a test's own text files (its YAML, mission, params and commands files) may hold.
MAX_TEXT_BYTES = 16 * 1024 * 1024


def read_text(path, what: str, error: type[SurrealistError] = SurrealistError, max_bytes: int = MAX_TEXT_BYTES) -> str:
    """A UTF-8 text file of at most ``max_bytes`` (:func:`regular_file` first; read no further than the limit, should
    the file grow), else a one-line ``error`` naming the file, never quoting it."""
    name = regular_file(path, what, error, max_bytes=max_bytes)
    try:
        with open(name, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as err:
        raise error(f"{name}: cannot read {what} ({err.strerror or err})") from None
    if len(data) > max_bytes:
        raise error(f"{name}: more than the {max_bytes} bytes a {what} may hold")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        raise error(f"{name}: not UTF-8 text (byte {err.start})") from None


#: The environment variable holding the folders (``os.pathsep``-separated) a test may read files under besides its
#: YAML's folder and the working folder; ``--allow-outside PATH`` sets it (worker processes inherit it).
ALLOW_OUTSIDE_ENV = "SURREALIST_ALLOW_OUTSIDE"


def allowed_folders(base, allow_outside=()) -> tuple:
    """The folders a test whose YAML is in ``base`` may read files under: ``base``, the working folder, the
    competition's ``case_studies`` of a tool's folder (:func:`tool_folders`) and the folders of
    ``$SURREALIST_ALLOW_OUTSIDE`` and ``allow_outside`` (all with their links resolved)."""
    import os
    from pathlib import Path

    extra = [p for p in os.environ.get(ALLOW_OUTSIDE_ENV, "").split(os.pathsep) if p] + list(allow_outside)
    layout = [folder / CASE_STUDIES for folder in tool_folders(base)]
    return tuple(Path(p).expanduser().resolve() for p in (base, Path.cwd(), *layout, *extra))


#: The competition's layout: a tool writes its tests into a folder of its own (``generated_tests/``) and names the
#: case study's files from the tool's folder (``case_studies/mission1.plan``), Aerialist's working folder there.
CASE_STUDIES = "case_studies"
GENERATED_TESTS = "generated_tests"  # where the competition's tools write their tests, in folders of their own


def tool_folders(base) -> list:
    """The folders a competition test in ``base`` may name ``case_studies/...`` from: the folder above ``base`` (a
    tool's ``generated_tests/``), and the tool's folder when ``base`` lies deeper in its ``generated_tests/`` (tools
    write ``generated_tests/<time stamp>/``, and Aerialist resolves from the tool's folder, its working folder)."""
    from pathlib import Path

    base = Path(base)
    return [base.parent] + [p.parent for p in base.parents if p.name == GENERATED_TESTS and p.parent != base.parent]


def _a_tools_case_study(path, base) -> bool:
    """Whether ``path`` lies in a ``case_studies`` folder of a tool's folder beside ``base`` (``surrealist compete``
    writes the tests a tool sends into ``flights/``, naming its copy's ``tool/case_studies/...`` by absolute path)."""
    from pathlib import Path

    parent = Path(base).resolve().parent
    return any(folder.name == CASE_STUDIES and folder.parent.parent == parent for folder in Path(path).parents)


def input_file(value, base, where: str, error: type[SurrealistError] = SurrealistError, missing_ok: bool = False,
               allow_outside=()):
    """The file a test's field names, resolved as Aerialist resolves it: an absolute path as it is, a relative one
    against the YAML's folder ``base``, then the working folder, then by its name in ``base`` (the paper's seeds name
    paths relative to their repository root: ``experiments/case0.plan``), and a path in the competition's
    ``case_studies/`` also from a tool's folder (:func:`tool_folders`). Never by walking up parents. The
    file must lie (links resolved) under :func:`allowed_folders` or in a tool's ``case_studies`` beside ``base``
    (:func:`_a_tools_case_study`), and be a regular file (:func:`regular_file`). Else
    a one-line ``error`` naming the field (``where``) and the path, never the file's contents; a file not found is
    None when ``missing_ok``."""
    from pathlib import Path

    if not isinstance(value, str) or not value.strip():
        raise error(f"{where}: expected a file path, got {value!r}")
    given = Path(value).expanduser()
    base = Path(base)
    tries = [given] if given.is_absolute() else [base / given, Path.cwd() / given, base / given.name]
    if not given.is_absolute() and given.parts[0] == CASE_STUDIES:  # the competition's layout: from a tool's folder
        tries += [folder / given for folder in tool_folders(base)]
    found = [p.resolve() for p in tries if p.exists()]
    if not found:
        if missing_ok:
            return None
        raise error(f"{where}: file {value!r} not found (looked in the YAML's folder and the working folder)")
    roots = allowed_folders(base, allow_outside)
    inside = next((p for p in found if any(p.is_relative_to(root) for root in roots)
                   or _a_tools_case_study(p, base)), None)
    if inside is None:
        shown = f"{value!r}" + (f" ({found[0]})" if str(found[0]) != value else "")
        raise error(f"{where}: file {shown} lies outside the YAML's folder and the working folder; "
                    f"--allow-outside FOLDER lets tests read files under FOLDER")
    try:
        return regular_file(str(inside), "file", error)
    except SurrealistError as err:
        raise error(f"{where}: {err}") from None


def safe_yaml(text: str, name: str):
    """``yaml.safe_load`` for files from anywhere: aliases only while they expand to a small document (not an alias
    bomb); nesting too deep is an error, not a crash; numbers as in YAML 1.2 (``1e9``) and numpy's (:func:`_loader`)."""
    import yaml

    loader = None
    try:  # one parse: the node graph is composed once, measured, then constructed
        loader = _loader()(text)
        node = loader.get_single_node()
        if node is not None and _expanded(node, {}) > MAX_YAML_NODES:
            raise InvalidTestCase(f"{name}: YAML aliases (*name) expand to more than {MAX_YAML_NODES} nodes")
        return None if node is None else loader.construct_document(node)
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark else ""
        raise InvalidTestCase(f"{name}: invalid YAML{where}") from None
    except RecursionError:
        raise InvalidTestCase(f"{name}: YAML nested too deeply") from None
    finally:
        if loader is not None:
            loader.dispose()


#: The tag Aerialist master's ``to_yaml`` gives an assertion's variable (its Trajectory class), read as its name.
TRAJECTORY_TAG = "tag:yaml.org,2002:python/name:aerialist.px4.trajectory.Trajectory"


MAX_YAML_NODES, _APPLY = 100_000, "tag:yaml.org,2002:python/object/apply:"  # a test YAML has some hundred nodes


def _expanded(node, sizes: dict) -> int:
    """How many nodes a composed YAML node stands for with its aliases expanded (a node within itself counts 0)."""
    if id(node) not in sizes:
        sizes[id(node)] = 0
        items = node.value if isinstance(node.value, list) else []  # a scalar's value is its text
        kids = [v for item in items for v in (item if isinstance(item, tuple) else (item,))]  # mappings: key, value
        sizes[id(node)] = 1 + sum(_expanded(v, sizes) for v in kids)
    return sizes[id(node)]


def _numpy_scalar(loader, node):
    """``!!python/object/apply:numpy...scalar [dtype, !!binary bytes]``: the number, when the dtype is numeric."""
    import numpy as np
    import yaml

    try:
        dtype_node, data = node.value
        spec = {k.value: v for k, v in dtype_node.value}
        dtype = np.dtype(spec["args"].value[0].value).newbyteorder(spec["state"].value[1].value)
        if dtype_node.tag == _APPLY + "numpy.dtype" and dtype.kind in "biuf":
            return np.frombuffer(loader.construct_yaml_binary(data), dtype=dtype, count=1)[0].item()
    except (ValueError, TypeError, KeyError, IndexError, AttributeError):
        pass
    raise yaml.constructor.ConstructorError(None, None, "not a numpy number", node.start_mark)


@functools.cache
def _loader():
    """A SafeLoader with YAML 1.2's floats (``1e9``, ``-2E-3``), Aerialist master's tag of the trajectory variable
    read as ``trajectory``, and numpy numbers as PyYAML's full dumper writes them (PALM's tests: without calling
    anything, :func:`_numpy_scalar`); no other Python tag."""
    import re

    import yaml

    class Loader(yaml.SafeLoader):
        pass

    exponent = re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$")
    Loader.add_implicit_resolver("tag:yaml.org,2002:float", exponent, list("-+0123456789"))
    Loader.add_constructor(TRAJECTORY_TAG, lambda loader, node: "trajectory")
    for module in ("numpy._core.multiarray", "numpy.core.multiarray"):  # numpy 2 and 1
        Loader.add_constructor(f"{_APPLY}{module}.scalar", _numpy_scalar)
    return Loader
