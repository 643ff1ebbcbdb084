"""Surrealist-Replicate-v0: find the obstacle layout whose simulated flight matches a real one (paper RQ1).

Reward: ``-DTW(real trajectory, average of the n simulated runs)``. Defaults are the paper's RQ1: the bundled
real flight ``case0.ulg``, the paper's seed 1, 5 runs per evaluation, budget 100, all mutators on every obstacle
(authors' order y, x, r, sy, sx, sz).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..aerialist import load_test
from ..errors import InvalidTestCase, LogFormatError
from ..evaluation import ReplicationObjective
from ..mutators import AUTHORS_ORDER, default_mutators, uav_mutators as uav_mutators_of
from ..sim.uav import decide_uav
from ..testcase import Obstacle, TestCase
from .base import EnvSetup, SurrealistEnv


class ReplicateEnv(SurrealistEnv):
    """Replicate a real flight by searching obstacle placements."""

    def __init__(self, reference_log=None, seed_test=None, runs: int = 5, budget: int = 100, mutators=None,
                 averaging: str = "dba", executor=None, store=None, random_seed: int = 0, sim_config=None,
                 workers: int | None = None, uav=None, reference_trajectory=None, allow_partial: bool = False,
                 uav_mutators=None, render_mode: str | None = None):
        """``reference_trajectory`` (a Trajectory) replaces the log's, e.g. a simulated flight with hidden
        obstacles that plays the real one; the seed test then must be given. A damaged log (truncated, or with
        corrupt data skipped) is refused unless ``allow_partial``: its flight may be cut short.

        ``uav``: the UAV profile; by default the log's own (:func:`~surrealist_gym.sim.profiles.profile_for_flight`:
        its vehicle's preset, on the ground as long as the log) unless ``sim_config`` is a full
        :class:`~surrealist_gym.sim.config.SimConfig`. ``uav_mutators``: search the UAV's settings as well as the
        obstacles (paper section 3): True for all of the profile's :data:`~surrealist_gym.sim.profiles.SETTINGS`,
        or their names, or :class:`~surrealist_gym.mutators.UavMutator` values; they come after the obstacles'."""
        from .. import data_path
        from ..logs import read_flight

        seed_kind = "tall"
        if isinstance(seed_test, str) and seed_test in SEEDS:
            seed_kind, seed_test = seed_test, None
        elif seed_test is not None and not isinstance(seed_test, TestCase):
            seed_test = load_test(seed_test)
        self.flight = None
        if reference_trajectory is not None:
            if seed_test is None:
                raise ValueError("reference_trajectory needs a seed_test")
            self.reference = reference_trajectory
        else:
            if seed_test is None and reference_log is None:
                seed_test = load_test(data_path("rq1-seed1.yaml"))
            if reference_log is None:
                reference_log = seed_test.reference_log or data_path("case0.ulg")
            self.flight = read_flight(reference_log)
            if self.flight.damage and not allow_partial:
                raise LogFormatError(f"{self.flight.path}: {self.flight.damage}; replicating it would replicate a "
                                     f"flight cut short (allow it with --allow-partial)")
            seed_test = replace(seed_test or seed_for(self.flight, seed_kind), reference_log=str(self.flight.path))
            self.reference = self.flight.trajectory
        self.averaging = averaging
        self.uav = decide_uav(seed_test, uav, flight=self.flight, config=sim_config)
        mutators = tuple(mutators or default_mutators(seed_test, AUTHORS_ORDER))
        if uav_mutators:
            if uav_mutators is True or all(isinstance(m, str) for m in uav_mutators):
                profile = self.uav.profile or decide_uav(seed_test).profile  # a SimConfig as it is: the seed's UAV
                names = None if uav_mutators is True else list(uav_mutators)
                uav_mutators = uav_mutators_of(profile, names)
            mutators += tuple(uav_mutators)
        setup = EnvSetup(runs=runs, random_seed=random_seed, sim_config=sim_config, uav=uav, executor=executor,
                         workers=workers, store=store)
        super().__init__(seed_test, mutators, budget, setup=setup, render_mode=render_mode)

    def _objective(self):
        return ReplicationObjective(self.reference, self.averaging)

    def _decide_uav(self, seed_test, setup):
        return self.uav  # decided with the log's vehicle

    def _reference(self):
        return self.reference


SEEDS = ("tall", "paper", "detours")  # the seeds a log without a seed test can start from (seed_test="paper" etc.)
TALLER_M = 2.0      # how much taller than the flight a seed box is that the UAV must fly around
CLEARANCE_M = 2.0   # the gap a detour keeps to what it flies around (about PX4-Avoidance's, as case0 and m0 fly)
FAR_SIDE_M = 8.0    # how much further a seed box reaches on the side the flight did not take: that side is long
DETOUR_PEAK_M = 2.0  # a deviation from the mission line smaller than this is not taken for a detour


