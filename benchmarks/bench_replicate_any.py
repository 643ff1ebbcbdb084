"""Replicating any flight: calibrate the UAV on the log, then replicate it, as a new user would.

For each flight, in one run:
- ``baseline``: the paper's set-up (``--uav px4-vision-case0 --seed paper``: the case0 PX4 Vision, whatever flew
  the log);
- ``default``: ``surrealist replicate LOG`` (the log's own vehicle, on the ground as long as the log);
- ``calibrated``: ``surrealist calibrate LOG --profile uav.yaml`` then ``replicate LOG --uav uav.yaml``;
- ``calibrated+search``: the same with ``--search-uav``.

It prints, per flight and configuration: seed and best DTW, the best's reduction against its own seed and against
the baseline's seed, best Fréchet, the best's duration against the real one, and wall time; and the calibration's
time. Flights: ``m0`` (shared/data/surrealist/experiments/m0.ulg, PX4 SITL + PX4-Avoidance) and, held out, PX4
SITL + PX4-Avoidance flights of the competition's mission1 (rilast-mission1/trajectories.csv, odd runs, which the
SITL profile's calibration did not see), written as ULogs with their mission and parameters (``held_out_log``).

    python benchmarks/bench_replicate_any.py                      # m0 and 3 held-out flights, budget 100, 5 runs
    python benchmarks/bench_replicate_any.py --flights m0 --configs default calibrated
"""
from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
M0 = SHARED / "surrealist" / "experiments" / "m0.ulg"
RILAST = SHARED / "competition" / "rilast-mission1"
CASE_STUDIES = SHARED / "competition" / "case_studies"
HELD_OUT = ("random_run3_193", "random_run3_182", "random_run1_15")
CONFIGS = ("baseline", "default", "calibrated", "calibrated+search")


def held_out_log(test_id: str, folder: Path) -> Path:
    """A rilast PX4 SITL flight of mission1 as a ULog: its 2 Hz trajectory (z up, first sample at the origin),
    mission1.plan, mission-params.csv plus the SITL Iris airframe (1015, avoidance on)."""
    from surrealist_gym.logs.ulog_writer import write_ulog
    from surrealist_gym.mission import read_plan

    rows = [r for r in csv.DictReader(open(RILAST / "trajectories.csv")) if r["test_id"] == test_id]
    xyz = np.array([[float(r["x"]), float(r["y"]), float(r["z"])] for r in rows])
    yaw = np.array([float(r["yaw"]) for r in rows])
    t = np.arange(len(xyz)) * 0.5
    v = np.gradient(xyz, t, axis=0)
    params = {"SYS_AUTOSTART": 1015, "COM_OBS_AVOID": 1, "MAV_TYPE": 2}
    for line in (CASE_STUDIES / "mission-params.csv").read_text().splitlines():
        if "," in line:
            name, value = (s.strip() for s in line.split(",", 1))
            params[name] = float(value) if "." in value else int(value)
    path = folder / f"{test_id}.ulg"
    write_ulog(path, (t * 1e6).astype(np.int64) + 100_000, xyz[:, 0], xyz[:, 1], -xyz[:, 2], v[:, 0], v[:, 1],
               -v[:, 2], yaw, params=params, mission=read_plan(CASE_STUDIES / "mission1.plan"))
    return path


def surrealist(*args: str) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "surrealist_gym.cli", *args], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)
    return time.perf_counter() - start


def figures(out: Path) -> dict:
    summary = json.loads((out / "summary.json").read_text())
    profiles = summary["profiles"]
    return {"seed_dtw": summary["seed_terms"]["dtw"], "best_dtw": summary["best_terms"]["dtw"],
            "best_frechet": summary["best_terms"]["frechet"], "real_s": profiles["real"]["duration_s"],
            "best_s": profiles["best"]["duration_s"], "uav": summary["best_uav_settings"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--flights", nargs="+", default=["m0", *HELD_OUT])
    parser.add_argument("--configs", nargs="+", default=list(CONFIGS), choices=CONFIGS)
    parser.add_argument("--budget", type=int, default=100)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "bench-replicate-any")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    common = ["--budget", str(args.budget), "--runs", str(args.runs), "--workers", str(args.workers)]
    print(f"{'flight':16s} {'config':18s} {'seed':>7s} {'best':>7s} {'vs seed':>8s} {'vs base':>8s} {'frechet':>8s} "
          f"{'real s':>7s} {'best s':>7s} {'wall s':>7s}")
    for flight in args.flights:
        log = M0 if flight == "m0" else held_out_log(flight, args.out)
        uav = args.out / f"{flight}-uav.yaml"
        if any(c.startswith("calibrated") for c in args.configs):
            seconds = surrealist("calibrate", str(log), "--profile", str(uav), "--workers", str(args.workers))
            print(f"{flight:16s} calibrate: {seconds:.1f} s")
        base_seed = None
        for config in args.configs:
            out = args.out / f"{flight}-{config}"
            extra = {"baseline": ["--uav", "px4-vision-case0", "--seed", "paper"], "default": [],
                     "calibrated": ["--uav", str(uav)], "calibrated+search": ["--uav", str(uav), "--search-uav"]}
            if not (out / "summary.json").is_file():
                wall = surrealist("replicate", str(log), *common, *extra[config], "--out", str(out))
            else:
                wall = json.loads((out / "summary.json").read_text())["wall_seconds"]
            f = figures(out)
            base_seed = f["seed_dtw"] if config == "baseline" else base_seed
            vs_base = f"{1 - f['best_dtw'] / base_seed:8.0%}" if base_seed else f"{'':8s}"
            print(f"{flight:16s} {config:18s} {f['seed_dtw']:7.1f} {f['best_dtw']:7.1f} "
                  f"{1 - f['best_dtw'] / f['seed_dtw']:8.0%} {vs_base} {f['best_frechet']:8.2f} {f['real_s']:7.1f} "
                  f"{f['best_s']:7.1f} {wall:7.1f}" + (f"  uav {f['uav']}" if f["uav"] else ""), flush=True)


if __name__ == "__main__":
    main()
