#!/usr/bin/python3
"""surrealist-gym's test generator for the UAV Testing Competition (written by ``surrealist export-tool``).

``python3 cli.py generate CASE_STUDY BUDGET``, as the competition runs every tool:

1. **Search in surrealist-gym's simulator** (a PX4 v1.12 SITL + PX4-Avoidance stand-in, about a second a flight):
   ``surrealist generate --case-study CASE_STUDY`` with ``sim_budget_factor x BUDGET`` single-run evaluations,
   run by the Python in ``$SURREALIST_PYTHON`` (default: this one). It keeps every distinct failure, re-flies
   each ``confirm`` times and ranks them by expected test score (``suite/suite.csv``).
2. **Spend the real budget**: the ranked failures, best first, each executed once through
   ``TestCase(case_study, obstacles).execute()`` (the Aerialist agent chosen by ``AGENT``), at most BUDGET
   executions; an execution that raises still counts.
3. **Write** the executed tests whose real flight came closer than 1.5 m to a box (the competition's soft failure),
   ordered by the points of that flight (5, 2, 1), then by the simulator's rank, as ``test_i.yaml``, ``.ulg`` and
   ``.png`` in a new folder under ``generated_tests/``, and print ``output folder: PATH``.

The settings are in ``surrealist-tool.json`` beside this file; the search's results folder and a record of every
execution (``executions.csv``) are in ``results/surrealist-<time>/``.
"""
import argparse
import csv
import json
import logging
import os
import shutil
import subprocess
import sys
from datetime import datetime
from pathlib import Path

import yaml
from aerialist.px4.aerialist_test import AerialistTest
from aerialist.px4.obstacle import Obstacle

from testcase import TestCase

HERE = Path(__file__).resolve().parent
SETTINGS_FILE = HERE / "surrealist-tool.json"
PYTHON_ENV = "SURREALIST_PYTHON"  # the interpreter of a virtual environment holding surrealist-gym
TESTS_FOLDER = Path("generated_tests")
RESULTS_FOLDER = Path("results")
POINTS = ((0.25, 5), (1.0, 2), (1.5, 1))  # the competition's points of a run closer than each distance [m]

logger = logging.getLogger("surrealist-tool")


def points(distance):
    return next((p for limit, p in POINTS if distance < limit), 0)


def search(case_study, budget, settings, out):
    """Run surrealist-gym's suite search on the case study; its ranked failures as (name, obstacle dicts)."""
    python = os.environ.get(PYTHON_ENV) or sys.executable
    command = [python, "-m", "surrealist_gym.cli", "generate", "--case-study", str(case_study),
               "--budget", str(settings["sim_budget_factor"] * budget), "--obstacles", str(settings["obstacles"]),
               "--confirm", str(settings["confirm"]), "--random-seed", str(settings["seed"]),
               "--workers", str(settings["workers"]), "--out", str(out)]
    # surrealist-gym has its own dependencies (numpy 2, shapely 2): nothing on this process's PYTHONPATH is passed on
    env = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    logger.info("searching in surrealist-gym's simulator: %s", " ".join(command))
    code = subprocess.call(command, env=env, stdin=subprocess.DEVNULL, stdout=sys.stderr.fileno())
    if code != 0:
        raise RuntimeError(f"surrealist generate ended with exit code {code} (interpreter {python}; set "
                           f"{PYTHON_ENV} to the Python of a virtual environment holding surrealist-gym)")
    table = out / "suite" / "suite.csv"
    if not table.is_file():
        return []
    with open(table, newline="", encoding="utf-8") as f:
        names = [row["test"] for row in csv.DictReader(f)]
    return [(name, yaml.safe_load((out / "suite" / f"{name}.yaml").read_text(encoding="utf-8"))
             ["simulation"]["obstacles"]) for name in names]


def box(found):
    """An Aerialist box from one obstacle of surrealist-gym's YAML (a new object each time, as Aerialist asks)."""
    size, position = found["size"], found["position"]
    return Obstacle(Obstacle.Size(l=float(size["l"]), w=float(size["w"]), h=float(size["h"])),
                    Obstacle.Position(x=float(position["x"]), y=float(position["y"]), z=0.0,
                                      r=float(position["r"])))


def spend(case_study, ranked, budget, record):
    """Execute the ranked tests, best first, at most ``budget``; the real failures, best first."""
    case = AerialistTest.from_yaml(str(case_study))
    failures = []
    with open(record, "w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["rank", "suite_test", "distance_m", "points", "error"])
        for rank, (name, obstacles) in enumerate(ranked[:budget], start=1):
            test = TestCase(case, [box(o) for o in obstacles])
            try:
                test.execute()
                distance = min(test.get_distances())
            except Exception as err:  # a simulation that gives no flight: skipped, as the competition asks
                logger.warning("%s: execution failed, skipped: %s", name, err)
                writer.writerow([rank, name, "", "", " ".join(str(err).split())])
                continue
            logger.info("%s (rank %d): %.2f m, %d points", name, rank, distance, points(distance))
            writer.writerow([rank, name, f"{distance:.3f}", points(distance), ""])
            if points(distance):
                failures.append((-points(distance), rank, test))
    return [test for _, _, test in sorted(failures, key=lambda item: item[:2])]


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
    settings = json.loads(SETTINGS_FILE.read_text(encoding="utf-8"))
    stamp = datetime.now().strftime("%Y%m%d-%H%M%S")
    results = RESULTS_FOLDER / f"surrealist-{stamp}"
    ranked = search(Path(case_study).resolve(), budget, settings, results)
    logger.info("%d distinct failures in the simulator; executing up to %d of them", len(ranked), budget)
    failures = spend(case_study, ranked, budget, results / "executions.csv")
    folder = TESTS_FOLDER / f"surrealist-{stamp}"
    written = write(failures, folder)
    print(f"{written} test cases generated ({min(budget, len(ranked))} executed of budget {budget}; record in "
          f"{results / 'executions.csv'})")
    print(f"output folder: {folder}/")


def main():
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
