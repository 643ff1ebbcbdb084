"""The Trajectory value and the paper's trajectory pipeline.

Frame: local, metres, x north, y east, z UP, origin at the first logged position; time in seconds from the first
sample. Real and simulated flights go through the same pipeline (:meth:`Trajectory.from_local_position`):
subtract the first timestamp and the first position, then average consecutive 0.5 s windows. The competition's
distance is measured on Aerialist's own pipeline (:meth:`Trajectory.aerialist`), whose windows are closed on the
right instead.
"""
from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np

from .errors import LogFormatError

WINDOW_S = 0.5


def frozen_array(a, dtype=np.float64) -> np.ndarray:
    """A read-only copy of ``a``."""
    arr = np.array(a, dtype=dtype, copy=True)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, slots=True, eq=False)
class Trajectory:
    """An immutable 3-D trajectory.

    Attributes:
        t: (N,) seconds since the first sample.
        xyz: (N, 3) positions in metres (x north, y east, z up).
        heading: (N,) heading in radians relative to the first sample, or None.
    """

    t: np.ndarray
    xyz: np.ndarray
    heading: np.ndarray | None = None

    def __post_init__(self):
        t = frozen_array(self.t)
        xyz = frozen_array(self.xyz)
        if xyz.ndim != 2 or xyz.shape[1] != 3:
            raise ValueError(f"Trajectory.xyz must have shape (N, 3), got {xyz.shape}")
        if t.shape != (xyz.shape[0],):
            raise ValueError(f"Trajectory.t must have shape ({xyz.shape[0]},), got {t.shape}")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "xyz", xyz)
        if self.heading is not None:
            heading = frozen_array(self.heading)
            if heading.shape != t.shape:
                raise ValueError(f"Trajectory.heading must have shape {t.shape}, got {heading.shape}")
            object.__setattr__(self, "heading", heading)

    # --- construction -------------------------------------------------------------------------------------------
    @classmethod
    def from_local_position(cls, timestamp_us, x, y, z, heading=None, window_s: float = WINDOW_S) -> "Trajectory":
        """Apply the paper's pipeline to raw NED local-position samples (z down, as logged).

        Subtract the first timestamp and position, flip z to up, and average consecutive ``window_s`` windows
        (each output point is the mean time, position and heading of the samples in its window).
        """
        ts = np.asarray(timestamp_us, dtype=np.int64)
        if ts.size == 0:
            raise ValueError("no samples")
        order = np.argsort(ts, kind="stable")
        rel_t, rel, h = _relative(ts[order], x, y, z, heading, order)
        return _window_means(cls, rel_t, rel, h, rel_t // int(round(window_s * 1e6)))

    @classmethod
    def aerialist(cls, timestamp_us, x, y, z, heading=None) -> "Trajectory":
        """Aerialist's pipeline on raw NED local-position samples: what ``Trajectory.extract_from_log`` of Aerialist
        0.2.1 and master make of a ULog's ``vehicle_local_position`` (with their defaults), on which they measure
        the competition's distance.

        As the paper's pipeline, but with Aerialist's ``downsample_time``: the samples are taken in log order (not
        sorted), and a window takes every next sample whose time is at most its end, so the 0.5 s windows are closed
        on the right, ``[0, 0.5], (0.5, 1.0], ...`` from the first sample (a window with no sample gives no point;
        a sample earlier than its predecessor joins the open window). The paper's are ``[0, 0.5), [0.5, 1.0),
        ...``: on a 10 Hz log each of Aerialist's points lies one sample later than the paper's.
        """
        ts = np.asarray(timestamp_us, dtype=np.int64)
        if ts.size == 0:
            raise ValueError("no samples")
        rel_t, rel, h = _relative(ts, x, y, z, heading)
        period_us = int(round(WINDOW_S * 1e6))  # Aerialist's TRJ_SMPL_PRD, 500000 us
        bins = np.maximum.accumulate(np.maximum((rel_t - 1) // period_us, 0))  # ceil(t / P) - 1, at least 0
        return _window_means(cls, rel_t, rel, h, bins)

    @classmethod
    def from_array(cls, xyz, dt: float = WINDOW_S) -> "Trajectory":
        """A trajectory from an (N, 3) array of positions sampled every ``dt`` seconds."""
        xyz = np.asarray(xyz, dtype=np.float64)
        return cls(np.arange(len(xyz)) * dt, xyz)

    @classmethod
    def read_csv(cls, path) -> "Trajectory":
        """Read the reference format: header ``timestamp,x,y,z,r``, timestamp in microseconds."""
        try:
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        except (OSError, ValueError) as err:
            raise LogFormatError(f"{os.fspath(path)}: not a trajectory CSV (timestamp,x,y,z,r): {err}") from err
        if data.shape[1] < 4:
            raise LogFormatError(f"{os.fspath(path)}: expected columns timestamp,x,y,z[,r], got {data.shape[1]}")
        heading = data[:, 4] if data.shape[1] > 4 else None
        return cls(data[:, 0] / 1e6, data[:, 1:4], heading)

    def write_csv(self, path) -> None:
        """Write the reference format read by :meth:`read_csv`."""
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["timestamp", "x", "y", "z", "r"])
            heading = self.heading if self.heading is not None else np.zeros(len(self))
            for ti, p, h in zip(self.t, self.xyz, heading):
                w.writerow([int(round(ti * 1e6)), f"{p[0]:.6f}", f"{p[1]:.6f}", f"{p[2]:.6f}", f"{h:.6f}"])

    # --- views and derived values -------------------------------------------------------------------------------
    def __len__(self) -> int:
        return self.xyz.shape[0]

    def __array__(self, dtype=None, copy=None):
        return self.xyz if dtype is None else self.xyz.astype(dtype)

    def __eq__(self, other) -> bool:
        if not isinstance(other, Trajectory):
            return NotImplemented
        same_heading = (self.heading is None and other.heading is None) or (
            self.heading is not None and other.heading is not None and np.array_equal(self.heading, other.heading)
        )
        return np.array_equal(self.t, other.t) and np.array_equal(self.xyz, other.xyz) and same_heading

    __hash__ = None  # arrays inside: compare by value, do not hash

    @property
    def x(self) -> np.ndarray:
        """North coordinates, x [m]."""
        return self.xyz[:, 0]

    @property
    def y(self) -> np.ndarray:
        """East coordinates, y [m]."""
        return self.xyz[:, 1]

    @property
    def z(self) -> np.ndarray:
        """Heights, z up [m]."""
        return self.xyz[:, 2]

    @property
    def duration(self) -> float:
        """Time from the first sample to the last [s] (0 when empty)."""
        return float(self.t[-1] - self.t[0]) if len(self) else 0.0

    def shifted(self, dx: float = 0.0, dy: float = 0.0, dz: float = 0.0) -> "Trajectory":
        """The same trajectory translated by (dx, dy, dz) metres."""
        return Trajectory(self.t, self.xyz + np.array([dx, dy, dz]), self.heading)

    def between(self, t0: float, t1: float) -> "Trajectory":
        """The samples with t0 <= t <= t1 (times unchanged)."""
        m = (self.t >= t0) & (self.t <= t1)
        return Trajectory(self.t[m], self.xyz[m], None if self.heading is None else self.heading[m])

    def extent(self) -> dict[str, tuple[float, float]]:
        """(min, max) of x, y and z."""
        return {k: (float(self.xyz[:, i].min()), float(self.xyz[:, i].max())) for i, k in enumerate("xyz")}


def _relative(ts, x, y, z, heading=None, order=None):
    """Times [us] and positions (z flipped up) relative to the first sample, and headings relative to its heading,
    in the given ``order`` of the samples (default: as given)."""
    take = (lambda a: a) if order is None else (lambda a: a[order])
    cols = [take(np.asarray(c, dtype=np.float64)) for c in (x, y, z)]
    rel = np.column_stack([cols[0] - cols[0][0], cols[1] - cols[1][0], -(cols[2] - cols[2][0])])
    h = None if heading is None else take(np.asarray(heading, dtype=np.float64))
    return ts - ts[0], rel, None if h is None else h - h[0]


def _window_means(cls, rel_t, rel, h, bins) -> Trajectory:
    """One point per run of equal consecutive ``bins``: the mean time [s], position and heading of its samples."""
    starts = np.flatnonzero(np.r_[True, bins[1:] != bins[:-1]])
    counts = np.diff(np.r_[starts, bins.size])
    mean_t = np.add.reduceat(rel_t.astype(np.float64), starts) / counts
    mean_xyz = np.add.reduceat(rel, starts, axis=0) / counts[:, None]
    mean_h = None if h is None else np.add.reduceat(h, starts) / counts
    return cls(mean_t / 1e6, mean_xyz, mean_h)


def as_points(trajectory) -> np.ndarray:
    """An (N, 3) float64 array from a Trajectory or an array-like of points."""
    if isinstance(trajectory, Trajectory):
        return trajectory.xyz
    pts = np.asarray(trajectory, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise ValueError(f"expected a Trajectory or an (N, 3) array, got shape {pts.shape}")
    return pts


@dataclass(frozen=True, slots=True, eq=False)
class Profile:
    """A trajectory over time: one value per sample.

    Attributes:
        t: (N,) seconds since the first sample.
        altitude: (N,) z [m] (up, relative to the start).
        horizontal_speed: (N,) speed in the x-y plane [m/s] (central differences, one-sided at the ends).
        distance_to_goal: (N,) horizontal distance to the goal [m].
    """

    t: np.ndarray
    altitude: np.ndarray
    horizontal_speed: np.ndarray
    distance_to_goal: np.ndarray

    @property
    def duration(self) -> float:
        """Time from the first sample to the last [s] (0 when empty)."""
        return float(self.t[-1] - self.t[0]) if len(self.t) else 0.0

    def summary(self) -> dict:
        """Duration [s], mean and max horizontal speed and its 10/50/90 percentiles [m/s], final distance to the
        goal [m]; rounded to 0.01 for ``summary.json``."""
        speed = self.horizontal_speed
        if speed.size == 0:
            return {"duration_s": 0.0, "samples": 0}
        p10, p50, p90 = np.percentile(speed, [10, 50, 90])
        return {"duration_s": round(self.duration, 2), "samples": int(speed.size),
                "mean_horizontal_speed_mps": round(float(speed.mean()), 2),
                "max_horizontal_speed_mps": round(float(speed.max()), 2),
                "horizontal_speed_percentiles_mps": {"p10": round(float(p10), 2), "p50": round(float(p50), 2),
                                                     "p90": round(float(p90), 2)},
                "final_distance_to_goal_m": round(float(self.distance_to_goal[-1]), 2)}


def profile(trajectory, goal=None, dt: float = WINDOW_S) -> Profile:
    """Altitude, horizontal speed and horizontal distance to ``goal`` over time.

    Time base: a :class:`Trajectory` keeps its own ``t``; an (N, 3) array of points (what an evaluation keeps:
    one run, or the DBA average of the runs, all from the paper's pipeline of 0.5 s window means) is taken as
    sampled every ``dt`` seconds from 0 (default :data:`WINDOW_S` = 0.5 s). ``goal`` is an (x, y[, z]) point;
    None means the trajectory's last point.
    """
    if not isinstance(trajectory, Trajectory):
        trajectory = Trajectory.from_array(as_points(trajectory), float(dt))  # (N, 2) points fail here
    t, xyz = trajectory.t - (trajectory.t[0] if len(trajectory) else 0.0), trajectory.xyz
    if len(xyz) == 0:
        empty = np.zeros(0)
        return Profile(empty, empty, empty, empty)
    goal_xy = xyz[-1, :2] if goal is None else np.asarray(goal, dtype=np.float64)[:2]
    if len(xyz) >= 2:
        velocity = np.gradient(xyz[:, :2], t, axis=0)
        speed = np.hypot(velocity[:, 0], velocity[:, 1])
    else:
        speed = np.zeros(1)
    distance = np.hypot(xyz[:, 0] - goal_xy[0], xyz[:, 1] - goal_xy[1])
    return Profile(frozen_array(t), frozen_array(xyz[:, 2]), frozen_array(speed), frozen_array(distance))


AIRBORNE_M = 0.3   # above the start: airborne [m]
MOVING_MPS = 0.3   # horizontal speed: moving [m/s]


@dataclass(frozen=True, slots=True)
class Phases:
    """The phases of a flight, the figures calibration matches (from its 0.5 s trajectory, time from its first sample).

    Attributes:
        liftoff_s: first sample more than 0.3 m above the start [s].
        touchdown_s: last such sample [s].
        leg_start_s: first airborne sample moving faster than 0.3 m/s [s].
        cruise_speed_mps: median horizontal speed while moving (airborne, > 0.3 m/s).
        cruise_altitude_m: median altitude while moving.
        climb_s: from lift-off to the first sample within 0.3 m of the altitude at which the UAV starts to move [s].
        descent_s: from the last moving sample to touchdown [s].
    """

    liftoff_s: float
    touchdown_s: float
    leg_start_s: float
    cruise_speed_mps: float
    cruise_altitude_m: float
    climb_s: float
    descent_s: float


def phases(trajectory: Trajectory, where: str = "flight") -> Phases:
    """The phases of a flight; a flight that never lifts off or never moves raises :class:`LogFormatError`."""
    p = profile(trajectory)
    z, v, t = p.altitude, p.horizontal_speed, p.t
    air = np.nonzero(z > AIRBORNE_M)[0]
    if len(air) < 4:
        raise LogFormatError(f"{where}: the flight never rises {AIRBORNE_M} m above its start: no take-off to fit")
    moving = np.nonzero((z > AIRBORNE_M) & (v > MOVING_MPS))[0]
    if len(moving) < 4:
        raise LogFormatError(f"{where}: the UAV never moves faster than {MOVING_MPS} m/s in the air: no cruise to fit")
    first_move, last_move = moving[0], moving[-1]
    at_height = np.nonzero(z[air[0]:] >= z[first_move] - 0.3)[0]
    climb_end = air[0] + (at_height[0] if len(at_height) else 0)
    return Phases(float(t[air[0]]), float(t[air[-1]]), float(t[first_move]), float(np.median(v[moving])),
                  float(np.median(z[moving])), float(t[climb_end] - t[air[0]]),
                  float(max(t[air[-1]] - t[last_move], 0.0)))


def airborne_time(t, xyz, threshold: float = AIRBORNE_M) -> float:
    """Time [s] from the first to the last sample with z above ``threshold`` [m] (to the end if never landed)."""
    up = np.flatnonzero(np.asarray(xyz)[:, 2] > threshold) if len(xyz) else np.zeros(0, dtype=int)
    return float(t[up[-1]] - t[up[0]]) if up.size else 0.0
