"""The reactive planner's cycle kernel (:mod:`surrealist_gym.sim.avoidance.reactive_cycle`) against the readable
:class:`~surrealist_gym.sim.avoidance.reactive.LocalPlanner` on the cycles of real flights: the same bits."""
from __future__ import annotations

import math

import numpy as np
import pytest
from numba import types
from numba.typed import Dict

from surrealist_gym import load_test
from surrealist_gym.sim import simulate
from surrealist_gym.sim.avoidance import reactive_cycle as kc
from surrealist_gym.sim.avoidance.reactive import LocalPlanner
from surrealist_gym.sim.uav import decide_uav
from tests.conftest import EXPERIMENTS, fly_the_python_outer_loop


def _recorded_cycles(test, monkeypatch):
    """Every LocalPlanner.update of one run of ``test`` (its UAV): the planner, then each call's arguments and
    output."""
    calls, planners = [], []
    update = LocalPlanner.update

    def recording(self, t, position, velocity, goal, hits, max_speed=None):
        if not planners:
            planners.append(self)
        args = (t, tuple(map(float, position)), tuple(map(float, velocity)), tuple(map(float, goal)),
                np.array(hits, dtype=np.float64).reshape(-1, 3), math.nan if max_speed is None else float(max_speed))
        out = update(self, t, position, velocity, goal, hits, max_speed)
        calls.append((args, out))
        return out

    monkeypatch.setattr(LocalPlanner, "update", recording)
    fly_the_python_outer_loop(monkeypatch)
    simulate(test, runs=1, seed=0, config=decide_uav(test).config)
    monkeypatch.undo()
    return planners[0], calls


@pytest.mark.parametrize("name", ["rq1-seed1", "rq2-seed"])
def test_the_kernel_gives_the_class_bits_over_a_flight(name, monkeypatch):
    """A flight of the case0 seeds (PX4 Vision, the reactive planner): each of its planner cycles replayed through
    the kernel from the initial state gives the class's velocity, yaw and waypoint, bit for bit."""
    planner, calls = _recorded_cycles(load_test(EXPERIMENTS / f"{name}.yaml"), monkeypatch)
    assert len(calls) > 100
    memory = Dict.empty(key_type=types.int64, value_type=types.float64)
    state, consts = kc.initial_state(), kc.constants(planner)
    avoided = 0
    for i, (args, want) in enumerate(calls):
        t, position, velocity, goal, hits, max_speed = args
        vel, yaw, waypoint = kc.cycle(memory, state, planner._cand, planner._cand_az, planner._cand_el,
                                      planner._params, consts, t, position, velocity, goal, hits, max_speed)
        assert vel == tuple(want.velocity) and yaw == want.yaw and waypoint == tuple(want.waypoint), i
        avoided += not math.isnan(state[kc.S_HEADING])
    assert avoided > 10  # the flight went round its box: the avoiding branch was replayed
