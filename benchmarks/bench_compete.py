"""``surrealist compete``: what one simulation costs a competition tool, against a plain simulate of the same test.

    python benchmarks/bench_compete.py                 # 6 tests (missions 1-3, two layouts each) + a warm-up
    python benchmarks/bench_compete.py --repeat 3      # each test three times

A small tool, written to a temporary folder (cli.py on Aerialist master's ``AerialistTest`` and ``DockerAgent``, as
the 2025 snippet builds its tests), runs through ``surrealist compete`` (the real shim, server and Aerialist) and
times each ``DockerAgent(test).run()`` in its own process: the request to the server, the flight, the ULog, and
Aerialist's ``AerialistTestResult`` reading it back into its ``Trajectory``. Baseline, in this process afterwards:
a plain simulate of the very same test and run (the server's YAML of it, the same run index, so the same noise
and flight): ``load_test``, ``simulate_runs`` and ``write_run_ulog``, as ``surrealist simulate --runs 1 --no-plot``
does. The first test of each side is a warm-up (the simulator's first flight in a process compiles its kernels)
and is not counted. Target: a tool's simulation costs at most 1.5x the plain simulate.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
THIRD_PARTY = ROOT.parent / "shared" / "third_party"
SNIPPETS = THIRD_PARTY / "uav-testing-competition" / "snippets"
MASTER = THIRD_PARTY / "aerialist-master"

#: (mission, boxes [l, w, h, x, y, r]); the first is the warm-up.
LAYOUTS = (
    ("mission1", [[10, 5, 20, -5, 25, 0]]),
    ("mission1", [[10, 5, 20, 5, 20, 30]]),
    ("mission1", [[8, 14, 18, 2, 28, 10], [6, 6, 15, -20, 15, 45]]),
    ("mission2", [[12, 4, 20, 0, 20, 80]]),
    ("mission2", [[6, 10, 17, 10, 16, 5], [15, 10, 23, -12, 30, 40]]),
    ("mission3", [[10, 5, 20, -5, 25, 0]]),
    ("mission3", [[14, 6, 22, 3, 22, 60]]),
)

TOOL = '''\
"""A benchmark tool: fly the layouts of layouts.json with Aerialist's DockerAgent, timing each run()."""
import json
import time

from aerialist.px4.aerialist_test import AerialistTest
from aerialist.px4.docker_agent import DockerAgent
from aerialist.px4.obstacle import Obstacle

times = []
for mission, boxes in json.load(open("layouts.json")):
    test = AerialistTest.from_yaml(f"case_studies/{mission}.yaml")
    test.simulation.obstacles = [Obstacle(Obstacle.Size(l, w, h), Obstacle.Position(x, y, 0, r))
                                 for l, w, h, x, y, r in boxes]
    start = time.perf_counter()
    results = DockerAgent(test).run()
    times.append(time.perf_counter() - start)
    assert len(results[0].record.positions) > 10
json.dump(times, open("times.json", "w"))
print("output folder: ./")
'''


def make_tool(folder: Path, layouts) -> Path:
    shutil.copytree(SNIPPETS / "case_studies", folder / "case_studies")
    (folder / "cli.py").write_text(TOOL, encoding="utf-8")
    (folder / "layouts.json").write_text(json.dumps(layouts), encoding="utf-8")
    return folder


def plain(flights, seed: int) -> list[tuple[float, float]]:
    """Wall time [s] of a plain simulate of each flight's test and run, and its simulated duration [s]."""
    from surrealist_gym.aerialist import load_test
    from surrealist_gym.logs import write_run_ulog
    from surrealist_gym.sim import simulate_runs
    from surrealist_gym.sim.profiles import load_profile

    config = load_profile("px4-v1.12-sitl-iris").sim_config()
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for n, flight in enumerate(flights):
            start = time.perf_counter()
            test = load_test(flight.test_file)
            run = simulate_runs(test, [n], seed, config)[0]
            write_run_ulog(Path(tmp) / f"{n}.ulg", run, mission=test.mission)
            out.append((time.perf_counter() - start, run.duration))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=1, help="fly each measured test this many times")
    args = parser.parse_args()
    from surrealist_gym.competition.compete import prepare, run
    from surrealist_gym.logs import read_flight

    layouts = [LAYOUTS[0]] + [layout for layout in LAYOUTS[1:] for _ in range(args.repeat)]
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        tool = make_tool(Path(tmp) / "tool", layouts)
        plan = prepare(tool, "mission1", len(layouts), Path(tmp) / "out", aerialist=MASTER)
        start = time.perf_counter()
        result = run(plan)
        wall = time.perf_counter() - start
        if result.returncode != 0:
            sys.exit(f"the benchmark tool failed: {result.problem}")
        tool_times = json.loads((plan.out / "tool" / "times.json").read_text())
        flights = result.flights
        durations = [read_flight(f.logs[0]).duration for f in flights]
        baseline = plain(flights, plan.seed)
    print(f"compete: {len(flights)} simulations in {wall:.1f} s wall (tool start-up, Aerialist import included)")
    print(f"{'test':>4}  {'mission':8}  {'boxes':>5}  {'flight':>7}  {'plain':>7}  {'server':>7}  {'tool':>7}  "
          f"{'tool/plain':>10}")
    ratios = []
    for n, ((mission, boxes), flight, tool_s, (plain_s, plain_dur), dur) in enumerate(
            zip(layouts, flights, tool_times, baseline, durations)):
        same = abs(plain_dur - dur) < 1.0
        mark = "" if same else "  (flight differs)"
        if n == 0:
            mark += "  warm-up, not counted"
        else:
            ratios.append(tool_s / plain_s)
        print(f"{n:>4}  {mission:8}  {len(boxes):>5}  {plain_dur:>6.1f}s  {plain_s:>6.3f}s  {flight.wall_s:>6.3f}s  "
              f"{tool_s:>6.3f}s  {tool_s / plain_s:>10.2f}{mark}")
    measured = slice(1, None)
    total_tool, total_plain = sum(tool_times[measured]), sum(b[0] for b in baseline[measured])
    print(f"tool/plain: median {statistics.median(ratios):.2f}, max {max(ratios):.2f}, "
          f"total {total_tool:.2f} s / {total_plain:.2f} s = {total_tool / total_plain:.2f} (target <= 1.5)")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
