"""Bad input, measured, in two corpora given to the command line as a new user would.

Damage: seeded random damage to real logs, plans and test YAMLs (``surrealist inspect LOG``, ``surrealist simulate
TEST``). A clean answer is exit 0 (the damage left a readable file) or exit 2 with one ``error:`` line naming the
file; never a traceback, never over 10 s or 1 GB.

Refusals: a seeded corpus of inputs that are wrong on purpose, over every command (simulate, replicate, generate,
generate --case-study, calibrate, fidelity, evaluate, surrogate train/eval, compare, train, inspect, compete): bad
option values, options that do not apply to the problem, old spellings of the vocabulary of docs/cli.md (``--seed``
where ``--random-seed`` is meant, ``generate SEED.yaml``, ``--runs-per-test``, ``--out`` naming a file), UAV profiles
outside their physical ranges or malformed, tests with out-of-range or non-numeric settings,
outputs that cannot be written (a file, a path under a file, a read-only tmpfs where this machine mounts one), FIFOs,
folders and devices where a file is expected, empty files, bad case-study names, argparse errors. Each case runs in
its own folder with cheap settings (``--budget 1 --runs 1``), so a command that wrongly accepts its input ends soon.
A clean answer is exit 2 with exactly one ``error:`` line, no traceback, before any work: the case's folder holds
exactly its inputs afterwards, unchanged (no output folder, no plot, no store turned into a database), within 10 s.

Prints the share of clean answers per kind, the slowest and the largest, and every unclean one.

    python benchmarks/bench_bad_input.py [--per-file 12] [--random-seed 2026] [--only damage|refusals] [--jobs 2]
"""
from __future__ import annotations

import argparse
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "surrealist_gym" / "data"
FORMATS = ROOT.parent / "shared" / "data" / "formats"
LOGS = [DATA / "case0.ulg", FORMATS / "ulog" / "px4tools_19_56_46.ulg",
        FORMATS / "tlog" / "dronekit_log_upload_test.tlog", FORMATS / "dataflash" / "pymavlink_test.BIN"]
TESTS = [DATA / "rq1-seed1.yaml", DATA / "rq2-seed.yaml"]
PLANS = [DATA / "case0.plan", DATA / "auto1.plan"]
QUIET = ["--runs", "1", "--no-plot", "--no-ulog", "--no-reference"]
COMPANIONS = ["case0.plan", "case0-params.csv", "case0-commands.csv", "auto1.plan", "auto1-params.csv",
              "auto-commands.csv"]


def damage(data: bytes, rng: np.random.Generator) -> bytes:
    """One to six edits (flip, delete, insert, cut), half of them in the first 4 KB (headers, definitions)."""
    out = bytearray(data)
    for _ in range(rng.integers(1, 7)):
        if not out:
            break
        span = min(4096, len(out)) if rng.random() < 0.5 else len(out)
        i = int(rng.integers(0, span))
        kind = rng.integers(0, 4)
        if kind == 0:
            out[i] ^= int(rng.integers(1, 256))
        elif kind == 1:
            del out[i:i + int(rng.integers(1, 9))]
        elif kind == 2:
            out[i:i] = bytes([int(rng.integers(0, 256))]) * int(rng.integers(1, 9))
        else:
            del out[i:]
    return bytes(out)


