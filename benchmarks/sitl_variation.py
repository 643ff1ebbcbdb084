"""The measured numbers behind the SITL profiles' run-to-run variation (docs/simulator.md).

    python benchmarks/sitl_variation.py

- ``m0.ulg`` (PX4 SITL Iris + PX4-Avoidance, with Gazebo's ground truth): the estimator's error while airborne
  (``vehicle_local_position`` minus ``vehicle_local_position_groundtruth``, offset at the first sample removed) and the
  simulated GPS's error (``vehicle_gps_position`` minus ``vehicle_global_position_groundtruth``) with its
  autocorrelation;
- ``rilast-mission1/trajectories.csv`` (24 PX4 SITL flights): when each leaves the ground (first 0.5 s sample above
  0.3 m), the spread of the mission start.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from pyulog import ULog

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
AIRBORNE_MARGIN_S = (17.0, 12.0)  # m0: lift-off ~17 s after its first sample; the last 12 s are landing and ground


def estimator_errors(path) -> dict:
    """Std of m0's estimator error while airborne (x, y, z [m]) and of its GPS error (north, east [m])."""
    topics = {d.name: d.data for d in ULog(str(path)).data_list if d.multi_id == 0}
    lp, gt = topics["vehicle_local_position"], topics["vehicle_local_position_groundtruth"]
    t = lp["timestamp"] / 1e6
    err = {k: lp[k] - np.interp(lp["timestamp"], gt["timestamp"], gt[k]) for k in ("x", "y", "z")}
    err = {k: v - v[0] for k, v in err.items()}
    air = (t > t[0] + AIRBORNE_MARGIN_S[0]) & (t < t[-1] - AIRBORNE_MARGIN_S[1])
    gps, ggt = topics["vehicle_gps_position"], topics["vehicle_global_position_groundtruth"]
    lat0 = np.interp(gps["timestamp"], ggt["timestamp"], ggt["lat"])
    lon0 = np.interp(gps["timestamp"], ggt["timestamp"], ggt["lon"])
    north = np.radians(gps["lat"] / 1e7 - lat0) * 6_371_000.0
    east = np.radians(gps["lon"] / 1e7 - lon0) * 6_371_000.0 * np.cos(np.radians(lat0))
    rate = 1e6 / float(np.median(np.diff(gps["timestamp"])))
    lag = int(round(4.0 * rate))
    n = north - north.mean()
    return {"local_std_xyz_m": [float(err[k][air].std()) for k in ("x", "y", "z")],
            "gps_std_ne_m": [float(north.std()), float(east.std())],
            "gps_rate_hz": rate, "gps_autocorrelation_4s": float(np.corrcoef(n[:-lag], n[lag:])[0, 1])}


def liftoff_times(path) -> np.ndarray:
    """Seconds from each trajectory's first sample to its first sample above 0.3 m (2 Hz samples)."""
    out = []
    for _, g in pd.read_csv(path).groupby("test_id"):
        z = g.sort_values("sample").z.to_numpy()
        if (z > 0.3).any():
            out.append(0.5 * int(np.argmax(z > 0.3)))
    return np.array(out)


def main() -> None:
    est = estimator_errors(DATA / "surrealist" / "experiments" / "m0.ulg")
    print("m0.ulg estimator error while airborne, std x / y / z: "
          + " / ".join(f"{v:.3f}" for v in est["local_std_xyz_m"]) + " m")
    print(f"m0.ulg GPS error, std north / east: {est['gps_std_ne_m'][0]:.3f} / {est['gps_std_ne_m'][1]:.3f} m "
          f"(logged at {est['gps_rate_hz']:.1f} Hz), autocorrelation at 4 s {est['gps_autocorrelation_4s']:.2f}")
    lift = liftoff_times(DATA / "competition" / "rilast-mission1" / "trajectories.csv")
    print(f"rilast-mission1: {len(lift)} PX4 flights leave the ground {lift.min():.1f}-{lift.max():.1f} s after their "
          f"first sample, median {np.median(lift):.1f} s, std {lift.std():.2f} s")


if __name__ == "__main__":
    main()
