"""The mission's frame: what lets one policy act on every case study, whatever its mission and number of boxes.

A case study's own action box (:class:`~surrealist_gym.competition.case_study_env.CaseStudyEnv`) names each box by
its place on the map, so what a policy learns there holds for that mission only. :class:`MissionFrame` names a box by
its place relative to the mission's path instead, and describes the mission in a fixed-size observation:

* **action** (``FRAME_ACTION_SIZE`` = 6 values in [-1, 1] per box, for the rules' maximum of boxes; a test of fewer
  boxes reads the first ones): where along the part of the path within the obstacle area (0 its start, 1 its end),
  how far to the path's left (+) or right (-), up to ``OFFSET_M``; l, w and h across the rules' ranges; and the turn
  relative to the path's heading there, -90 to +90 degrees. The centre is then kept within the rules' x and y bounds
  and the box turned into the rules' [0, 90] degrees (:func:`~surrealist_gym.competition.rules.canonical_box`), so the
  layout is within the rules' ranges as the case study's own action is; overlaps and walled-off layouts are still the
  env's to refuse.
* **observation** (``FRAME_OBSERVATION_SIZE`` values): up to ``MAX_WAYPOINTS`` positioned mission items (x, y, and a
  1 for an item present), the share of the path within the obstacle area, the number of boxes (one-hot), the wind
  (mean and maximum speed, direction) and the share of the budget left.

:class:`MissionFrameEnv` wraps a case-study env in this frame (for training); ``PPOAgent(frame="mission")`` acts
through the same frame on the case-study env itself (for search), so what it returns is the env's own action.

Example::

    frame = MissionFrame(load_case_study("mission2"), boxes=2)
    env_action = frame.env_action(np.zeros(FRAME_ACTION_SIZE))   # two boxes mid-path, on the path, mid-sized
"""
from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
from shapely.geometry import LineString, MultiLineString, box

from ..testcase import Obstacle, TestCase
from .rules import LAYOUT_FIELDS, RULES, Rules, canonical_box

MAX_WAYPOINTS = 6  # positioned items a mission may have in the observation (the competition's missions have 2-4)
OFFSET_M = 12.0  # how far from the path a box's centre may be put [m]
FIELDS_PER_BOX = 6
FRAME_ACTION_SIZE = FIELDS_PER_BOX * RULES.max_obstacles
FRAME_OBSERVATION_SIZE = 3 * MAX_WAYPOINTS + 1 + RULES.max_obstacles + 4 + 1
_X_SCALE, _Y_SCALE, _WIND_SCALE = 40.0, 60.0, 10.0  # the observation's units: metres and m/s over these
OBSERVATION_BOUND = 5.0  # every observation value is clipped to +-this (a waypoint 200 m out, a 50 m/s wind)


OBSERVATION_SPACE = gym.spaces.Box(-OBSERVATION_BOUND, OBSERVATION_BOUND, shape=(FRAME_OBSERVATION_SIZE,),
                                   dtype=np.float32)
ACTION_SPACE = gym.spaces.Box(-1.0, 1.0, shape=(FRAME_ACTION_SIZE,), dtype=np.float32)


