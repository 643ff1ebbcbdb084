"""Simulator speed (and, with --realism, the realism figures of docs/simulator.md).

    python benchmarks/bench_sim.py               # speed: one run, a batch of 10, plain PyBullet baseline; SITL Iris
                                                 # on 1-3 boxes and a batch of 10 tests x 5 runs, on each physics
    python benchmarks/bench_sim.py --realism     # case0 figures vs the real flight + docs/img/sim_*.png

Speed: the case0 mission (rq1-seed1.yaml: case0.plan, case0-params.csv, case0.ulg's parameters, the paper's seed-1
box) with avoidance on; wall time is the best of several repetitions after a warm-up (numba compilation and
PyBullet client creation excluded); the baseline is a plain PyBullet loop (one body, applyExternalForce +
stepSimulation at physics_hz, no control) over the same simulated time, measured in the same process.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENTS = ROOT.parent / "shared" / "data" / "surrealist" / "experiments"


def _best(fn, repeat: int) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def plain_pybullet(seconds: float, hz: float) -> float:
    """Wall time of a bare PyBullet loop: one 1.4 kg box, one applyExternalForce and one stepSimulation per step."""
    import pybullet as pb

    cid = pb.connect(pb.DIRECT)
    try:
        pb.setGravity(0, 0, 9.80665, physicsClientId=cid)
        pb.setTimeStep(1.0 / hz, physicsClientId=cid)
        shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[0.2, 0.2, 0.08], physicsClientId=cid)
        body = pb.createMultiBody(1.4, shape, basePosition=[0, 0, -3], physicsClientId=cid)
        force, n = (0.0, 0.0, -1.4 * 9.80665), int(seconds * hz)
        t0 = time.perf_counter()
        for _ in range(n):
            pos, _ = pb.getBasePositionAndOrientation(body, physicsClientId=cid)
            pb.applyExternalForce(body, -1, force, pos, pb.WORLD_FRAME, physicsClientId=cid)
            pb.stepSimulation(physicsClientId=cid)
        return time.perf_counter() - t0
    finally:
        pb.disconnect(cid)


def speed(repeat: int) -> None:
    import surrealist_gym as sg
    from surrealist_gym.sim import SimConfig, simulate

    test = sg.load_test(EXPERIMENTS / "rq1-seed1.yaml")
    cfg = SimConfig(avoidance=True)
    simulate(test, runs=1, config=cfg)  # warm-up: numba caches, PyBullet client pool
    (run,) = simulate(test, runs=1, config=cfg)
    one = _best(lambda: simulate(test, runs=1, config=cfg), repeat)
    batch = simulate(test, runs=10, config=cfg)
    ten = _best(lambda: simulate(test, runs=10, config=cfg), max(1, repeat // 2))
    simulated = sum(r.duration for r in batch)
    base = _best(lambda: plain_pybullet(run.duration, cfg.physics_hz), repeat)
    print(f"config: physics {cfg.physics_hz:g} Hz, control {cfg.control_hz:g} Hz, outer {cfg.outer_hz:g} Hz, "
          f"planner {cfg.planner_hz:g} Hz, vehicle {cfg.vehicle.value}; python {sys.version.split()[0]}, "
          f"{os.cpu_count()} CPUs")
    print(f"one run (case0 + seed-1 box, avoidance on, {run.status.value}): {run.duration:.1f} s simulated in "
          f"{one * 1e3:.1f} ms wall -> {run.duration / one:.0f}x real time")
    print(f"batch of 10 in one world ({sum(r.status.value == 'success' for r in batch)}/10 success): "
          f"{simulated:.1f} s simulated in {ten * 1e3:.1f} ms -> {simulated / ten:.0f}x real time (aggregate)")
    print(f"plain PyBullet loop, same {run.duration:.1f} s at {cfg.physics_hz:g} Hz: {base * 1e3:.1f} ms -> "
          f"{run.duration / base:.0f}x real time; one full run flies at {base / one:.2f}x the bare loop's speed")
    sitl_speed(repeat)


RILAST_TESTS = {1: "random_run0_1", 2: "random_run3_194", 3: "random_run0_0"}  # rilast-mission1 tests by boxes


def rilast_tests(ids=None) -> list:
    """Competition mission1 tests of the rilast-mission1 set (``../shared/data/competition``): the given test ids,
    or every test of the set."""
    import csv
    import json

    import surrealist_gym as sg

    competition = ROOT.parent / "shared" / "data" / "competition"
    mission1 = sg.load_test(competition / "case_studies" / "mission1.yaml")
    with open(competition / "rilast-mission1" / "tests.csv", newline="") as f:
        rows = {r["test_id"]: r for r in csv.DictReader(f)}
    return [mission1.with_obstacles([sg.Obstacle(**o) for o in json.loads(rows[i]["obstacles"])])
            for i in (ids if ids is not None else rows)]


def sitl_speed(repeat: int, batch_tests: int = 10, batch_runs: int = 5, workers: int = 2) -> None:
    """Competition tests on the PX4 SITL Iris profile (PX4-Avoidance model, look-ahead tree), on each physics: one
    run of a rilast test with 1, 2 and 3 boxes against the bare PyBullet loop over the same simulated time, and a
    batch of ``batch_tests`` tests x ``batch_runs`` runs on a local pool of ``workers`` processes and on as many threads
    of this process (aggregate)."""
    import dataclasses

    from surrealist_gym.executors import executor_for, fly_many
    from surrealist_gym.sim import Physics, simulate
    from surrealist_gym.sim.profiles import load_profile

    base_cfg = load_profile("px4-v1.12-sitl-iris").sim_config()
    for physics in Physics:
        cfg = dataclasses.replace(base_cfg, physics=physics)
        bare = []  # the bare loop's speed [x real time], each time it is measured
        for boxes, test in zip(RILAST_TESTS, rilast_tests(RILAST_TESTS.values())):
            (run,) = simulate(test, runs=1, config=cfg)  # warm-up
            one = _best(lambda: simulate(test, runs=1, config=cfg), repeat)
            base = _best(lambda: plain_pybullet(run.duration, cfg.physics_hz), repeat)
            bare.append(run.duration / base)
            print(f"{physics.value}: one run of mission1 + rilast {RILAST_TESTS[boxes]} ({boxes} box"
                  f"{'es' if boxes > 1 else ''}, {run.status.value}): {run.duration:.1f} s simulated in "
                  f"{one * 1e3:.0f} ms -> {run.duration / one:.0f}x real time; the bare PyBullet loop "
                  f"{run.duration / base:.0f}x in this run: {base / one:.2f}x its speed")
        tests = rilast_tests()[:batch_tests]
        for where in ("process", "threads"):
            with executor_for(where, workers) as pool:
                fly_many(tests[:workers], 1, 0, cfg, pool)  # warm-up: the workers' imports and numba caches
                t0 = time.perf_counter()
                records = fly_many(tests, batch_runs, 0, cfg, pool)
                wall = time.perf_counter() - t0
            simulated = sum(r.duration for rs in records for r in rs)
            on = f"{workers} worker processes" if where == "process" else f"{workers} threads of this process"
            print(f"{physics.value}: batch of {len(tests)} tests x {batch_runs} runs on {on}: "
                  f"{simulated:.0f} s simulated in {wall:.1f} s -> {simulated / wall:.0f}x real time (aggregate), "
                  f"{simulated / wall / np.median(bare):.2f}x the bare PyBullet loop ({np.median(bare):.0f}x, the "
                  f"median above)")


def _stats(traj) -> dict:
    t, xyz = traj.t, traj.xyz
    v = np.gradient(xyz, t, axis=0)
    up, hs = v[:, 2], np.hypot(v[:, 0], v[:, 1])
    air = xyz[:, 2] > 0.5
    return {"duration_s": t[-1], "climb_m_s": np.median(up[up > 0.3]), "descent_m_s": np.median(-up[up < -0.3]),
            "max_alt_m": xyz[:, 2].max(), "median_alt_m": np.median(xyz[air, 2]),
            "horiz_speed_m_s": np.median(hs[air & (xyz[:, 2] > 1.5)]), "max_horiz_speed_m_s": hs.max(),
            "end_x": xyz[-1, 0], "end_y": xyz[-1, 1]}


def realism(runs: int, img: Path) -> None:
    import surrealist_gym as sg
    from surrealist_gym.logs.plots import plot_trajectories
    from surrealist_gym.sim import SimConfig, simulate

    real = sg.read_flight(EXPERIMENTS / "case0.ulg").trajectory
    rows = [("real case0.ulg", _stats(real), None)]
    img.mkdir(parents=True, exist_ok=True)
    for name in ("rq1-seed1", "rq1-seed2"):
        test = sg.load_test(EXPERIMENTS / f"{name}.yaml")
        res = simulate(test, runs=runs, seed=0)
        d = np.array([sg.dtw(r.trajectory, real) for r in res])
        f = np.array([sg.frechet(r.trajectory, real) for r in res])
        st = {k: np.mean([_stats(r.trajectory)[k] for r in res]) for k in rows[0][1]}
        rows.append((f"sim {name} ({runs} runs)", st, (d, f, [r.status.value for r in res],
                                                      min(r.min_distance for r in res))))
        plot_trajectories(img / f"sim_{name}.png", [r.trajectory for r in res], obstacles=test.obstacles,
                          title=f"{name}: {runs} simulated runs vs the real case0 flight", reference=real,
                          reference_label="real flight (case0.ulg)")
    free = sg.load_test(EXPERIMENTS / "rq1-seed1.yaml").with_obstacles([])
    res = simulate(free, runs=runs, seed=0)
    rows.append((f"sim no obstacle ({runs} runs)", {k: np.mean([_stats(r.trajectory)[k] for r in res])
                                                    for k in rows[0][1]}, None))
    blocked = sg.load_test(EXPERIMENTS / "rq1-seed1.yaml")
    box = blocked.obstacles[0]
    from dataclasses import replace
    flat = blocked.with_obstacles([replace(box, x=-16.6459 * 0.52, y=6.8592 * 0.52)])
    skim = simulate(flat, runs=runs, seed=0, config=SimConfig(avoidance=False))
    print(f"3-m box on the path, avoidance off: {[r.status.value for r in skim]}")
    blocked = blocked.with_obstacles([replace(box, x=-16.6459 * 0.52, y=6.8592 * 0.52, h=4.0)])
    on = simulate(blocked, runs=runs, seed=0, config=SimConfig(avoidance=True))
    off = simulate(blocked, runs=runs, seed=0, config=SimConfig(avoidance=False))
    plot_trajectories(img / "sim_avoidance.png", [r.trajectory for r in on + off],
                      labels=[f"avoidance on: {r.status.value}" if i == 0 else None for i, r in enumerate(on)] +
                      [f"avoidance off: {r.status.value}" if i == 0 else None for i, r in enumerate(off)],
                      styles=[{"color": "tab:blue"}] * runs + [{"color": "tab:red"}] * runs,
                      obstacles=blocked.obstacles, title="seed-1 box moved onto the straight path (4 m tall)")
    keys = list(rows[0][1])
    print("| flight | " + " | ".join(keys) + " |")
    print("|---" * (len(keys) + 1) + "|")
    for name, st, _ in rows:
        print(f"| {name} | " + " | ".join(f"{st[k]:.2f}" for k in keys) + " |")
    for name, _, extra in rows:
        if extra is not None:
            d, f, statuses, mind = extra
            print(f"{name}: DTW {d.mean():.1f} +- {d.std():.1f} (min {d.min():.1f}), Frechet {f.mean():.2f} +- "
                  f"{f.std():.2f} m; statuses {statuses}; min distance {mind:.2f} m")
    print(f"4-m box on the path: avoidance on {[r.status.value for r in on]} (min distance "
          f"{min(r.min_distance for r in on):.2f} m); off {[r.status.value for r in off]}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--realism", action="store_true", help="realism figures and docs/img/sim_*.png")
    parser.add_argument("--runs", type=int, default=5, help="runs per test for --realism")
    args = parser.parse_args()
    if args.realism:
        realism(args.runs, ROOT / "docs" / "img")
    else:
        speed(args.repeat)


if __name__ == "__main__":
    main()
