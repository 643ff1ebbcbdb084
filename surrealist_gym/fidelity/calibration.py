"""Identify a UAV from its flight logs: the settings its PX4 parameters do not fix, fitted phase by phase.

A log fixes the PX4 parameters (cruise speed, take-off and landing speeds, ...), and the simulator reads them from it.
What it does not fix is fitted here, each setting from the phase of the flight it shapes (:data:`FITS`):

- ``takeoff_delay_s`` from the lift-off time (the first 0.5 s sample more than 0.3 m above the start);
- ``takeoff_hold_s`` from the time the first leg starts (the first airborne sample moving faster than 0.3 m/s);
- the planner's pace setting from the median horizontal speed while the UAV moves (> 0.3 m/s, airborne);
- the simple planner's altitude setting (how far from an obstacle it starts to rise over it) from the median
  altitude while it moves.

PX4-Avoidance's cruise altitude is not fitted, only reported: in the model it comes from the camera's ground returns
against the pitch cost, and a pitch cost low enough to meet m0's 5.3 m makes the planner climb over low boxes and
sink to the ground before tall ones (docs/calibration.md).

Each fit flies the log's mission (no obstacles unless a seed test is given) on the profile, with the setting set
through the test's ``uav.<setting>`` param, over a grid of the setting's range, interpolates the value that meets the
real figure, and flies that value to measure the residual. Several logs of one UAV fit one value (their mean residual
is zero). Climb, descent and touchdown are set by PX4 parameters the log holds; they are reported as checks.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from ..errors import DependencyNotInstalled, FrozenDict, InvalidProfile, LogFormatError, MissionError
from ..sim.config import UAV_SETTING_PREFIX, AvoidanceModel
from ..sim.profiles import SETTINGS, TIMING_SETTINGS, UavProfile, check_multirotor, vehicle_of
from ..sim.uav import decide_uav
from ..testcase import TestCase
from ..trajectory import Phases, Trajectory, phases, profile as time_profile

__all__ = ["Calibration", "FITS", "Fit", "calibrate"]


@dataclass(frozen=True, slots=True)
class Fit:
    """What one setting is fitted to: a figure of :class:`Phases`, and how the printout names it."""

    setting: str
    figure: str
    label: str


# Per avoidance model: the settings fitted, in order (the timings first: they shift the rest of the flight)
FITS = FrozenDict({
    AvoidanceModel.PX4: (Fit("takeoff_delay_s", "liftoff_s", "lift-off [s]"),
                         Fit("takeoff_hold_s", "leg_start_s", "first leg starts [s]"),
                         Fit("planner.heading_offset_deg", "cruise_speed_mps", "cruise speed [m/s]")),
    AvoidanceModel.SIMPLE: (Fit("takeoff_delay_s", "liftoff_s", "lift-off [s]"),
                            Fit("takeoff_hold_s", "leg_start_s", "first leg starts [s]"),
                            Fit("planner.avoid_speed", "cruise_speed_mps", "cruise speed [m/s]"),
                            Fit("planner.vertical_radius", "cruise_altitude_m", "cruise altitude [m]")),
})
CHECKS = FrozenDict({AvoidanceModel.PX4: (("cruise_altitude_m", "cruise altitude [m]"), ("climb_s", "climb [s]"),
                               ("descent_s", "descent [s]"), ("touchdown_s", "touchdown [s]")),
          AvoidanceModel.SIMPLE: (("climb_s", "climb [s]"), ("descent_s", "descent [s]"),
                                  ("touchdown_s", "touchdown [s]"))})


@dataclass(frozen=True, slots=True)
class FittedSetting:
    """One fitted setting: its value, and the real and simulated figure it was fitted to (mean over the logs)."""

    setting: str
    label: str
    value: float
    before: float
    real: float
    simulated: float
    note: str = ""

    @property
    def residual(self) -> float:
        return self.real - self.simulated


@dataclass(frozen=True, slots=True)
class Calibration:
    """The fitted profile, each setting's fit, the checks, and the flights (real, before and after) per log."""

    profile: UavProfile
    fitted: tuple[FittedSetting, ...]
    checks: tuple[tuple[str, float, float], ...]          # (label, real, simulated), means over the logs
    flights: tuple[tuple[str, Trajectory, Trajectory, Trajectory, tuple], ...]  # (log, real, before, after, goal)
    simulations: int