def answer(command: list[str]) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    start = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
        code, err = done.returncode, done.stderr
    except subprocess.TimeoutExpired:
        code, err = None, "timeout after 60 s"
    seconds = time.perf_counter() - start
    rss_mb = max(before, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    clean = (code == 0 or (code == 2 and len(errors) == 1)) and "Traceback" not in err
    return {"clean": clean and seconds <= 10.0 and rss_mb <= 1024, "code": code, "seconds": seconds,
            "rss_mb": rss_mb, "error": errors[0] if errors else err.strip().splitlines()[-1:] or ""}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--per-file", type=int, default=12, help="damaged copies of each file (default 12)")
    parser.add_argument("--random-seed", type=int, default=2026,
                        help="seed of the damage and the corpus (default 2026)")
    parser.add_argument("--only", choices=["damage", "refusals"], default=None, help="run one corpus only")
    parser.add_argument("--jobs", type=int, default=2, help="commands run at the same time (refusals; default 2)")
    args = parser.parse_args()
    if args.only != "refusals":
        damage_corpus(args)
    if args.only != "damage":
        refusal_corpus(args)
    return 0


def damage_corpus(args) -> None:
    rng = np.random.default_rng(args.random_seed)
    cli = [sys.executable, "-m", "surrealist_gym.cli"]
    results: dict[str, list[dict]] = {"log": [], "test": [], "plan": []}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name in COMPANIONS:
            shutil.copy(DATA / name, folder / name)
        sources = [("log", p) for p in LOGS if p.is_file()] + [("test", p) for p in TESTS] + \
                  [("plan", p) for p in PLANS]
        for kind, source in sources:
            for i in range(args.per_file):
                path = folder / f"bad{i}-{source.name}"
                path.write_bytes(damage(source.read_bytes(), rng))
                if kind == "log":
                    command = cli + ["inspect", str(path), "--no-plot"]
                elif kind == "test":
                    command = cli + ["simulate", str(path), *QUIET, "--out", str(folder / "out")]
                else:  # a damaged plan behind an intact test
                    test = folder / f"bad{i}-test.yaml"
                    test.write_text((DATA / "rq1-seed1.yaml").read_text().replace(
                        "case0.plan", path.name).replace("auto1.plan", path.name))
                    command = cli + ["simulate", str(test), *QUIET, "--out", str(folder / "out")]
                results[kind].append({"file": path.name, **answer(command)})
    print("| input | damaged files | clean answers | exit 2 | slowest [s] | largest [MB] |")
    print("|---|---|---|---|---|---|")
    for kind, rows in results.items():
        if rows:
            clean = sum(r["clean"] for r in rows)
            print(f"| {kind} | {len(rows)} | {clean} ({clean / len(rows):.0%}) | {sum(r['code'] == 2 for r in rows)} | "
                  f"{max(r['seconds'] for r in rows):.1f} | {max(r['rss_mb'] for r in rows):.0f} |")
    for kind, rows in results.items():
        for r in [r for r in rows if r["code"] == 2][:2]:
            print(f"e.g. {kind}: {r['error']}")
    unclean = [r for rows in results.values() for r in rows if not r["clean"]]
    for r in unclean:
        print(f"unclean: {r['file']}: exit {r['code']}, {r['seconds']:.1f} s, {r['rss_mb']:.0f} MB: {r['error']}")


# --- refusals: inputs that are wrong on purpose, over every command --------------------------------------------------
SHARED = ROOT.parent / "shared" / "data"
CASE0 = DATA / "case0.ulg"
STORE = ROOT / "tests" / "data" / "stores" / "rq2-rep0.sqlite"
LABELS_CSV = SHARED / "competition" / "rilast-mission1" / "tests.csv"
CAMBA = SHARED / "competition" / "camba-collection"
CASE_STUDIES = SHARED / "competition" / "case_studies"
SEED_FILES = ["rq2-seed.yaml", "auto1.plan", "auto1-params.csv", "auto-commands.csv"]
CHEAP = {  # each command with settings that keep a wrongly accepted input short; "out" is the output it writes
    "simulate": ["simulate", "rq2-seed.yaml", "--runs", "1", "--no-plot", "--no-ulog", "--out", "out"],
    "replicate": ["replicate", str(CASE0), "--budget", "1", "--runs", "1", "--workers", "1", "--out", "out"],
    "generate": ["generate", "--seed", "rq2-seed.yaml", "--budget", "1", "--runs", "1", "--workers", "1", "--out",
                 "out"],
    "case-study": ["generate", "--case-study", "mission1", "--budget", "1", "--runs", "1", "--workers", "1",
                   "--confirm", "0", "--out", "out"],
    "calibrate": ["calibrate", str(CASE0), "--runs", "1", "--workers", "1", "--profile", "uav.yaml"],
    "fidelity": ["fidelity", str(LABELS_CSV), "--limit", "1", "--workers", "1", "--out", "out"],
    "evaluate": ["evaluate", "{camba}", "--runs", "1", "--workers", "1", "--out", "out"],
    "surrogate-train": ["surrogate", "train", str(STORE), "--problem", "generate", "--kind", "knn", "--out", "model"],
    "surrogate-eval": ["surrogate", "eval", "{model}", str(STORE)],
    "compare": ["compare", "--env", "Surrealist-Generate-v0", "--agents", "random", "--budget", "1",
                "--repetitions", "1", "--runs", "1", "--inline", "--out", "out"],
    "train": ["train", "--steps", "1", "--episode-budget", "2", "--problem", "generate", "--policy", "policy.zip"],
    "inspect": ["inspect", str(CASE0), "--out", "plots"],
    "compete": ["compete", "tool", "mission1", "1", "--out", "out"],
}
# (command, flag, bad values): whole numbers, numbers and names that the options do not take
OPTIONS = [
    ("simulate", "--runs", ["0", "-1", "x"]), ("simulate", "--random-seed", ["-1", "1.5"]),
    ("simulate", "--seed", ["0"]), ("fidelity", "--seed", ["0"]),
    ("simulate", "--param", ["MPC_XY_CRUISE", "MPC_XY_CRUISE=abc", "MPC_XY_CRUISE=1e9", "NAV_ACC_RAD=-1",
                             "MPC_THR_HOVER=0", "=3"]),
    ("simulate", "--reference", ["missing.ulg"]), ("simulate", "--vehicle", ["boat"]),
    ("replicate", "--budget", ["0", "-3"]), ("replicate", "--runs", ["0"]), ("replicate", "--workers", ["0"]),
    ("replicate", "--random-seed", ["-1"]), ("replicate", "--first-runs", ["3,2", "x", "1,1"]),
    ("replicate", "--agent", ["bogus", "module:Nope", "ppo:missing.zip"]), ("replicate", "--preset", ["fast"]),
    ("replicate", "--averaging", ["median"]), ("replicate", "--seed", ["nope", "missing.yaml"]),
    ("replicate", "--resume", ["no-such-folder"]),
    ("generate", "--budget", ["0"]), ("generate", "--runs", ["-2"]), ("generate", "--aggregate", ["max"]),
    ("generate", "--agent", ["nope"]), ("generate", "--surrogate", ["no-model"]), ("generate", "--screen", ["x"]),
    ("generate", "--obstacles", ["2"]), ("generate", "--confirm", ["3"]),
    ("case-study", "--obstacles", ["0", "4"]), ("case-study", "--confirm", ["-1"]),
    ("calibrate", "--runs", ["0"]), ("calibrate", "--workers", ["0"]), ("calibrate", "--seed", ["missing.yaml"]),
    ("calibrate", "--uav", ["no-such-preset"]),
    ("fidelity", "--runs", ["0"]), ("fidelity", "--every", ["0"]), ("fidelity", "--limit", ["0"]),
    ("fidelity", "--close", ["-1", "nan", "inf"]), ("fidelity", "--buffer", ["-0.5", "nan"]),
    ("fidelity", "--mission", ["missing.yaml"]), ("fidelity", "--labels", ["labels.csv"]),
    ("evaluate", "--runs", ["0"]), ("evaluate", "--workers", ["0"]), ("evaluate", "--uav", ["nope"]),
    ("surrogate-train", "--members", ["0"]), ("surrogate-train", "--epochs", ["0"]), ("surrogate-train", "--k", ["0"]),
    ("surrogate-train", "--holdout", ["5", "-1"]), ("surrogate-train", "--kind", ["forest"]),
    ("surrogate-train", "--target", ["speed"]), ("surrogate-train", "--seed", ["missing.yaml"]),
    ("compare", "--repetitions", ["0"]), ("compare", "--budget", ["0"]), ("compare", "--parallel", ["0"]),
    ("compare", "--env", ["CartPole-v1"]), ("compare", "--agents", ["", ",", "bogus", "ppo:missing.zip"]),
    ("compare", "--seed", ["missing.yaml"]), ("compare", "--log", ["missing.ulg"]),
    ("train", "--steps", ["0"]), ("train", "--episode-budget", ["1"]), ("train", "--runs", ["0"]),
    ("train", "--spread", ["0", "5", "nan", "-1"]), ("train", "--threads", ["0"]),
    ("train", "--algorithm", ["dqn"]), ("train", "--seed", ["missing.yaml"]),
]
ARGPARSE = [["simulate"], ["calibrate", str(CASE0)], ["fidelity"], ["surrogate"], ["surrogate", "eval"],
            ["surrogate", "train", str(STORE)], ["evaluate"], ["nope"], ["inspect", "--bogus"],
            ["generate", "--budget"], ["replicate", "--runs", "many"], ["compare", "--inline", "yes"]]


@dataclass(frozen=True)
class Case:
    kind: str
    name: str
    argv: tuple[str, ...]
    setup: Callable[[Path], None] = field(default=lambda folder: None)


def _with(argv: list[str], flag: str, value: str) -> list[str]:
    """``argv`` with ``flag`` set to ``value`` (replaced where it is given, else added)."""
    argv = list(argv)
    if flag in argv:
        argv[argv.index(flag) + 1] = value
        return argv
    return argv + [flag, value]


def _write(name: str, text: str | bytes) -> Callable[[Path], None]:
    def setup(folder: Path) -> None:
        (folder / name).write_bytes(text if isinstance(text, bytes) else text.encode())
    return setup


def _violation(rng: np.random.Generator, key: str):
    """A value outside ``key``'s physical range: below it, above it, not finite, or not a number."""
    from surrealist_gym.errors import RANGES

    r = RANGES[key]
    choices = ["nan", "inf", "string"]
    if math.isfinite(r.low):
        choices.append("low")
    if math.isfinite(r.high):
        choices.append("high")
    kind = choices[int(rng.integers(len(choices)))]
    if kind == "low":
        return r.low if r.low_open else r.low - float(rng.uniform(0.01, 10.0))
    if kind == "high":
        return r.high if r.high_open else r.high * float(rng.uniform(1.01, 1e6)) + 1.0
    return {"nan": ".nan", "inf": ".inf", "string": "fast"}[kind]


def _yaml_value(value) -> str:
    return value if isinstance(value, str) else repr(float(value))


def _profile_body(key: str, value) -> str:
    """A profile YAML setting ``key`` (a PX4 parameter, a section field or a timing) to ``value``."""
    px4_planner = {"planner.max_sensor_range", "planner.max_point_age_s", "planner.heading_offset_deg"}
    model = "px4" if key in px4_planner else "simple"
    head = f"name: bad\navoidance_model: {model}\n"
    if key.isupper():
        return head + f"params: {{{key}: {_yaml_value(value)}}}\n"
    if "." in key:
        section, name = key.split(".", 1)
        return head + f"{section}: {{{name}: {_yaml_value(value)}}}\n"
    return head + f"{key}: {_yaml_value(value)}\n"


def _test_yaml(params: str = "", commands: str = "commands_file: auto-commands.csv",
               params_file: str = "auto1-params.csv") -> str:
    return (f"drone:\n  port: ros\n  params_file: {params_file}\n  mission_file: auto1.plan\n  params: {{{params}}}\n"
            f"simulation:\n  simulator: ros\n  obstacles: [7.625, 5.0625, 20, 17.1875, 17.53125, 0, 0]\n"
            f"test:\n  {commands}\n")


def _fifo(name: str) -> Callable[[Path], None]:
    return lambda folder: os.mkfifo(folder / name)


def _folder(name: str) -> Callable[[Path], None]:
    return lambda folder: (folder / name).mkdir()


def corpus(rng: np.random.Generator) -> list[Case]:
    """The seeded refusal corpus: every case an input that must be refused."""
    from surrealist_gym.errors import RANGES

    cases = []

    def add(kind, name, argv, setup=lambda folder: None):
        cases.append(Case(kind, name, tuple(argv), setup))

    # bad option values (two drawn where more are listed)
    for command, flag, values in OPTIONS:
        picked = values if len(values) <= 2 else [str(v) for v in rng.choice(values, size=2, replace=False)]
        for value in picked:
            add("option", f"{command} {flag} {value!r}", _with(CHEAP[command], flag, str(value)))
    # UAV profiles: a value out of every range, spread over the commands that take --uav
    takers = ["simulate", "replicate", "generate", "case-study", "calibrate", "fidelity", "evaluate"]
    for i, key in enumerate(sorted(RANGES)):
        if rng.random() < 0.45:  # a seeded share of the table's keys
            continue
        value = _violation(rng, key)
        command = takers[i % len(takers)]
        add("profile", f"{command} --uav {key}={value}", _with(CHEAP[command], "--uav", "uav-bad.yaml"),
            _write("uav-bad.yaml", _profile_body(key, value)))
    malformed = {"unknown key": "name: x\nbogus: 1\n", "unknown planner key": "name: x\nplanner: {nope: 1}\n",
                 "unknown sensor key": "name: x\nsensor: {nope: 1}\n", "unknown noise key": "name: x\nnoise: {n: 1}\n",
                 "bad vehicle": "name: x\nvehicle: boat\n", "bad model": "name: x\navoidance_model: magic\n",
                 "params not a mapping": "name: x\nparams: [1, 2]\n", "YAML syntax": "name: [x\n",
                 "a list": "- name: x\n", "alias bomb": "a: &a [1]\nb: *a\n", "binary": bytes(range(256)),
                 "params string": "name: x\nparams: {MPC_XY_CRUISE: fast}\n", "empty": ""}
    for i, (what, body) in enumerate(malformed.items()):
        command = takers[(i + 3) % len(takers)]
        add("profile", f"{command} --uav ({what})", _with(CHEAP[command], "--uav", "uav-bad.yaml"),
            _write("uav-bad.yaml", body))
    add("profile", "simulate --uav profile.txt", _with(CHEAP["simulate"], "--uav", "profile.txt"),
        _write("profile.txt", "name: x\n"))
    # tests: settings out of range, non-numeric commands, through every command that reads a test
    bad_tests = {
        "uav.planner.cruise_speed 1e9": _test_yaml("uav.planner.cruise_speed: 1.0e9"),
        "uav.takeoff_delay_s -1": _test_yaml("uav.takeoff_delay_s: -1"),
        "uav.no_such_setting": _test_yaml("uav.no_such_setting: 1"),
        "MPC_THR_HOVER 0": _test_yaml("MPC_THR_HOVER: 0, MPC_USE_HTE: 0"),
        "MPC_XY_CRUISE -5": _test_yaml("MPC_XY_CRUISE: -5"),
        "MPC_ACC_HOR 0": _test_yaml("MPC_ACC_HOR: 0"),
        "NAV_ACC_RAD inf": _test_yaml("NAV_ACC_RAD: .inf"),
        "MPC_TKO_SPEED string": _test_yaml("MPC_TKO_SPEED: quick"),
        "command x string": _test_yaml(commands="commands: [{timestamp: 1, mode: 3, x: abc}]"),
        "command without timestamp": _test_yaml(commands="commands: [{mode: 3}]"),
        "command mode 2.5": _test_yaml(commands="commands: [{timestamp: 1, mode: 2.5}]"),
        "params file MPC_XY_CRUISE 0": _test_yaml(params_file="bad-params.csv"),
    }
    readers = [("simulate", CHEAP["simulate"][:1] + ["t.yaml"] + CHEAP["simulate"][2:]),
               ("generate", _with(CHEAP["generate"], "--seed", "t.yaml")),
               ("evaluate", ["evaluate", "t.yaml", "--any-layout", "--runs", "1", "--workers", "1", "--out", "out"]),
               ("replicate --seed", _with(CHEAP["replicate"], "--seed", "t.yaml")),
               ("train --seed", _with(CHEAP["train"], "--seed", "t.yaml")),
               ("compare --seed", _with(CHEAP["compare"], "--seed", "t.yaml")),
               ("surrogate train --seed", _with(CHEAP["surrogate-train"], "--seed", "t.yaml"))]
    for i, (what, text) in enumerate(bad_tests.items()):
        for j in (0, 1, 2):
            reader, argv = readers[(i + j * 3) % len(readers)]
            setups = [_write("t.yaml", text), _write("bad-params.csv", "NAV_ACC_RAD, 0.5\nMPC_XY_CRUISE, 0\n")]
            add("test", f"{reader} ({what})", argv, lambda folder, setups=setups: [s(folder) for s in setups])
    # outputs that cannot be written
    outputs = [("simulate", "--out"), ("replicate", "--out"), ("generate", "--out"), ("case-study", "--out"),
               ("fidelity", "--out"), ("evaluate", "--out"), ("surrogate-train", "--out"), ("compare", "--out")]
    for command, flag in outputs:
        add("output", f"{command} {flag} FILE", _with(CHEAP[command], flag, "afile"), _write("afile", "x"))
        add("output", f"{command} {flag} FILE/x", _with(CHEAP[command], flag, "afile/x"), _write("afile", "x"))
        add("output", f"{command} {flag} read-only", _with(CHEAP[command], flag, "{ro}/x"))
    for command, flag, bad in [("calibrate", "--profile", "uav.txt"), ("calibrate", "--profile", "afile/uav.yaml"),
                               ("calibrate", "--profile", "{ro}/uav.yaml"), ("calibrate", "--plot", "plot.txt"),
                               ("calibrate", "--plot", "afile/p.png"), ("calibrate", "--plot", "{ro}/p.png"),
                               ("inspect", "--out", "afile/plots"), ("inspect", "--out", "{ro}/plots"),
                               ("inspect", "--out", "afile"),
                               ("surrogate-eval", "--plot", "eval.txt"), ("surrogate-eval", "--plot", "afile/e.png"),
                               ("surrogate-eval", "--plot", "{ro}/e.png"), ("train", "--policy", "afile/p.zip"),
                               ("train", "--policy", "{ro}/p.zip"), ("calibrate", "--profile", "afile")]:
        add("output", f"{command} {flag} {bad}", _with(CHEAP[command], flag, bad), _write("afile", "x"))
    # FIFOs, folders and devices where a file is expected
    for maker, label in ((_fifo, "FIFO"), (_folder, "folder")):
        for command, argv in [
                ("inspect", ["inspect", "x.ulg", "--no-plot"]),
                ("calibrate", ["calibrate", "x.ulg", "--profile", "u.yaml"]),
                ("replicate", ["replicate", "x.ulg"] + CHEAP["replicate"][2:]),
                ("compare --log", _with(CHEAP["compare"], "--log", "x.ulg")),
                ("simulate", ["simulate", "x.yaml"] + CHEAP["simulate"][2:]),
                ("generate", _with(CHEAP["generate"], "--seed", "x.yaml")),
                ("simulate --uav", _with(CHEAP["simulate"], "--uav", "x.yaml")),
                ("generate --case-study", _with(CHEAP["case-study"], "--case-study", "x.yaml")),
                ("fidelity --labels", ["fidelity", "{camba}", "--labels", "x.csv", "--limit", "1", "--out", "out"]),
                ("fidelity --mission", _with(CHEAP["fidelity"], "--mission", "x.yaml")),
                ("surrogate train", ["surrogate", "train", "x.sqlite", "--out", "model"]),
                ("surrogate eval", ["surrogate", "eval", "{model}", "x.sqlite"]),
                ("compare --agents ppo", _with(CHEAP["compare"], "--agents", "ppo:x.zip"))]:
            name = next(a for a in argv if a.startswith("x.") or a.startswith("ppo:x."))
            add("non-regular", f"{command} {label}", argv, maker(name.removeprefix("ppo:")))
    for command, argv in [("inspect", ["inspect", "/dev/null", "--no-plot"]),
                          ("simulate", ["simulate", "/dev/null"] + CHEAP["simulate"][2:]),
                          ("surrogate train", ["surrogate", "train", "/dev/null", "--out", "model"]),
                          ("surrogate eval MODEL", ["surrogate", "eval", "x.model", str(STORE)])]:
        add("non-regular", f"{command} device/FIFO", argv, _fifo("x.model"))
    # empty files
    for command, argv, name in [("inspect", ["inspect", "e.ulg", "--no-plot"], "e.ulg"),
                                ("calibrate", ["calibrate", "e.ulg", "--profile", "u.yaml"], "e.ulg"),
                                ("simulate", ["simulate", "e.yaml"] + CHEAP["simulate"][2:], "e.yaml"),
                                ("generate", _with(CHEAP["generate"], "--seed", "e.yaml"), "e.yaml"),
                                ("simulate --uav", _with(CHEAP["simulate"], "--uav", "e.yaml"), "e.yaml"),
                                ("surrogate train", ["surrogate", "train", "e.sqlite", "--out", "model"], "e.sqlite"),
                                ("surrogate eval", ["surrogate", "eval", "{model}", "e.sqlite"], "e.sqlite"),
                                ("fidelity", ["fidelity", "e.csv", "--out", "out"], "e.csv"),
                                ("case-study", _with(CHEAP["case-study"], "--case-study", "e.yaml"), "e.yaml"),
                                ("compare --agents ppo", _with(CHEAP["compare"], "--agents", "ppo:e.zip"), "e.zip"),
                                ("evaluate", ["evaluate", "e.yaml", "--runs", "1", "--out", "out"], "e.yaml")]:
        add("empty", f"{command} empty {name}", argv, _write(name, b""))
    add("empty", "simulate (empty plan)", ["simulate", "t.yaml"] + CHEAP["simulate"][2:],
        lambda folder: [(folder / "t.yaml").write_text(_test_yaml().replace("auto1.plan", "e.plan")),
                        (folder / "e.plan").write_bytes(b"")])
    # case studies
    for name in ["mission9", "", "../../etc/passwd", "missing.yaml", "Mission 1", "uav.yaml"]:
        add("case-study", f"--case-study {name!r}", _with(CHEAP["case-study"], "--case-study", name),
            _write("uav.yaml", "name: x\n"))
    add("case-study", "--case-study with a seed test", _with(CHEAP["case-study"], "--seed", "rq2-seed.yaml"))
    # old spellings of the vocabulary (docs/cli.md): each refused, naming the new one
    for name, argv in [("generate SEED.yaml", ["generate", "rq2-seed.yaml"] + CHEAP["generate"][3:]),
                       ("compete --runs-per-test", CHEAP["compete"] + ["--runs-per-test", "2"]),
                       ("compete BUDGET 0", CHEAP["compete"][:3] + ["0", "--out", "out"]),
                       ("train --out p.zip", _with(CHEAP["train"], "--policy", "p.zip")[:-2] + ["--out", "p.zip"]),
                       ("calibrate --out u.yaml", CHEAP["calibrate"][:-2] + ["--out", "u.yaml"]),
                       ("inspect --out case0.png", _with(CHEAP["inspect"], "--out", "case0.png")),
                       ("simulate --seed", _with(CHEAP["simulate"], "--seed", "1"))]:
        add("old spelling", name, argv)
    # stores that are not evaluation stores
    for what, body in [("random bytes", bytes(rng.integers(0, 256, 4096, dtype=np.uint8))),
                       ("text", b"not sqlite " * 100), ("sqlite header only", b"SQLite format 3\x00" + bytes(84))]:
        for command in ("surrogate train", "surrogate eval"):
            argv = (["surrogate", "train", "bad.sqlite", "--out", "model"] if command == "surrogate train"
                    else ["surrogate", "eval", "{model}", "bad.sqlite"])
            add("store", f"{command} ({what})", argv, _write("bad.sqlite", body))
    # a policy that holds a pickle
    add("policy", "compare --agents ppo:pickle.zip", _with(CHEAP["compare"], "--agents", "ppo:pickle.zip"),
        _pickled_policy)
    add("policy", "replicate --agent ppo:pickle.zip", _with(CHEAP["replicate"], "--agent", "ppo:pickle.zip"),
        _pickled_policy)
    add("policy", "compare --agents ppo:not-a-zip", _with(CHEAP["compare"], "--agents", "ppo:bad.zip"),
        _write("bad.zip", b"PK\x03\x04 not a zip"))
    for argv in ARGPARSE:
        add("argparse", " ".join(argv) or "(none)", argv)
    _what_a_test_reads(add)
    return cases


# --- compete: a tool folder is untrusted (issue 44) ------------------------------------------------------------------
def compete_untrusted_cases() -> list[Case]:
    """``compete`` on a tool folder holding a link out of it, a loop or a FIFO: refused before anything is written."""
    def tool(make: Callable[[Path], None]) -> Callable[[Path], None]:
        def setup(folder: Path) -> None:
            (folder / "tool").mkdir()
            (folder / "tool" / "cli.py").write_text("print('never run')\n")
            make(folder / "tool")
        return setup
    argv = ("compete", "tool", "mission1", "1", "--out", "out")
    return [Case("compete-tool", name, argv, tool(make)) for name, make in [
        ("link out (etc -> /etc)", lambda t: os.symlink("/etc", t / "etc")),
        ("link out (up -> ..)", lambda t: os.symlink("..", t / "up")),
        ("loop (loop -> .)", lambda t: os.symlink(".", t / "loop")),
        ("FIFO in the tool", lambda t: os.mkfifo(t / "pipe"))]]


# --- issue 44: tests read only what they should; outputs kept; each refusal one line -----------------------------
def _what_a_test_reads(add) -> None:
    """Files a test should not read, CSV fields over csv's limit, 3,000 boxes, one folder under two names, nested
    JSON, a dangling export-tool folder, and outputs that hold a model or a policy already."""
    simulate = ["simulate", "t.yaml"] + CHEAP["simulate"][2:]
    for value, extra in [("etc/passwd", []), ("/etc/passwd", []), ("../../../../../../etc/passwd", []),
                         ("/proc/self/environ", []), ("/proc/self/environ", ["--allow-outside", "/"]),
                         ("/proc/kmsg", ["--allow-outside", "/"]), ("/dev/zero", ["--allow-outside", "/dev"]),
                         ("link.csv", [])]:
        add("reads", f"simulate params_file {value} {' '.join(extra)}".strip(), simulate + extra,
            lambda folder, v=value: [_write("t.yaml", _test_yaml(params_file=v))(folder),
                                     (folder / "link.csv").symlink_to("/etc/passwd")])
    huge = "MPC_XY_CRUISE, " + "1" * 140_000 + "\n"
    for command, argv in [("simulate", simulate), ("generate", _with(CHEAP["generate"], "--seed", "t.yaml")),
                          ("evaluate", ["evaluate", "t.yaml", "--any-layout", "--runs", "1", "--workers", "1",
                                        "--out", "out"]),
                          ("replicate --seed", _with(CHEAP["replicate"], "--seed", "t.yaml"))]:
        for field_ in ("params", "commands"):
            body = _test_yaml(params_file="big.csv") if field_ == "params" else _test_yaml(
                commands="commands_file: big.csv")
            add("reads", f"{command} ({field_} CSV field over 128 KB)", argv,
                lambda folder, b=body: [_write("t.yaml", b)(folder), _write("big.csv", huge)(folder)])
    boxes = "".join(f"    - {{size: {{l: 1, w: 1, h: 1}}, position: {{x: {3 * (k % 60)}, y: {3 * (k // 60)}}}}}\n"
                    for k in range(3000)) + "    - {size: {l: 1, w: 1, h: 1}, position: {x: 0.5, y: 0.5}}\n"
    add("reads", "simulate (3,000 boxes, two overlapping)", simulate,
        _write("t.yaml", _test_yaml().replace("  obstacles: [7.625, 5.0625, 20, 17.1875, 17.53125, 0, 0]\n",
                                              "  obstacles:\n" + boxes)))

    def two_names(folder: Path) -> None:
        (folder / "suite").mkdir()
        shutil.copytree(CASE_STUDIES, folder / "case_studies")
        shutil.copy(sorted(CAMBA.glob("*.yaml"))[0], folder / "suite")
        (folder / "again").symlink_to("suite")
    for extra in ([], ["--competition", "2025"]):
        add("reads", f"evaluate suite again {' '.join(extra)}".strip(),
            ["evaluate", "suite", "again", "--runs", "1", "--workers", "1", "--out", "out"] + extra, two_names)
    nested = "[" * 50_000 + "]" * 50_000
    add("reads", "fidelity (obstacles JSON nested 50,000 deep)",
        ["fidelity", "deep.csv", "--mission", str(CASE_STUDIES / "mission1.yaml"), "--workers", "1", "--out", "out"],
        _write("deep.csv", f'test_id,obstacles,px4_min_distance_2d\nt1,"{nested}",1.0\n'))
    add("reads", "export-tool DIR (a dangling link)", ["export-tool", "tool"],
        lambda folder: (folder / "tool").symlink_to("nowhere"))
    add("reads", "surrogate train --out MODEL (holds a model)", CHEAP["surrogate-train"][:-1] + ["m"],
        lambda folder: [(folder / "m").mkdir(), _write("m/meta.json", "{}")(folder)])
    add("reads", "surrogate train A LINK-TO-A --holdout 1",
        ["surrogate", "train", "a.sqlite", "b.sqlite", "--problem", "generate", "--kind", "knn", "--holdout", "1",
         "--out", "model"],
        lambda folder: [shutil.copy(STORE, folder / "a.sqlite"), (folder / "b.sqlite").symlink_to("a.sqlite")])
    add("reads", "train --policy p.zip (holds a policy)", CHEAP["train"], _write("policy.zip", b"PK policy"))


def _pickled_policy(folder: Path) -> None:
    import io
    import zipfile

    import torch

    buffer = io.BytesIO()
    torch.save({"action_net.weight": torch.zeros(2, 2), "payload": argparse.Namespace(code=1)}, buffer)
    with zipfile.ZipFile(folder / "pickle.zip", "w") as archive:
        archive.writestr("policy.pth", buffer.getvalue())


def _snapshot(folder: Path) -> dict[str, tuple]:
    """Every entry under ``folder`` with its size and modification time (stat never opens a FIFO)."""
    out = {}
    for path in sorted(folder.rglob("*")):
        info = path.lstat()
        out[str(path.relative_to(folder))] = (info.st_mode, info.st_size, info.st_mtime_ns)
    return out


def refusal(case: Case, folder: Path, places: dict[str, str]) -> dict:
    """Run one case in its own folder: exit 2, one error line, no traceback, nothing written, within 10 s."""
    for name in SEED_FILES:
        shutil.copy(DATA / name, folder / name)
    case.setup(folder)
    before = _snapshot(folder)
    command = [sys.executable, "-m", "surrealist_gym.cli", *(a.format(**places) for a in case.argv)]
    env = {**os.environ, "SURREALIST_CASE_STUDIES": str(CASE_STUDIES), "PYTHONWARNINGS": "ignore"}
    start = time.perf_counter()
    try:
        done = subprocess.run(command, cwd=folder, capture_output=True, text=True, timeout=60, env=env)
        code, err = done.returncode, done.stderr
    except subprocess.TimeoutExpired:
        code, err = None, "timeout after 60 s (a command waiting on its input, or flying)"
    seconds = time.perf_counter() - start
    after = _snapshot(folder)
    wrote = sorted(k for k in after if before.get(k) != after[k]) + sorted(k for k in before if k not in after)
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    clean = code == 2 and len(errors) == 1 and "Traceback" not in err and not wrote and seconds <= 10.0
    return {"kind": case.kind, "name": case.name, "clean": clean, "code": code, "seconds": seconds, "wrote": wrote,
            "error": errors[0] if errors else (err.strip().splitlines() or [""])[-1]}


def _read_only(folder: Path) -> bool:
    """Mount a read-only tmpfs on ``folder`` (root on Linux); False where this machine does not allow it."""
    folder.mkdir()
    return subprocess.run(["mount", "-t", "tmpfs", "-o", "ro,size=1m", "tmpfs", str(folder)],
                          capture_output=True).returncode == 0


def refusal_corpus(args) -> None:
    rng = np.random.default_rng(args.random_seed + 1)
    cases = corpus(rng) + compete_untrusted_cases()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        ro = tmp / "ro"
        mounted = _read_only(ro)
        if not mounted:
            cases = [c for c in cases if not any("{ro}" in a for a in c.argv)]
            print("(no read-only tmpfs here: its cases are left out)")
        model = tmp / "model"
        subprocess.run([sys.executable, "-m", "surrealist_gym.cli", *CHEAP["surrogate-train"][:-1], str(model)],
                       capture_output=True, check=True)
        camba = sorted(p for p in CAMBA.glob("*.yaml"))[0]
        places = {"ro": str(ro), "model": str(model), "camba": str(camba)}
        folders = []
        for i, case in enumerate(cases):
            folders.append(tmp / f"case{i:03d}")
            folders[-1].mkdir()
        start = time.perf_counter()
        try:
            with ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
                rows = list(pool.map(lambda pair: refusal(pair[0], pair[1], places), zip(cases, folders)))
        finally:
            if mounted:
                subprocess.run(["umount", str(ro)], check=False)
        wall = time.perf_counter() - start
    kinds = list(dict.fromkeys(r["kind"] for r in rows))
    print(f"\nrefusals: {len(rows)} bad inputs over every command, seed {args.random_seed + 1}, {args.jobs} at a time, "
          f"{wall:.0f} s wall")
    print("| input | cases | clean answers | exit 2 | wrote something | slowest [s] |")
    print("|---|---|---|---|---|---|")
    for kind in kinds + ["all"]:
        part = [r for r in rows if kind in ("all", r["kind"])]
        clean = sum(r["clean"] for r in part)
        print(f"| {kind} | {len(part)} | {clean} ({clean / len(part):.0%}) | {sum(r['code'] == 2 for r in part)} | "
              f"{sum(bool(r['wrote']) for r in part)} | {max(r['seconds'] for r in part):.1f} |")
    for kind in kinds:
        example = next((r for r in rows if r["kind"] == kind and r["clean"]), None)
        if example:
            print(f"e.g. {kind}: {example['name']}: {example['error']}")
    for r in rows:
        if not r["clean"]:
            print(f"unclean: {r['kind']}: {r['name']}: exit {r['code']}, {r['seconds']:.1f} s"
                  + (f", wrote {', '.join(r['wrote'][:3])}" if r["wrote"] else "") + f": {r['error'][:160]}")


if __name__ == "__main__":
    sys.exit(main())
