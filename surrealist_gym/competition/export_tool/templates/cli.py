#!/usr/bin/python3
"""surrealist-gym's test generator for the UAV Testing Competition (written by ``surrealist export-tool``).

``python3 cli.py generate CASE_STUDY BUDGET``, as the competition runs every tool:

1. **Search in surrealist-gym's simulator** (a PX4 v1.12 SITL + PX4-Avoidance stand-in, about a second a flight):
   ``surrealist generate --case-study CASE_STUDY`` with ``sim_budget_factor x BUDGET`` single-run evaluations,
   run by the Python in ``$SURREALIST_PYTHON`` (default: this one). It keeps every distinct failure, re-flies
   each ``confirm`` times and ranks them by expected test score (``suite/suite.csv``).
2. **Spend the real budget**: the ranked failures, best first, each executed once through
   ``TestCase(case_study, obstacles).execute()`` (the Aerialist agent chosen by ``AGENT``); then, while budget is
   left, the search's other failing evaluations (``evaluations.csv``) in :func:`diverse_order` of their expected test
   score in the simulator, against the ground the tests that failed in their execution already cover; then its near
   misses, closest first. At most BUDGET executions; one that raises still counts.
3. **Write** the executed tests whose real flight came closer than 1.5 m to a box (the competition's soft failure, by
   Aerialist's own distance), in :func:`diverse_order` of the test score of that flight (its points over boxes
   squared and minutes flown, as the competition scores a test), as ``test_i.yaml``, ``.ulg`` and ``.png`` in a new
   folder under ``generated_tests/``, and print ``output folder: PATH``. The 2025 edition scores the first 20 a tool
   wrote, on failures and on the area diversity of their boxes.

The settings are in ``surrealist-tool.json`` beside this file; the search's results folder and a record of every
execution (``executions.csv``) are in ``results/surrealist-<time>/``.
"""
import argparse
import csv
import json
import logging
import math
import os
import shutil
import subprocess
import sys
from datetime import datetime
from pathlib import Path

import yaml
from aerialist.px4.aerialist_test import AerialistTest
from aerialist.px4.obstacle import Obstacle
from pyulog import ULog
from shapely.ops import unary_union
from testcase import TestCase

HERE = Path(__file__).resolve().parent
SETTINGS_FILE = HERE / "surrealist-tool.json"
PYTHON_ENV = "SURREALIST_PYTHON"  # the interpreter of a virtual environment holding surrealist-gym
TESTS_FOLDER = Path("generated_tests")
RESULTS_FOLDER = Path("results")
POINTS = ((0.25, 5), (1.0, 2), (1.5, 1))  # the competition's points of a run closer than each distance [m]
MAX_BOXES = 3
SCORED = 20  # the tests the 2025 edition scores: the first 20 written

logger = logging.getLogger("surrealist-tool")


def points(distance):
    """The competition's points of one run at ``distance`` [m] from the obstacles (0 at 1.5 m or more)."""
    return next((p for limit, p in POINTS if distance < limit), 0)


def test_score(points_, minutes, boxes):
    """The competition's score of a test from one flight: ``points x 10 / (boxes^2 x minutes)``."""
    return points_ * 10.0 / (boxes ** 2 * minutes) if minutes > 0 and boxes else 0.0


def footprint(obstacles):
    """The ground the obstacles cover (Aerialist's rotated box geometry, united)."""
    return unary_union([box(o).geometry for o in obstacles])


def similarity(a, b):
    """The 2025 similarity of two tests: the area of the intersection of their footprints over that of the union."""
    union = a.union(b).area
    return a.intersection(b).area / union if union > 0 else 1.0


def diverse_order(items, first, covered=()):
    """Items ``(score, footprint, value)`` in the order to use them: the first ``first`` one at a time, each the
    greatest ``score x (1 - its largest similarity to the footprints already chosen or in covered)`` (a duplicate
    of one of them comes last); the rest by score."""
    rest = sorted(items, key=lambda item: -item[0])
    chosen = []
    while rest and len(chosen) < first:
        taken = list(covered) + [item[1] for item in chosen]
        best = max(range(len(rest)), key=lambda k: rest[k][0] * (
            1.0 - max((similarity(rest[k][1], other) for other in taken), default=0.0)))
        chosen.append(rest.pop(best))
    return [item[2] for item in chosen + rest]