def _check_vehicle(flight, profile: UavProfile) -> None:
    """A log is calibrated on a profile of its own vehicle (when its airframe tells which)."""
    vehicle = vehicle_of(flight)
    if vehicle is not None and vehicle != profile.vehicle:
        raise InvalidProfile(f"{flight.path}: flown by {vehicle.value} (PX4 airframe "
                             f"{int(flight.params['SYS_AUTOSTART'])}), but profile {profile.name!r} flies "
                             f"{profile.vehicle.value}: calibrate a profile of the log's vehicle")


def _mission_test(flight, seed_test: TestCase | None) -> TestCase:
    if flight.mission is None or sum(it.has_position for it in flight.mission.items) < 2:
        raise MissionError(f"{flight.path}: the log holds no mission with two positions: nothing to fly to "
                           f"calibrate")
    if seed_test is not None:
        return replace(seed_test, reference_log=str(flight.path))
    return TestCase(mission=flight.mission, params=dict(flight.params), reference_log=str(flight.path))


def calibrate(flights: Sequence, base: UavProfile | None = None, seed_test: TestCase | None = None, runs: int = 2,
              executor=None, grid: int = 5, passes: int = 2, seed: int = 0,
              progress: Callable[[str], None] | None = None, store=None) -> Calibration:
    """Fit the settings of ``base`` (default: the first log's vehicle, :func:`~surrealist_gym.sim.uav.decide_uav`)
    that the logs' PX4 parameters do not fix, to the logs' phases.

    Args:
        flights: :class:`~surrealist_gym.logs.FlightLog` values of one UAV.
        seed_test: the obstacles to fly the missions with (default none).
        runs: runs per simulated figure (common noise, seeds 0..runs-1).
        executor: where the runs fly (an executor of :mod:`surrealist_gym.executors`; default this process): the
            logs' missions fly together (:func:`~surrealist_gym.executors.fly_many`).
        grid: values of each setting's range flown before interpolating.
        passes: rounds over the settings (the pace moves the altitude a little, and back).
        store: an SQLite file (:class:`~surrealist_gym.store.EvaluationStore`) that keeps every run as it completes:
            a calibration interrupted and run again on it reads those back instead of flying them, and ends as an
            uninterrupted one (a store of another calibration is a one-line error).
    """
    from ..executors import InlineExecutor, fly_many

    if not flights:
        raise LogFormatError("calibrate: no log given")
    for flight in flights:
        check_multirotor(flight)
    uav = decide_uav(uav=base, flight=flights[0], config={"common_noise": True})
    base = uav.profile
    for flight in flights:
        _check_vehicle(flight, base)
    executor = executor or InlineExecutor()
    tests = [_mission_test(f, seed_test) for f in flights]
    real = [phases(f.trajectory, str(f.path)) for f in flights]
    goals = [tuple(f.mission.waypoints[-1]) for f in flights]
    config = uav.config
    settings = {s.name: s for s in SETTINGS[base.avoidance_model]}
    values = {fit.setting: settings[fit.setting].value(base) for fit in FITS[base.avoidance_model]}
    count = [0]
    cache: dict[tuple, tuple] = {}
    db, stored = _runs_store(store, tests, runs, seed, config) if store is not None else (None, {})

    def fly(vals: dict) -> tuple[list[Phases], list[Trajectory]]:
        key = tuple(sorted((k, round(v, 6)) for k, v in vals.items()))
        if key not in cache:
            got, trajs = [], []
            settings_of = {UAV_SETTING_PREFIX + k: v for k, v in vals.items()}
            batch = [replace(test, params={**test.params, **settings_of}) for test in tests]
            flown_runs = fly_many(batch, runs, seed, config, executor, have=[stored.get(t.key(), {}) for t in batch],
                                  done=None if db is None else lambda i, records: _keep(db, batch[i], records))
            for flight, results in zip(flights, flown_runs):
                count[0] += len(results)
                flown = [r for r in results if len(r.trajectory) >= 4]
                where = f"{flight.path} on profile {base.name!r} with {dict(vals)}"
                figures = [phases(r.trajectory, where) for r in flown]
                if not figures:
                    raise LogFormatError(f"{where}: no simulated run flew")
                got.append(Phases(*np.mean([[getattr(f, n) for n in Phases.__slots__] for f in figures], axis=0)))
                trajs.append(flown[0].trajectory)
            cache[key] = (got, trajs)
        return cache[key]

    try:
        return _fit(flights, base, real, goals, settings, values, fly, grid, passes, progress, count)
    finally:
        if db is not None:
            db.close()