def seed_for(flight, kind: str = "tall") -> TestCase:
    """The seed test of a log without one: ``tall`` (default: the paper's box in the middle of the mission line,
    :data:`TALLER_M` taller than the flight, so it is flown around, not over), ``paper`` (:func:`seed_from_flight`:
    3 x 3 x 3 m) or ``detours`` (:func:`seed_from_detours`)."""
    if kind == "tall":
        paper = seed_from_flight(flight)
        height = round(max(float(np.max(flight.trajectory.xyz[:, 2])) + TALLER_M, paper.obstacles[0].h), 2)
        return replace(paper, obstacles=(replace(paper.obstacles[0], h=height),))
    if kind == "paper":
        return seed_from_flight(flight)
    if kind == "detours":
        return seed_from_detours(flight)
    raise InvalidTestCase(f"seed {kind!r}: expected a test YAML or one of {SEEDS}")


def seed_from_flight(flight, size: float = 3.0) -> TestCase:
    """The paper's seed for a log without one: a size^3 box near the middle of the straight path, turned along it."""
    x0, y0, x1, y1 = _mission_ends(flight)
    yaw = math.degrees(math.atan2(y1 - y0, x1 - x0))
    box = Obstacle(size, size, size, (x0 + x1) / 2, (y0 + y1) / 2, 0.0, yaw)
    return TestCase(mission=flight.mission, obstacles=(box,), params=dict(flight.params),
                    reference_log=str(flight.path))


def seed_from_detours(flight, max_obstacles: int = 3) -> TestCase:
    """A seed whose boxes stand where the real flight leaves its mission line (the straight line from the first to
    the last position of the mission), one per detour (up to ``max_obstacles``, largest first).

    A detour is a peak of the flight's distance from the line, at least :data:`DETOUR_PEAK_M` high and standing
    1.5 m above what is around it (``scipy.signal.find_peaks``). Its box is as long, along the line, as the part of
    the detour above half its prominence; its near edge leaves :data:`CLEARANCE_M` to the detour's widest point;
    it reaches :data:`FAR_SIDE_M` further on the other side of the line than on the detour's side, so that going
    round the detour's side is the short way; it is :data:`TALLER_M` taller than the flight.
    The paper's box (:func:`seed_from_flight`) when the flight keeps to its line.
    """
    from scipy.signal import find_peaks, peak_widths

    x0, y0, x1, y1 = _mission_ends(flight)
    xyz = np.asarray(flight.trajectory.xyz)
    start, end = np.array([x0, y0]), np.array([x1, y1])
    unit = (end - start) / max(float(np.hypot(*(end - start))), 1e-9)
    rel = xyz[:, :2] - start
    along = rel @ unit
    across = rel @ np.array([-unit[1], unit[0]])  # left of the line positive
    boxes = []
    for side in (1.0, -1.0):
        signed = side * across
        peaks, _ = find_peaks(signed, height=DETOUR_PEAK_M, prominence=1.5)
        if len(peaks) == 0:
            continue
        _, _, left, right = peak_widths(signed, peaks, rel_height=0.5)
        for peak, lo, hi in zip(peaks, left, right):
            span = np.interp([lo, hi], np.arange(len(along)), along)
            boxes.append((float(signed[peak]), side, float(along[peak]), float(abs(span[1] - span[0]))))
    height = round(float(xyz[:, 2].max()) + TALLER_M, 2)
    yaw = math.degrees(math.atan2(unit[1], unit[0]))
    obstacles = []
    for width, side, centre, length in sorted(boxes, reverse=True)[:max_obstacles]:
        near = max(width - CLEARANCE_M, 0.5)            # from the line to the box's edge on the detour's side
        across_size = 2 * near + FAR_SIDE_M
        offset = side * (near - across_size / 2)
        point = start + unit * centre + offset * np.array([-unit[1], unit[0]])
        obstacles.append(Obstacle(round(min(max(length, 2.0), 20.0), 2), round(across_size, 2), height,
                                  round(float(point[0]), 2), round(float(point[1]), 2), 0.0, round(yaw, 1)))
    paper = seed_from_flight(flight)
    for n in range(len(obstacles), 0, -1):  # detours too close to hold a box each: the largest ones
        try:
            return replace(paper, obstacles=tuple(obstacles[:n]))
        except InvalidTestCase:
            continue
    return paper


def _mission_ends(flight) -> tuple[float, float, float, float]:
    if flight.mission is None or len(flight.mission.waypoints) < 2:
        raise InvalidTestCase(f"{flight.path}: the log holds no mission with two positions to place a seed obstacle "
                              f"on; give a seed test (--seed TEST.yaml)")
    (x0, y0, _), (x1, y1, _) = flight.mission.waypoints[0], flight.mission.waypoints[-1]
    return x0, y0, x1, y1