def search(case_study, budget, settings, out):
    """Run surrealist-gym's suite search on the case study, writing its results folder ``out``."""
    python = os.environ.get(PYTHON_ENV) or sys.executable
    command = [python, "-m", "surrealist_gym.cli", "generate", "--case-study", str(case_study),
               "--budget", str(settings["sim_budget_factor"] * budget), "--obstacles", str(settings["obstacles"]),
               "--confirm", str(settings["confirm"]), "--buffer", str(settings["buffer"]),
               "--random-seed", str(settings["seed"]), "--workers", str(settings["workers"]),
               "--agent", settings.get("agent", "suite"), "--out", str(out)]
    if settings.get("px4_verdict"):  # rank the failures by the model of PX4's verdict (suite/suite.csv's order)
        command.append("--px4-verdict")
    # surrealist-gym has its own dependencies (numpy 2, shapely 2): nothing on this process's PYTHONPATH is passed on
    env = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    logger.info("searching in surrealist-gym's simulator: %s", " ".join(command))
    code = subprocess.call(command, env=env, stdin=subprocess.DEVNULL, stdout=sys.stderr.fileno())
    if code != 0:
        raise RuntimeError(f"surrealist generate ended with exit code {code} (interpreter {python}; set "
                           f"{PYTHON_ENV} to the Python of a virtual environment holding surrealist-gym)")


