"""Case studies drawn at random within the competition's rules, and an env that draws a new one at every reset: what a
policy for every mission trains on (``surrealist train --problem missions``).

A drawn mission has the shapes of the competition's 2024 case studies (``mission1``: out; ``mission2``: out and back;
``mission3``: out, across, back): it takes off at home to 10 m, flies 1 to 4 further legs at 10 m and lands at the
last one. Each leg crosses the obstacle area to its far end (north-east of it, 45-60 m from home) or back to its
near end (within 5 m of home's line), or, at one end, moves sideways by 8-20 m; the first leg crosses. The parameters
and commands are the base case study's (``mission1``: the competition's). Half of the drawn case studies blow a wind
(1-6 m/s mean, gusting up to 3 m/s more, from a random horizontal direction), as the 2026 case studies do. The
number of boxes is drawn from 1 to the rules' maximum. A drawn case study times out at ``DRAWN_TIMEOUT_S``.

Registered as ``Surrealist-Missions-v0``.

Example::

    env = gym.make("Surrealist-Missions-v0", budget=15)
    obs, info = env.reset(seed=0)       # a drawn case study, in its mission's frame (MissionFrameEnv)
"""
from __future__ import annotations

import math

import numpy as np

from ..envs.drawn import DrawnProblems
from ..mission import Command, Mission, MissionItem
from ..testcase import TestCase, Wind
from .mission_frame import ACTION_SPACE, OBSERVATION_SPACE, MissionFrameEnv
from .rules import RULES, load_case_study

ALTITUDE_M = 10.0
FAR_END_M = (45.0, 60.0)  # where a leg across the obstacle area ends, beyond it [m along y]
NEAR_END_M = (-3.0, 5.0)  # where a leg back ends [m along y]
SIDEWAYS_M = (8.0, 20.0)
X_RANGE_M = (-30.0, 20.0)  # the waypoints' x stays over the obstacle area's x range
#: A drawn case study's time limit [s of simulated time]: its longest mission (4 legs of up to ~65 m) takes ~130 s at
#: the SITL UAV's pace, so a run still flying at 300 s is stuck, as one still flying at the competition's 500 s is;
#: ending it sooner keeps its closest distance, which is what the reward reads, and spends less on stuck runs.
DRAWN_TIMEOUT_S = 300.0


def random_mission(rng: np.random.Generator, home: tuple[float, float, float], legs: int | None = None) -> Mission:
    """A mission of the 2024 case studies' shapes: take-off, ``legs`` (1 to 4, drawn when None) legs, landing."""
    legs = int(rng.integers(1, 5)) if legs is None else int(legs)
    if not 1 <= legs <= 4:
        raise ValueError(f"random_mission: expected 1 to 4 legs, got {legs}")
    x, y, far = 0.0, 0.0, False
    points = []
    for leg in range(legs):
        if leg == 0 or rng.random() < 0.65:  # across the area, to its other end
            far = not far
            y = float(rng.uniform(*(FAR_END_M if far else NEAR_END_M)))
            x = float(np.clip(x + rng.uniform(-15.0, 10.0), *X_RANGE_M))
        else:  # sideways at this end
            step = float(rng.uniform(*SIDEWAYS_M)) * (1 if rng.random() < 0.5 else -1)
            if not X_RANGE_M[0] <= x + step <= X_RANGE_M[1]:
                step = -step
            x = float(np.clip(x + step, *X_RANGE_M))
            y = float(y + rng.uniform(-2.0, 2.0))
        points.append((round(x, 3), round(y, 3)))
    items = [MissionItem(Command.TAKEOFF, 0.0, 0.0, ALTITUDE_M)]
    items += [MissionItem(Command.WAYPOINT, px, py, ALTITUDE_M) for px, py in points[:-1]]
    items.append(MissionItem(Command.LAND, points[-1][0], points[-1][1], 0.0))
    return Mission(tuple(items), home, cruise_speed=15, source="drawn")


def random_wind(rng: np.random.Generator) -> Wind | None:
    """No wind half the time; else a steady wind of 1-6 m/s gusting up to 3 m/s more, from a random direction."""
    if rng.random() < 0.5:
        return None
    mean = float(rng.uniform(1.0, 6.0))
    angle = float(rng.uniform(0.0, 2 * math.pi))
    return Wind(velocity_mean=round(mean, 3), velocity_max=round(mean + float(rng.uniform(0.0, 3.0)), 3),
                direction=(round(math.cos(angle), 6), round(math.sin(angle), 6), 0.0))


def random_case_study(rng: np.random.Generator, base: TestCase | None = None) -> TestCase:
    """A case study with a drawn mission and wind, on ``base``'s parameters and commands (default ``mission1``)."""
    from dataclasses import replace

    base = load_case_study("mission1") if base is None else base
    return replace(base, mission=random_mission(rng, base.mission.home), wind=random_wind(rng), mission_file=None,
                   obstacles=(), timeout=DRAWN_TIMEOUT_S)


class MissionCaseStudies(DrawnProblems):
    """A case-study env (:class:`~surrealist_gym.competition.case_study_env.CaseStudyEnv`) in its mission's frame
    (:class:`~surrealist_gym.competition.mission_frame.MissionFrameEnv`) whose case study and number of boxes are drawn
    anew at every reset (:func:`random_case_study`), for training one policy on every mission.

    Args:
        budget: evaluations per episode (one drawn case study).
        runs: simulations per evaluation.
        random_seed: the draws' and the noise's seed when ``reset`` is given none.
        boxes: the numbers of boxes drawn from (default 1 to the rules' maximum).
        **env_options: options of the case-study env (``sim_config``, ``uav``, ``executor``, ...).
    """

    def __init__(self, budget: int = 15, runs: int = 1, random_seed: int = 0, boxes=None, **env_options):
        self.budget, self.runs, self.env_options = int(budget), int(runs), env_options
        self.boxes = tuple(boxes) if boxes is not None else tuple(range(1, RULES.max_obstacles + 1))
        self._base = load_case_study("mission1")
        self.random_seed = int(random_seed)
        self.action_space, self.observation_space = ACTION_SPACE, OBSERVATION_SPACE

    def _draw(self):
        """A drawn case study and number of boxes, in its mission's frame."""
        from .case_study_env import CaseStudyEnv

        case_study = random_case_study(self.np_random, self._base)
        boxes = int(self.np_random.choice(self.boxes))
        noise = int(self.np_random.integers(0, 2**31 - 1))
        return MissionFrameEnv(CaseStudyEnv(case_study, obstacles=boxes, runs=self.runs, budget=self.budget,
                                            random_seed=noise, **self.env_options))
