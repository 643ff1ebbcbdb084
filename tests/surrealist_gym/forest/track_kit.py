"""Helpers of the track's tests: the kit's paths (../shared/third_party/uav-testing-track-2027), its generators run
unedited, and its validate.py's verdicts read (validate.py and preflight.py are oracles, used in the tests only)."""
from __future__ import annotations

import contextlib
import io
import json
import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
KIT = ROOT.parent / "shared" / "third_party" / "uav-testing-track-2027"
STARTER_KIT = KIT / "starter_kit"
MANIFEST = KIT / "data" / "train" / "manifest.jsonl"
FLIGHTS = sorted((KIT / "flights").glob("*.json"))

# Runs a generator that writes /out/submission.json unedited, its /out moved to the folder given (argv[2]).
_OUT_MOVED = """
import builtins, os, runpy, sys
script, out = sys.argv[1], sys.argv[2]
real_open, real_makedirs = builtins.open, os.makedirs
def moved(p):
    return out + p[4:] if isinstance(p, str) and (p == "/out" or p.startswith("/out/")) else p
builtins.open = lambda f, *a, **k: real_open(moved(f), *a, **k)
os.makedirs = lambda p, *a, **k: real_makedirs(moved(p), *a, **k)
sys.argv = [script]
runpy.run_path(script, run_name="__main__")
"""


def run_generator(name: str, seed: int, out: Path, n: int = 20) -> Path:
    """The submission the kit's generator ``name`` writes for F11_SEED=seed, F11_N=n, in ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    env = {**os.environ, "F11_SEED": str(seed), "F11_N": str(n)}
    if name == "random_baseline":  # its entrypoint.py runs /gen/random_gen.py with these arguments (--out supported)
        argv = [str(KIT / "examples" / "random_baseline" / "random_gen.py"), "--n", str(n), "--seed", str(seed),
                "--name", "random-baseline", "--out", str(out / "submission.json")]
    else:  # svm_generator and the starter kit write /out/submission.json, reading F11_SEED and F11_N
        script = KIT / ("starter_kit" if name == "starter_kit" else f"examples/{name}") / "generate.py"
        argv = ["-c", _OUT_MOVED, str(script), str(out)]
    subprocess.run([sys.executable, *argv], env=env, check=True, capture_output=True, timeout=300)
    return out / "submission.json"


GENERATED = [("random_baseline", 7), ("random_baseline", 2027), ("svm_generator", 7), ("svm_generator", 2027),
             ("starter_kit", 7)]


def validate_subprocess(path: Path) -> tuple[bool, list[str]]:
    """validate.py run on ``path``: (accepted, its output lines)."""
    run = subprocess.run([sys.executable, str(STARTER_KIT / "validate.py"), str(path)], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode in (0, 1) and not run.stderr, run.stderr
    return run.returncode == 0, run.stdout.splitlines()


def validate_in_process(validate, path: Path) -> tuple[bool, list[str]]:
    """validate.py's main run here on ``path`` (for sweeps over many files): (accepted, its output lines)."""
    out, argv = io.StringIO(), sys.argv
    sys.argv = ["validate.py", str(path)]
    try:
        with contextlib.redirect_stdout(out):
            validate.main()
        accepted = True
    except SystemExit as stop:
        accepted = stop.code in (0, None)
    finally:
        sys.argv = argv
    return accepted, out.getvalue().splitlines()


#: validate.py's rejections, by the rule each names (our Rule's member name) and the field it names, if any.
REJECTIONS = [
    (r"submission is not valid json", "JSON"),
    (r"submission must be an object with a 'scenarios' list", "SUBMISSION_SHAPE"),
    (r"submission name .* must be a string token", "SUBMISSION_NAME"),
    (r"^\d+ scenarios; must be exactly", "COUNT"),
    (r"^scenario \d+ is not an object", "SCENARIO_OBJECT"),
    (r"^scenario \d+ id .* must be a string token", "SCENARIO_ID"),
    (r"^duplicate scenario id", "DUPLICATE_ID"),
    (r"seed must be an integer", "SEED_INTEGER"),
    (r"field (?P<field>\w+) missing or not a finite number", "NUMBER"),
    (r"obstacle (?P<field>radius|height) missing or not finite", "OBSTACLE_NUMBER"),
    (r"obstacle (?P<field>radius|height)=.* out of \[", "RANGE"),
    (r": (?P<field>\w+)=.* out of \[", "RANGE"),
    (r"patrol must be a list of", "WAYPOINTS"),
    (r"patrol waypoint \d+ must be \[x, y\]", "WAYPOINT_FORM"),
    (r"waypoint \d+ outside", "EDGE_MARGIN"),
    (r"leg \d+ length", "LEG"),
    (r"turn at waypoint \d+", "TURN"),
    (r"obstacle must be \{type: poles", "OBSTACLE_TYPE"),
    (r"obstacle xy must be a list", "POLE_COUNT"),
    (r"pole \d+ must be \[x, y\]", "POLE_FORM"),
    (r"pole \d+ outside the", "POLE_EXTENT"),
    (r"pole \d+ is .* from the route", "POLE_LANE"),
    (r"pole \d+ is .* from a waypoint", "POLE_WAYPOINT"),
    (r"poles \d+ and \d+ are .* apart", "POLE_SEPARATION"),
    (r"unknown field\(s\)", "UNKNOWN_FIELD"),
    (r"unknown obstacle field\(s\)", "UNKNOWN_OBSTACLE_FIELD"),
    (r"is identical to .* apart from its id", "DUPLICATE_SCENARIO"),
    (r"distinct scenario recipe", "RECIPES"),
]
_REJECT = "[f11_validate] REJECT: "
_NOTE = re.compile(r"\[f11_validate\] note: scenario (\S+) leaves (\d+\.\d\d) m of free lateral width \((.*)\)")


def rejection(lines: list[str]) -> tuple[str, str | None, str | None]:
    """The rule validate.py's rejection names (a Rule member's name), the scenario it names (or None) and the
    field (or None)."""
    text = next(line for line in lines if line.startswith(_REJECT))[len(_REJECT):]
    rule, match = next((rule, m) for pattern, rule in REJECTIONS if (m := re.search(pattern, text)))
    scenario = re.match(r"scenario (\S+?):? ", text)
    return rule, scenario and scenario.group(1), match.groupdict().get("field")


def notes(lines: list[str]) -> list[tuple[str, str, bool]]:
    """validate.py's notes on tight lanes: (scenario id, free width at 2 decimals, whether blocked)."""
    return [(m.group(1), m.group(2), m.group(3).startswith("lane fully blocked"))
            for line in lines if (m := _NOTE.match(line))]


def manifest_scenarios() -> list[dict]:
    """The train manifest's scenarios as submission.json writes them, one per scenario id (the first record's)."""
    seen = {}
    for line in MANIFEST.read_text().splitlines():
        record = json.loads(line)
        assert record["split"] == "train"  # the kit's copy holds the train split alone
        seen.setdefault(record["scenario"], {"id": record["scenario"], "seed": record["seed"], **record["params"],
                                             "patrol": record["patrol"], "obstacle": record["poles"]})
    return list(seen.values())