def _fit(flights, base, real, goals, settings, values, fly, grid, passes, progress, count) -> Calibration:
    """The passes over the settings (``fly``: the logs' missions flown with some values), then the calibration."""
    def mean(figs: list[Phases], name: str) -> float:
        return float(np.mean([getattr(f, name) for f in figs]))

    before_trajs = fly(values)[1]  # the flights before calibration, for the figure
    notes: dict[str, str] = {}
    for _ in range(passes):
        for fit in FITS[base.avoidance_model]:
            s = settings[fit.setting]
            target = mean(real, fit.figure)
            if fit.setting in TIMING_SETTINGS:  # a shift: the figure moves one for one with the time
                for _ in range(2):
                    got = mean(fly(values)[0], fit.figure)
                    values[s.name] = float(np.clip(round(values[s.name] + target - got, 2), s.low, s.high))
                continue
            xs = np.geomspace(s.low, s.high, grid) if s.log_scale else np.linspace(s.low, s.high, grid)
            ys = np.array([mean(fly({**values, s.name: float(x)})[0], fit.figure) for x in xs])
            if progress:
                progress(f"{s.name}: {', '.join(f'{x:g}->{y:.2f}' for x, y in zip(xs, ys))}")
            value = _solve(xs, ys, target)
            if np.ptp(ys) < 0.02 * max(abs(target), 1e-6):
                value, notes[s.name] = values[s.name], "no effect on these flights: kept"
            elif value is None:
                value = float(xs[int(np.argmin(np.abs(ys - target)))])
                notes[s.name] = "the real figure is out of the setting's reach: the nearest value flown"
            else:
                notes.pop(s.name, None)
                nearest = int(np.argmin(np.abs(ys - target)))  # the response is noisy: keep what flies closest
                got = mean(fly({**values, s.name: round(float(value), 3)})[0], fit.figure)
                if abs(got - target) > abs(ys[nearest] - target):
                    value = float(xs[nearest])
            values[s.name] = round(float(value), 3)
    after_figs, after_trajs = fly(values)
    fitted = tuple(FittedSetting(f.setting, f.label, values[f.setting], settings[f.setting].value(base),
                                 mean(real, f.figure), mean(after_figs, f.figure), notes.get(f.setting, ""))
                   for f in FITS[base.avoidance_model])
    checks = tuple((label, mean(real, name), mean(after_figs, name)) for name, label in CHECKS[base.avoidance_model])
    names = ", ".join(Path(str(f.path)).name for f in flights)
    fitted_profile = base.with_settings(values, name=f"calibrated-{Path(str(flights[0].path)).stem}",
                                        description=f"{base.name} calibrated on {names} (surrealist calibrate)")
    flown = tuple((str(f.path), f.trajectory, b, a, g)
                  for f, b, a, g in zip(flights, before_trajs, after_trajs, goals))
    return Calibration(fitted_profile, fitted, checks, flown, count[0])


