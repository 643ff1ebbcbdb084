"""Every shipped planner and mutator satisfies its Protocol (sim/avoidance/planner.py, mutators.PropertyMutator):
declared, by shape (each member present) and through isinstance on real instances; the planner's run-loop step is its
update."""
from __future__ import annotations

import dataclasses
import inspect
import math
import typing

import numpy as np

from surrealist_gym import mutators
from surrealist_gym.competition.rules import layout_mutators, seed_layout
from surrealist_gym.mutators import PropertyMutator, default_mutators, uav_mutators, wind_mutators
from surrealist_gym.sim.avoidance import reactive
from surrealist_gym.sim.avoidance.planner import Planner, PlannerCommand
from surrealist_gym.sim.avoidance.px4 import local_planner
from surrealist_gym.sim.config import PlannerConfig, SimConfig
from surrealist_gym.sim.profiles import PRESETS
from surrealist_gym.testcase import TestCase


def _members(protocol) -> set[str]:
    """The protocol's own members: annotated attributes, methods and properties."""
    own = {name for name, value in vars(protocol).items()
           if not name.startswith("__") and (callable(value) or isinstance(value, property))}
    return own | set(vars(protocol).get("__annotations__", {}))


def _classes(module, suffix: str) -> list[type]:
    return [cls for name, cls in vars(module).items()
            if inspect.isclass(cls) and cls.__module__ == module.__name__ and name.endswith(suffix)
            and not getattr(cls, "_is_protocol", False) and not issubclass(cls, (str, float))]


def test_the_protocols_name_what_the_run_loop_and_the_agents_use():
    assert _members(Planner) == {"reset", "step"}
    assert _members(PlannerCommand) == {"position", "yaw"}
    assert _members(PropertyMutator) == {"default_step", "min_step", "low", "high", "default_value", "name",
                                         "valid_range", "apply"}


def test_every_shipped_planner_declares_and_has_the_planner_shape():
    planners = _classes(reactive, "Planner") + _classes(local_planner, "Planner")
    outputs = _classes(reactive, "PlannerOutput") + _classes(local_planner, "PlannerOutput")
    assert {c.__name__ for c in planners} == {"LocalPlanner", "Px4LocalPlanner"}
    assert {c.__name__ for c in outputs} == {"PlannerOutput", "Px4PlannerOutput"}
    for cls in planners:
        assert Planner in cls.__mro__
        assert all(callable(getattr(cls, m)) for m in _members(Planner))
        assert list(inspect.signature(cls.step).parameters) == list(inspect.signature(Planner.step).parameters)
    for cls in outputs:
        assert PlannerCommand in cls.__mro__ and hasattr(cls, "__slots__") and "__dict__" not in dir(cls)


def test_a_planner_step_is_its_update_and_returns_a_command():
    hits = np.array([[10.0, y, z] for y in np.linspace(-4, 6, 21) for z in (8.0, 10.0, 12.0)])  # a wall ahead
    args = (0.1, (0.0, 0.0, 10.0), (1.0, 0.0, 0.0), 0.0, (40.0, 0.0, 10.0), (0.0, 0.0, 10.0), hits, 3.0)
    for make in (reactive.LocalPlanner, local_planner.Px4LocalPlanner):
        planner = make()
        assert isinstance(planner, Planner)
        out = planner.step(*args)
        assert isinstance(out, PlannerCommand) and math.isfinite(out.yaw)
        planner.reset()
        again = planner.step(*args)
        assert np.array_equal(np.asarray(again.yaw), np.asarray(out.yaw))
    t, pos, vel, yaw, goal, prev, hits, cruise = args
    simple = reactive.LocalPlanner().update(t, pos, vel, goal, hits, max_speed=cruise)
    assert reactive.LocalPlanner().step(*args) == simple and simple.position is None
    px4 = local_planner.Px4LocalPlanner().update(t, pos, vel, yaw, goal, prev, hits)
    stepped = local_planner.Px4LocalPlanner().step(*args)
    assert (stepped.position, stepped.yaw, stepped.state) == (px4.position, px4.yaw, px4.state)
    assert np.array_equal(stepped.path, px4.path)


def test_every_preset_planner_config_is_in_the_config_union():
    union = typing.get_args(PlannerConfig)
    names = {ref.__forward_arg__ for ref in union}
    assert names == {"AvoidanceConfig", "Px4AvoidanceConfig"}
    classes = (reactive.AvoidanceConfig, local_planner.Px4AvoidanceConfig)
    for profile in PRESETS.values():
        assert isinstance(profile.sim_config().avoidance_config, classes)
    hint = {f.name: f.type for f in dataclasses.fields(SimConfig)}
    assert hint["avoidance_config"] == "PlannerConfig | None" and hint["sensor_config"] == "DepthSensorConfig | None"


def test_every_shipped_mutator_declares_and_has_the_mutator_shape():
    classes = _classes(mutators, "Mutator")
    assert {c.__name__ for c in classes} == {"Mutator", "UavMutator", "WindMutator"}
    for cls in classes:
        assert PropertyMutator in cls.__mro__ and dataclasses.is_dataclass(cls)
        assert "__dict__" not in dir(cls)  # the protocol base keeps the slots
        fields = {f.name for f in dataclasses.fields(cls)}
        assert {"default_step", "min_step", "low", "high", "default_value"} <= fields
    seed = TestCase(mission=None, obstacles=seed_layout(2))
    shipped = (default_mutators(seed) + layout_mutators(seed) + wind_mutators()
               + sum((uav_mutators(p) for p in PRESETS.values()), ()))
    assert {type(m).__name__ for m in shipped} == {"Mutator", "UavMutator", "WindMutator"}
    for m in shipped:
        assert isinstance(m, PropertyMutator)
        low, high = m.valid_range(seed)
        assert m.low <= low <= high <= m.high and isinstance(m.name, str)
        assert m.apply(seed, m.default_value) is seed
    assert not isinstance(object(), PropertyMutator)
