"""``SimConfig(physics="compiled")`` against PyBullet on the same seeds: statuses, competition distances and
trajectories.

Both loops hold a vehicle still at its starting pose until its thrust first exceeds its weight (a vehicle resting
on rigid ground does not move), so the take-off starts from the same state; in the air the integration is the same
to rounding (test_rigid_body). They differ only at touchdown (Bullet's contact solver against the compiled ground
contact), which comes at the end of a mission. Without the hold, Bullet's solver and the compiled contact left the
idle vehicle 0.1-0.5 mm apart by the take-off, enough to flip planner decisions and part runs by metres.
"""
from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
import pytest

from surrealist_gym import Mission, MissionItem, Obstacle, TestCase, Wind, load_test
from surrealist_gym.cli import main as cli_main
from surrealist_gym.errors import SurrealistError
from surrealist_gym.evaluation import search_identity
from surrealist_gym.mission import Command
from surrealist_gym.sim import NoiseConfig, Physics, RunStatus, SimConfig, simulate
from surrealist_gym.sim.config import PHYSICS_ENV, TREE_REUSE_ENV
from surrealist_gym.sim.uav import decide_uav
from surrealist_gym.store import EvaluationStore
from tests.conftest import CASE_STUDIES, EXPERIMENTS, SHARED_DATA

RILAST = SHARED_DATA / "competition" / "rilast-mission1" / "tests.csv"


def _both(test, runs, config):
    a = simulate(test, runs=runs, seed=0, config=dataclasses.replace(config, physics=Physics.PYBULLET))
    # the PyBullet loop, the reference, builds PX4-Avoidance's tree every cycle: so does the compiled one here
    b = simulate(test, runs=runs, seed=0, config=dataclasses.replace(config, physics=Physics.COMPILED,
                                                                     tree_reuse_m=0.0))
    return a, b


def _deviation(a, b, last: bool = True) -> float:
    """Largest distance between two runs' true positions at the same times [m] (over the shorter run; without
    the last sample unless ``last``)."""
    n = min(len(a.true_t), len(b.true_t)) - (0 if last else 1)
    return float(np.linalg.norm(a.true_xyz[:n] - b.true_xyz[:n], axis=1).max())


def test_physics_is_a_checked_choice(monkeypatch, tmp_path, capsys):
    monkeypatch.delenv(PHYSICS_ENV, raising=False)
    assert SimConfig().physics == Physics.COMPILED
    assert SimConfig(physics="pybullet").physics == Physics.PYBULLET
    with pytest.raises(ValueError):
        SimConfig(physics="bullet")
    monkeypatch.setenv(PHYSICS_ENV, "pybullet")
    assert SimConfig().physics == Physics.PYBULLET
    # a store's search identity names the physics only when it is not PyBullet, so stores flown on PyBullet
    # before the compiled physics existed resume on PyBullet, and only there
    assert repr(SimConfig()) == repr(SimConfig(physics="compiled"))
    assert "physics" not in search_identity(object(), 5, 0, SimConfig())
    assert search_identity(object(), 5, 0, SimConfig(physics="compiled"))["physics"] == "compiled"
    with EvaluationStore(tmp_path / "evaluations.sqlite") as store:
        store.claim(search_identity(object(), 5, 0, SimConfig()))
        refused = r"another physics \(pybullet there, compiled here\); set \$SURREALIST_PHYSICS=pybullet"
        with pytest.raises(SurrealistError, match=refused):
            store.claim(search_identity(object(), 5, 0, SimConfig(physics="compiled")))
    # a bad value is a one-line error, exit code 2, before any work
    monkeypatch.setenv(PHYSICS_ENV, "bullet")
    with pytest.raises(SurrealistError, match=r"\$SURREALIST_PHYSICS: 'bullet' is not a physics"):
        SimConfig()
    assert cli_main(["simulate", str(EXPERIMENTS / "rq1-seed1.yaml")]) == 2
    assert capsys.readouterr().err == "error: $SURREALIST_PHYSICS: 'bullet' is not a physics (compiled or pybullet)\n"


def test_the_tree_reuse_is_named_in_a_store_identity_where_it_acts(monkeypatch, tmp_path):
    """``SimConfig.tree_reuse_m`` is out of the repr; a store's identity names it only for the compiled loop flying
    PX4-Avoidance, so a store flown without it is refused by a search with it, and the simple planner's stores
    resume whatever it is. A bad value is refused."""
    monkeypatch.delenv(PHYSICS_ENV, raising=False)
    monkeypatch.delenv(TREE_REUSE_ENV, raising=False)
    sitl = decide_uav(uav="px4-v1.12-sitl-iris").config
    on = dataclasses.replace(sitl, tree_reuse_m=0.2, tree_reuse_cycles=9)
    off = dataclasses.replace(sitl, tree_reuse_m=0.0)
    assert repr(on) == repr(off) and on.reuses_trees and not off.reuses_trees
    assert search_identity(object(), 5, 0, on)["tree_reuse"] == "0.2 m, 9 cycles"
    assert "tree_reuse" not in search_identity(object(), 5, 0, off)
    simple = dataclasses.replace(SimConfig(), tree_reuse_m=0.2)
    assert "tree_reuse" not in search_identity(object(), 5, 0, simple)
    assert "tree_reuse" not in search_identity(object(), 5, 0, dataclasses.replace(on, physics="pybullet"))
    with EvaluationStore(tmp_path / "evaluations.sqlite") as store:
        store.claim(search_identity(object(), 5, 0, off))
        refused = r"another reuse of the planner's tree \(none there, 0.2 m, 9 cycles here\); set " \
                  r"\$SURREALIST_TREE_REUSE=0 to resume"
        with pytest.raises(SurrealistError, match=refused):
            store.claim(search_identity(object(), 5, 0, on))
        monkeypatch.setenv(TREE_REUSE_ENV, "0")  # what the message says resumes it
        store.claim(search_identity(object(), 5, 0, dataclasses.replace(sitl, tree_reuse_m=SimConfig().tree_reuse_m)))
    with EvaluationStore(tmp_path / "reused.sqlite") as store:  # and a store flown with it, by default
        store.claim(search_identity(object(), 5, 0, on))
        monkeypatch.delenv(TREE_REUSE_ENV)
        default = dataclasses.replace(sitl, tree_reuse_m=SimConfig().tree_reuse_m)
        resumed_with = r"\(0.2 m, 9 cycles there, none here\); set \$SURREALIST_TREE_REUSE=0.2"
        with pytest.raises(SurrealistError, match=resumed_with):
            store.claim(search_identity(object(), 5, 0, default))
    monkeypatch.setenv(TREE_REUSE_ENV, "0.5")
    assert SimConfig().tree_reuse_m == 0.5
    monkeypatch.setenv(TREE_REUSE_ENV, "near")
    with pytest.raises(SurrealistError, match=r"\$SURREALIST_TREE_REUSE: 'near' is not a distance"):
        SimConfig()
    monkeypatch.delenv(TREE_REUSE_ENV)
    assert SimConfig().tree_reuse_m == 0.0 and not decide_uav(uav="px4-v1.12-sitl-iris").config.reuses_trees
    for bad in ({"tree_reuse_m": -0.1}, {"tree_reuse_m": math.inf}, {"tree_reuse_cycles": 1.5},
                {"tree_reuse_cycles": -1}):
        with pytest.raises(ValueError, match="SimConfig.tree_reuse"):
            SimConfig(**bad)