def _runs_store(store, tests, runs: int, seed: int, config) -> tuple:
    """The calibration's store, claimed for its identity (the logs' missions, runs, seed, simulator settings), and
    the runs it holds by test key ({key: {index: RunRecord}})."""
    from ..outcomes import RunRecord
    from .measure import open_store

    db = open_store(store, tests, runs, seed, config, "calibrate")
    try:
        held: dict[str, dict] = {}
        for row in db:
            held.setdefault(row.test_key, {}).update(
                (r["index"], RunRecord.from_dict(r, t)) for r, t in zip(row.runs, row.info["trajectories"]))
    except BaseException:
        db.close()
        raise
    return db, held


def _keep(db, test: TestCase, records) -> None:
    """Store a chunk of runs of ``test`` (with their trajectories) and commit it."""
    from ..store import StoredEvaluation

    db.add(StoredEvaluation(test.key(), {}, tuple(r.index for r in records), tuple(r.to_dict() for r in records),
                            None, {"trajectories": [r.trajectory.xyz.tolist() for r in records]}))


def _solve(xs: np.ndarray, ys: np.ndarray, target: float) -> float | None:
    """The x where the piecewise-linear ys(xs) meets target, nearest the best grid point; None if it never does."""
    best = None
    for i in range(len(xs) - 1):
        y0, y1 = ys[i] - target, ys[i + 1] - target
        if y0 == 0:
            x = xs[i]
        elif y0 * y1 < 0 or y1 == 0:
            x = xs[i] + (xs[i + 1] - xs[i]) * y0 / (y0 - y1)
        else:
            continue
        score = min(abs(ys[i] - target), abs(ys[i + 1] - target))
        if best is None or score < best[0]:
            best = (score, float(x))
    return None if best is None else best[1]


def format_calibration(cal: Calibration) -> str:
    """The fitted values with their residuals, and the checks, as the command prints them."""
    lines = [f"{'setting':28s} {'value':>8s} {'(was)':>8s}  {'fitted to':20s} {'real':>7s} {'sim':>7s} {'resid':>7s}"]
    for f in cal.fitted:
        lines.append(f"{f.setting:28s} {f.value:8.2f} {f.before:8.2f}  {f.label:20s} {f.real:7.2f} {f.simulated:7.2f} "
                     f"{f.residual:+7.2f}" + (f"  ({f.note})" if f.note else ""))
    lines.append("checks (not fitted: set by the log's PX4 parameters, or by obstacles):")
    for label, r, s in cal.checks:
        lines.append(f"  {label:46s} {r:7.2f} {s:7.2f} {r - s:+7.2f}")
    return "\n".join(lines)


def plot_calibration(cal: Calibration, path) -> None:
    """Altitude, horizontal speed and distance to the goal over time, per log: real, the base profile, calibrated."""
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except ImportError as err:
        raise DependencyNotInstalled("plots need matplotlib: pip install matplotlib") from err
    n = len(cal.flights)
    fig = Figure(figsize=(6 * n, 8))
    FigureCanvasAgg(fig)
    axes = fig.subplots(3, n, sharex="col", squeeze=False)
    for j, (log, real, before, after, goal) in enumerate(cal.flights):
        for label, traj, style in (("real", real, dict(color="black", lw=2.5)),
                                   ("before", before, dict(color="tab:orange", lw=1.2)),
                                   ("calibrated", after, dict(color="tab:blue", lw=1.5))):
            p = time_profile(traj, goal)
            for ax, y in zip(axes[:, j], (p.altitude, p.horizontal_speed, p.distance_to_goal)):
                ax.plot(p.t, y, label=label, **style)
        axes[0, j].set_title(log.rsplit("/", 1)[-1])
        axes[2, j].set_xlabel("time [s]")
        for ax, name in zip(axes[:, j], ("altitude [m]", "horizontal speed [m/s]", "distance to goal [m]")):
            ax.set_ylabel(name)
            ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(f"surrealist calibrate: {cal.profile.name}")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