def ranked_suite(out):
    """The search's distinct failures, best first, as (name, obstacles); and the evaluations that found them."""
    table = out / "suite" / "suite.csv"
    if not table.is_file():
        return [], set()
    with open(table, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    return ([(row["test"], yaml.safe_load((out / "suite" / f"{row['test']}.yaml").read_text(encoding="utf-8"))
              ["simulation"]["obstacles"]) for row in rows], {row["evaluation"] for row in rows})


def neighbours(out, members, executed, failed, count):
    """The search's other evaluations (``evaluations.csv``: not suite members, not executed), as (name, obstacles):
    those that failed in the simulator, in :func:`diverse_order` of their expected test score there against the
    ground ``failed`` covers (the first ``count``); then the near misses, closest first."""
    with open(out / "evaluations.csv", newline="", encoding="utf-8") as f:
        rows = [row for row in csv.DictReader(f) if row["evaluation"] not in members and row.get("o0_l")
                and math.isfinite(float(row["min_distance"] or "nan"))]  # flown, not refused
    found = {}
    for row in rows:
        obstacles = [{"size": {k: float(row[f"o{i}_{k}"]) for k in "lwh"},
                      "position": {k: float(row[f"o{i}_{k}"]) for k in "xyzr"}}
                     for i in range(MAX_BOXES) if row.get(f"o{i}_l")]
        if layout(obstacles) not in executed:
            found.setdefault(layout(obstacles), (f"evaluation-{row['evaluation']}", obstacles,
                                                 float(row["min_distance"]), float(row.get("flight_s") or 0.0)))
    failing = [(test_score(points(distance), seconds / 60.0, len(obstacles)), footprint(obstacles), (name, obstacles))
               for name, obstacles, distance, seconds in found.values() if points(distance)]
    misses = sorted((item for item in found.values() if not points(item[2])), key=lambda item: item[2])
    return (diverse_order(failing, count, [footprint(obstacles) for obstacles in failed])
            + [(name, obstacles) for name, obstacles, _, _ in misses])


def layout(obstacles):
    """A hashable key of the obstacles: each one's (x, y, r, l, w, h)."""
    return tuple((o["position"]["x"], o["position"]["y"], o["position"]["r"], o["size"]["l"], o["size"]["w"],
                  o["size"]["h"]) for o in obstacles)


def box(found):
    """An Aerialist box from one obstacle of surrealist-gym's YAML (a new object each time, as Aerialist asks)."""
    size, position = found["size"], found["position"]
    return Obstacle(Obstacle.Size(l=float(size["l"]), w=float(size["w"]), h=float(size["h"])),
                    Obstacle.Position(x=float(position["x"]), y=float(position["y"]), z=0.0,
                                      r=float(position["r"])))


def minutes_flown(log_file):
    """The span of a flight's ULog [min]."""
    log = ULog(str(log_file))
    return (log.last_timestamp - log.start_timestamp) / 60e6


def execute(case, name, obstacles, writer, phase):
    """Execute one test (one simulation of the budget); its TestCase, distance [m] and minutes flown, (None, None)
    when it failed."""
    test = TestCase(case, [box(o) for o in obstacles])
    try:
        test.execute()
        distance = min(test.get_distances())
        minutes = minutes_flown(test.log_file)
    except Exception as err:  # a simulation that gives no flight: skipped, as the competition asks
        logger.warning("%s: execution failed, skipped: %s", name, err)
        writer.writerow([phase, name, "", "", "", "", " ".join(str(err).split())])
        return test, None, None
    score = test_score(points(distance), minutes, len(obstacles))
    logger.info("%s (%s): %.2f m, %d points, %.2f min", name, phase, distance, points(distance), minutes)
    writer.writerow([phase, name, f"{distance:.3f}", points(distance), f"{minutes:.3f}", f"{score:.4f}", ""])
    return test, distance, minutes


def spend(case_study, out, budget):
    """At most ``budget`` executions: the ranked suite, best first, then the search's other failures (see
    :func:`neighbours`). The tests that failed in their execution, in :func:`diverse_order` of their test score."""
    case = AerialistTest.from_yaml(str(case_study))
    ranked, members = ranked_suite(out)
    logger.info("%d distinct failures in the simulator; budget %d", len(ranked), budget)
    flown = []  # (obstacles, test, distance, minutes) in the order executed
    with open(out / "executions.csv", "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["phase", "test", "distance_m", "points", "minutes", "test_score", "error"])
        for name, obstacles in ranked[:budget]:
            flown.append((obstacles, *execute(case, name, obstacles, writer, "suite")))
        if len(flown) < budget:
            failed = [obstacles for obstacles, _, distance, _ in flown if distance is not None and points(distance)]
            executed = {layout(obstacles) for obstacles, _, _, _ in flown}
            left = budget - len(flown)
            for name, obstacles in neighbours(out, members, executed, failed, left)[:left]:
                flown.append((obstacles, *execute(case, name, obstacles, writer, "neighbour")))
    failures = [(test_score(points(distance), minutes, len(obstacles)), footprint(obstacles), test)
                for obstacles, test, distance, minutes in flown if distance is not None and points(distance)]
    return len(flown), diverse_order(failures, SCORED)


def write(tests, folder):
    """Each test as test_i.yaml, .ulg and .png; a test whose plot fails is left out."""
    folder.mkdir(parents=True)
    written = 0
    for test in tests:
        try:
            test.plot()
        except Exception as err:
            logger.warning("plot failed, test left out: %s", err)
            continue
        test.save_yaml(str(folder / f"test_{written}.yaml"))
        shutil.copy2(test.log_file, folder / f"test_{written}.ulg")
        shutil.copy2(test.plot_file, folder / f"test_{written}.png")
        written += 1
    return written


def generate(case_study, budget):
    """Search, execute the budget's tests and write the failures to a new folder of generated tests."""
    settings = json.loads(SETTINGS_FILE.read_text(encoding="utf-8"))
    stamp = datetime.now().strftime("%Y%m%d-%H%M%S")
    results = RESULTS_FOLDER / f"surrealist-{stamp}"
    search(Path(case_study).resolve(), budget, settings, results)
    executed, failures = spend(case_study, results, budget)
    folder = TESTS_FOLDER / f"surrealist-{stamp}"
    written = write(failures, folder)
    print(f"{written} test cases generated ({executed} executed of budget {budget}; record in "
          f"{results / 'executions.csv'})")
    print(f"output folder: {folder}/")


def main():
    """The tool's command line: ``generate TEST.yaml BUDGET``; exit 1 when the generation fails."""
    parser = argparse.ArgumentParser(description="surrealist-gym's UAV test generator")
    commands = parser.add_subparsers(dest="command", required=True)
    command = commands.add_parser("generate", description="generate tests")
    command.add_argument("test", help="the case study's test description (YAML)")
    command.add_argument("budget", type=int, help="simulations allowed (executions of a test)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    try:
        generate(args.test, args.budget)
    except Exception as err:
        logger.exception("generation failed: %s", err)
        sys.exit(1)


if __name__ == "__main__":
    main()