class MissionFrame:
    """A case study's mission, seen by a policy: its observation and the boxes a frame action stands for.

    Args:
        test: the case study (its mission, and its wind if any; its obstacles are not read).
        boxes: the number of boxes of its tests (1 to the rules' maximum).
        rules: the competition's rules.
    """

    def __init__(self, test: TestCase, boxes: int, rules: Rules = RULES):
        if test.mission is None:
            raise ValueError("MissionFrame: the case study has no mission")
        if not 1 <= boxes <= rules.max_obstacles:
            raise ValueError(f"MissionFrame: expected 1 to {rules.max_obstacles} boxes, got {boxes}")
        self.rules, self.boxes = rules, int(boxes)
        points = [(0.0, 0.0)] + [(x, y) for x, y, _ in test.mission.waypoints]
        self.waypoints = tuple(points[1:MAX_WAYPOINTS + 1])
        distinct = _distinct(points)
        path = LineString(distinct) if len(distinct) > 1 else None
        area = box(rules.x[0], rules.y[0], rules.x[1], rules.y[1])
        inside = path.intersection(area) if path is not None else LineString()
        pieces = list(inside.geoms) if isinstance(inside, MultiLineString) else [inside]
        self._pieces = [p for p in pieces if isinstance(p, LineString) and p.length > 1e-6]
        if not self._pieces:  # the path never crosses the obstacle area: the frame follows the area's mid-line
            (x0, x1), y = rules.x, sum(rules.y) / 2
            self._pieces = [LineString([((x0 + x1) / 2, rules.y[0]), ((x0 + x1) / 2, rules.y[1])])] if path is None \
                else [LineString([(x0, y), (x1, y)])]
        self._ends = np.cumsum([p.length for p in self._pieces])
        self.path_share = float(self._ends[-1] / path.length) if path is not None and path.length > 0 else 0.0
        self.wind = test.wind
        self._mission_obs = self._mission_observation()

    @classmethod
    def of(cls, env) -> "MissionFrame":
        """The frame of a case-study env (any layer of it): its case study, its number of boxes and its rules."""
        inner = env.unwrapped
        return cls(inner.case_study, len(inner.seed_test.obstacles), inner.rules)

    # --- observation --------------------------------------------------------------------------------------------
    def _mission_observation(self) -> np.ndarray:
        slots = np.zeros((MAX_WAYPOINTS, 3))
        for i, (x, y) in enumerate(self.waypoints):
            slots[i] = (x / _X_SCALE, y / _Y_SCALE, 1.0)
        count = np.zeros(self.rules.max_obstacles)
        count[self.boxes - 1] = 1.0
        wind = np.zeros(4)
        if self.wind is not None and self.wind.velocity_mean > 0:
            dx, dy = self.wind.direction[0], self.wind.direction[1]
            norm = math.hypot(dx, dy) or 1.0
            top = self.wind.velocity_max or self.wind.velocity_mean
            wind = np.array([self.wind.velocity_mean / _WIND_SCALE, top / _WIND_SCALE, dx / norm, dy / norm])
        return np.concatenate([slots.reshape(-1), [self.path_share], count, wind])

    def observe(self, env) -> np.ndarray:
        """The observation as ``env`` stands (the share of its budget left)."""
        return self.observation(max(env.budget_left, 0) / env.budget)

    def observation(self, budget_share: float = 1.0) -> np.ndarray:
        """The observation: the mission, the boxes, the wind and the share of the budget left."""
        obs = np.concatenate([self._mission_obs, [float(budget_share)]])
        return np.clip(obs, -OBSERVATION_BOUND, OBSERVATION_BOUND).astype(np.float32)

    # --- action ---------------------------------------------------------------------------------------------------
    def layout(self, action) -> tuple[Obstacle, ...]:
        """The boxes (within the rules' ranges, possibly overlapping) a frame action stands for."""
        a = np.clip(np.asarray(action, dtype=np.float64).reshape(-1), -1.0, 1.0)
        if a.size != FRAME_ACTION_SIZE:
            raise ValueError(f"MissionFrame: expected {FRAME_ACTION_SIZE} action values, got {a.size}")
        return tuple(self._box(a[FIELDS_PER_BOX * i:FIELDS_PER_BOX * (i + 1)]) for i in range(self.boxes))

    def _box(self, a: np.ndarray) -> Obstacle:
        along, offset, l_, w_, h_, turn = a
        x, y, heading = self._point((along + 1) / 2 * self._ends[-1])
        x, y = x - math.sin(heading) * offset * OFFSET_M, y + math.cos(heading) * offset * OFFSET_M
        size = {name: _scale(v, self.rules.bounds(name)) for name, v in zip("lwh", (l_, w_, h_))}
        x, y = float(np.clip(x, *self.rules.x)), float(np.clip(y, *self.rules.y))
        r = math.degrees(heading) + 90.0 * turn
        return canonical_box(Obstacle(size["l"], size["w"], size["h"], x, y, 0.0, r % 180.0))

    def _point(self, distance: float) -> tuple[float, float, float]:
        """The point at ``distance`` along the path within the area, and the path's heading there [rad]."""
        i = int(min(np.searchsorted(self._ends, distance), len(self._pieces) - 1))
        piece = self._pieces[i]
        local = float(np.clip(distance - (self._ends[i] - piece.length), 0.0, piece.length))
        here = piece.interpolate(local)
        ahead, behind = piece.interpolate(min(local + 0.5, piece.length)), piece.interpolate(max(local - 0.5, 0.0))
        return here.x, here.y, math.atan2(ahead.y - behind.y, ahead.x - behind.x)

    def env_action(self, action) -> np.ndarray:
        """The case-study env's own action (the rules' box: -1 a rule's low bound, +1 its high bound) of the layout a
        frame action stands for."""
        values = []
        for o in self.layout(action):
            for name in LAYOUT_FIELDS:
                low, high = self.rules.bounds(name)
                values.append((getattr(o, name) - low) / (high - low) * 2.0 - 1.0)
        return np.clip(np.array(values), -1.0, 1.0)


class MissionFrameEnv(gym.Wrapper):
    """A case-study env seen in its mission's frame: the frame's observation and action (for training one policy on
    many missions). The reward, termination and info are the case-study env's."""

    def __init__(self, env):
        super().__init__(env)
        self.frame = MissionFrame.of(env)
        self.action_space, self.observation_space = ACTION_SPACE, OBSERVATION_SPACE

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset the case-study env; the frame's observation, and its info."""
        _, info = self.env.reset(seed=seed, options=options)
        return self.frame.observe(self.env.unwrapped), info

    def step(self, action):
        """Step the case-study env with the layout a frame action stands for."""
        _, reward, terminated, truncated, info = self.env.step(self.frame.env_action(action))
        return self.frame.observe(self.env.unwrapped), reward, terminated, truncated, info


def _scale(value: float, bounds: tuple[float, float]) -> float:
    low, high = bounds
    return low + (value + 1.0) / 2.0 * (high - low)


def _distinct(points):
    out = []
    for p in points:
        if not out or math.dist(out[-1], p) > 1e-6:
            out.append(p)
    return out