def test_takeoff_and_box_collision_agree():
    """No noise: a take-off to 5 m, then straight into a box without avoidance: same statuses, collision times
    within one control step, true positions within 2 mm (measured 1.4 mm, from the second on the ground) up to the
    last sample (PyBullet's is after its contact impulse, 2 cm away)."""
    mission = Mission(items=(MissionItem(Command.TAKEOFF, 0.0, 0.0, 5.0),
                             MissionItem(Command.WAYPOINT, 20.0, 0.0, 5.0)), home=(47.0, 8.0, 400.0))
    test = TestCase(mission=mission, obstacles=(Obstacle(2.0, 6.0, 10.0, 10.0, 0.0, 0.0, 20.0),))
    cfg = SimConfig(avoidance=False, noise=NoiseConfig.off(), takeoff_delay_s=1.0)
    (a,), (b,) = _both(test, 1, cfg)
    assert a.status == b.status == RunStatus.COLLISION
    assert abs(a.duration - b.duration) <= 0.0100001
    assert _deviation(a, b, last=False) < 2e-3


def rilast_case(test_id: str):
    with open(RILAST, newline="") as f:
        row = next(r for r in csv.DictReader(f) if r["test_id"] == test_id)
    obstacles = [Obstacle(**o) for o in json.loads(row["obstacles"])]
    return load_test(CASE_STUDIES / "mission1.yaml").with_obstacles(obstacles)


def shipped_scenarios():
    mission1 = load_test(CASE_STUDIES / "mission1.yaml")
    return {
        "rq1-seed1": load_test(EXPERIMENTS / "rq1-seed1.yaml"),  # case0, PX4 Vision, the simple planner
        "rq2-seed": load_test(EXPERIMENTS / "rq2-seed.yaml"),
        "rilast 1 box": rilast_case("random_run0_1"),  # mission1, SITL Iris, PX4-Avoidance
        "rilast 2 boxes": rilast_case("random_run3_194"),
        "rilast 3 boxes": rilast_case("random_run0_0"),
        "mission1 cylinders": mission1.with_obstacles([Obstacle(6, 6, 20, -5, 20, shape="cylinder"),
                                                       Obstacle(4, 4, 15, 3, 35, shape="cylinder")]),
        "mission1 box, wind": dataclasses.replace(rilast_case("random_run0_1"), wind=Wind(
            velocity_mean=6.0, velocity_variance=1.0, direction=(0.0, 1.0, 0.0))),
    }


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:.*is not supported")
def test_agreement_over_shipped_scenarios():
    """Two runs (seed 0) of each scenario with its default UAV: every status the same, every competition distance
    within 0.05 m (measured: equal to 1e-4 m) and every true trajectory within 0.05 m of the other at the same times
    (measured: 25 mm at most, in the landing of an rq2-seed run, where the ground contacts differ)."""
    total = 0
    for name, test in shipped_scenarios().items():
        a, b = _both(test, 2, decide_uav(test).config)
        for ra, rb in zip(a, b):
            assert ra.status == rb.status, (name, ra.message, rb.message)
            if math.isfinite(ra.competition_distance):
                assert abs(ra.competition_distance - rb.competition_distance) <= 0.05, name
            assert _deviation(ra, rb) <= 0.05, name
            total += 1
    assert total == 14


def test_a_flip_ends_the_run_as_an_error_on_both():
    """A rate loop with about 17 times PX4's default D gain (0.05 against 0.003) rocks the vehicle over within 1.5 s
    of the take-off: both loops end the run as an error at the same time, with the same words."""
    test = load_test(EXPERIMENTS / "rq1-seed1.yaml")
    config = SimConfig(params={"MC_ROLLRATE_D": 0.05, "MC_PITCHRATE_D": 0.05}, timeout_s=30.0)
    ((a,), (b,)) = _both(test, 1, config)
    assert a.status == b.status == RunStatus.ERROR
    assert a.message == b.message and a.message.startswith("vehicle flipped or state invalid")
    assert a.duration == pytest.approx(b.duration, abs=0.02) and a.duration < 10.0
