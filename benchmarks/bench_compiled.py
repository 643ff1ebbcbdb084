"""The compiled flight loop's parts against PyBullet (docs/compiled-loop.md).

    python benchmarks/bench_compiled.py

Prints: the depth sensor's ray batch (the SITL Iris camera, 30 x 23 rays) by the closed-form kernel and by PyBullet's
rayTestBatch; one vehicle contact query; one control step of the rigid body by the kernel and by PyBullet (state
read, force, step); the navigator and flight task (every ``Navigator.update`` call of the flight below replayed
through the class, through the kernel called from Python and through the kernel in a compiled loop); the
PX4-Avoidance look-ahead tree (every build of the flight below replayed through the dense reference and through
``build_tree``, and the whole flight with each); one px4-v1.12-sitl-iris flight of mission1 + rilast
random_run3_194 with each physics, and the bare PyBullet loop over the same simulated time. Best of several
repetitions after a warm-up, except where two versions alternate (medians).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import math

import numpy as np
from bench_sim import ROOT, _best, plain_pybullet
from numba import njit

from surrealist_gym.sim.navigation import navigator_kernels as nk, navigator_state as ns


def _per_call(fn, n: int, repeat: int = 5) -> float:
    return _best(lambda: [fn() for _ in range(n)], repeat) / n


def _navigator_calls(test, config) -> tuple[tuple, list[tuple]]:
    """One flight's Navigator: its constructor's arguments and the arguments of every ``update`` call."""
    from surrealist_gym.sim import simulate
    from surrealist_gym.sim.navigation.navigator import Navigator

    made, calls = [], []
    init, update = Navigator.__init__, Navigator.update

    def recording_init(self, *args):
        init(self, *args)
        made.append(args)

    def recording_update(self, *args):
        calls.append(args)
        return update(self, *args)

    Navigator.__init__, Navigator.update = recording_init, recording_update
    try:
        simulate(test, runs=1, config=config)
    finally:
        Navigator.__init__, Navigator.update = init, update
    return made[0], calls


@njit(cache=True)
def _replay_navigator(state, mission, params, table):  # pragma: no cover - compiled
    """``nav_update`` over a table of recorded calls (t, pos, vel, yaw, dt, ground, plan kind, plan vector, plan
    yaw), as the compiled outer loop will call it."""
    total = 0.0
    for k in range(table.shape[0]):
        r = table[k]
        out = nk.nav_update(state, mission, params, r[0], (r[1], r[2], r[3]), (r[4], r[5], r[6]), r[7], r[8],
                            r[9] > 0.5, int(r[10]), (r[11], r[12], r[13]), r[14])
        total += out[3]
    return total


def navigator_per_call(test, config) -> None:
    """Print the navigator + flight task's cost per update: the class, the kernel from Python, the kernel in a
    compiled loop, on every update call of one flight."""
    from surrealist_gym.sim.navigation.navigator import Navigator

    made, calls = _navigator_calls(test, config)
    mission, params = ns.mission_array(made[0]), ns.param_vector(made[1], *made[2:])
    inputs = [(*args[:6], *ns.plan_inputs(args[6])) for args in calls]
    table = np.array([(t, *pos, *vel, yaw, dt, float(ground), kind, *vector, plan_yaw)
                      for t, pos, vel, yaw, dt, ground, kind, vector, plan_yaw in inputs], dtype=np.float64)

    def run_class():
        nav = Navigator(*made)
        for args in calls:
            nav.update(*args)

    def run_kernel():
        state = ns.initial_state(params)
        for t, pos, vel, yaw, dt, ground, kind, vector, plan_yaw in inputs:
            nk.nav_update(state, mission, params, t, pos, vel, yaw, dt, ground, kind, vector, plan_yaw)

    def run_compiled():
        _replay_navigator(ns.initial_state(params), mission, params, table)

    run_kernel(), run_compiled()  # compile
    n = len(calls)
    ref, kernel, compiled = (_best(fn, 5) / n for fn in (run_class, run_kernel, run_compiled))
    print(f"navigator + flight task, the flight's {n} updates: class {ref * 1e6:.1f} us per call, kernel "
          f"{kernel * 1e6:.2f} us called from Python ({ref / kernel:.0f}x), {compiled * 1e6:.3f} us in a compiled "
          f"loop ({ref / compiled:.0f}x)")


def _tree_calls(test, config) -> list[tuple]:
    """The arguments of every look-ahead tree build of one flight (``build_tree`` as ``Px4LocalPlanner.update``
    calls it), without the output buffer."""
    from surrealist_gym.sim import runner, simulate
    from surrealist_gym.sim.avoidance.px4 import local_planner as px4_avoidance

    calls, build, fly = [], px4_avoidance.build_tree, runner._fly_compiled

    def recording(cloud, *args):
        calls.append((cloud.copy(), *args[:-1]))
        return build(cloud, *args)

    # the Python outer loop (the compiled loop's bit-identical reference) runs the planner class, which calls
    # px4_avoidance.build_tree; the compiled loop calls the kernel from compiled code
    px4_avoidance.build_tree, runner._fly_compiled = recording, runner._fly_compiled_outer
    try:
        simulate(test, runs=1, config=config)
    finally:
        px4_avoidance.build_tree, runner._fly_compiled = build, fly
    return calls


def tree_per_build(test, config, repeat: int = 9) -> None:
    """Print the look-ahead tree's cost per build on every build of one flight, the dense reference
    (``build_tree_reference``) against ``build_tree`` (checked equal first), and the whole flight with each (on
    the Python outer loop, where the planner class calls the tree); the two alternate, medians."""
    import time

    from surrealist_gym.sim import runner, simulate
    from surrealist_gym.sim.avoidance.px4 import local_planner as px4_avoidance
    from surrealist_gym.sim.avoidance.px4.settings import MAX_NODES
    from surrealist_gym.sim.avoidance.px4.tree import build_tree, tree_work
    from surrealist_gym.sim.reference.px4_tree import build_tree_reference

    calls = _tree_calls(test, config)
    path, other = np.empty((MAX_NODES, 3)), np.empty((MAX_NODES, 3))
    work = tree_work(calls[0][5])
    for args in calls:
        k = build_tree_reference(*args, path)
        assert build_tree(*args, other, work) == k and np.array_equal(path[:k], other[:k])

    def replay(build, *extra):
        t0 = time.perf_counter()
        for args in calls:
            build(*args, path, *extra)
        return (time.perf_counter() - t0) / len(calls)

    ref, new = [], []
    for _ in range(repeat):
        ref.append(replay(build_tree_reference))
        new.append(replay(build_tree, work))
    ref, new = float(np.median(ref)), float(np.median(new))
    print(f"look-ahead tree, the flight's {len(calls)} builds (same paths): dense reference {ref * 1e6:.0f} us, "
          f"build_tree {new * 1e6:.0f} us per build ({ref / new:.2f}x)")

    def flight(build):  # on the Python outer loop, whose planner class calls px4_avoidance.build_tree
        fly = runner._fly_compiled
        px4_avoidance.build_tree, runner._fly_compiled = build, runner._fly_compiled_outer
        try:
            t0 = time.perf_counter()
            (run,) = simulate(test, runs=1, config=config)
            return time.perf_counter() - t0, run
        finally:
            px4_avoidance.build_tree, runner._fly_compiled = build_tree, fly

    flights = {build: [] for build in (build_tree_reference, build_tree)}
    for _ in range(max(repeat // 2, 3)):
        for build, times in flights.items():
            times.append(flight(build))
    (before, a), (after, b) = ((float(np.median([t for t, _ in v])), v[0][1]) for v in flights.values())
    same = np.array_equal(a.true_xyz, b.true_xyz)
    print(f"flight on the Python outer loop with the dense reference tree {before * 1e3:.0f} ms, with build_tree "
          f"{after * 1e3:.0f} ms "
          f"({before / after:.2f}x; {a.duration:.1f} s simulated, same trajectory: {same})")


def main() -> None:
    import surrealist_gym as sg
    from surrealist_gym.sim import simulate
    from surrealist_gym.sim.profiles import load_profile
    from surrealist_gym.sim.sensing.sensor import DepthSensor
    from surrealist_gym.sim.vehicle import geometry_kernels as gk, rigid_body as rb
    from surrealist_gym.sim.vehicle.airframe import IRIS
    from surrealist_gym.sim.vehicle.pybullet_quiet import pb
    from surrealist_gym.sim.vehicle.world import World

    competition = ROOT.parent / "shared" / "data" / "competition"
    with open(competition / "rilast-mission1" / "tests.csv", newline="") as f:
        row = next(r for r in csv.DictReader(f) if r["test_id"] == "random_run3_194")
    obstacles = [sg.Obstacle(**o) for o in json.loads(row["obstacles"])]
    test = sg.load_test(competition / "case_studies" / "mission1.yaml").with_obstacles(obstacles)
    profile = load_profile("px4-v1.12-sitl-iris")

    sensor, scene = DepthSensor(obstacles, profile.sensor_config()), gk.scene_array(obstacles)
    p, yaw, r = np.array([2.0, 24.0, 10.0]), math.radians(80.0), sensor._rays  # facing both boxes
    c, s = math.cos(yaw), math.sin(yaw)
    d = np.stack([r[:, 0] * c - r[:, 1] * s, r[:, 0] * s + r[:, 1] * c, r[:, 2]], axis=1) * 18.0
    a = np.tile(p, (len(d), 1))
    t, what = np.empty(len(d)), np.empty(len(d), dtype=np.int64)
    gk.cast_rays(a, d, 1.0, scene, True, t, what)
    kernel = _per_call(lambda: gk.cast_rays(a, d, 1.0, scene, True, t, what), 200)
    flip = np.array([1.0, 1.0, -1.0])
    with World(obstacles, IRIS, 1, 200.0, 100.0) as world:
        froms, tos = (a * flip).tolist(), ((a + d) * flip).tolist()
        bullet = _per_call(lambda: pb.rayTestBatch(froms, tos, physicsClientId=world.cid), 20)
        body, cid = world.vehicles[0], world.cid
        pb.resetBasePositionAndOrientation(body, [0, 0, -10], [0, 0, 0, 1], physicsClientId=cid)

        def pb_step():
            pos, _ = pb.getBasePositionAndOrientation(body, physicsClientId=cid)
            pb.getBaseVelocity(body, physicsClientId=cid)
            pb.applyExternalForce(body, -1, (0.0, 0.0, -14.7), pos, pb.WORLD_FRAME, physicsClientId=cid)
            pb.stepSimulation(physicsClientId=cid)
            pb.getContactPoints(physicsClientId=cid)

        pb_one = _per_call(pb_step, 2000)
    print(f"ray batch, {len(d)} rays ({int((what >= 0).sum())} hit a box): kernel {kernel * 1e6:.1f} us, PyBullet "
          f"rayTestBatch {bullet * 1e6:.0f} us ({bullet / kernel:.0f}x)")
    half = np.array([x / 2 for x in IRIS.size])
    axes, centre, thr = gk.vehicle_axes_ned(0.0, 0.0, 0.3, math.sqrt(1 - 0.09)), np.array([-7.0, 11.0, 10.0]), \
        gk.contact_threshold(half)
    contact = _per_call(lambda: gk.vehicle_contact(centre, axes, half, thr, scene), 5000)
    state, body_p = rb.initial_state((0.0, 0.0, -10.0)), rb.body_params(IRIS)
    kstep = _per_call(lambda: rb.step(state, (0.0, 0.0, -14.7), (0.0, 0.0, 0.0), 0.01, 2, body_p, half), 5000)
    from surrealist_gym.sim.config import PX4_DEFAULTS
    from surrealist_gym.sim.vehicle.compiled_physics import advance
    from surrealist_gym.sim.vehicle.control import kernel_params

    kp, ks = kernel_params(dict(PX4_DEFAULTS), IRIS, 0.01, (IRIS.drag_xy, IRIS.drag_z, IRIS.drag_quad)), np.zeros(10)
    state = rb.initial_state((0.0, 0.0, -10.0))
    hover = (1.0, 0.0, 0.0, 0.0), IRIS.hover_command, (0.0, 0.0, 0.0)
    n = 1000
    loop = _per_call(lambda: advance(state, *hover, 0.01, True, True, kp, ks, n, 2, body_p, half, scene, thr), 5) / n
    print(f"vehicle contact query: {contact * 1e6:.2f} us; one control step (2 sub-steps): rigid body alone "
          f"{kstep * 1e6:.2f} us called from Python, inner loop + rigid body + contacts {loop * 1e6:.2f} us in the "
          f"compiled loop; PyBullet read + force + step + contacts {pb_one * 1e6:.1f} us")
    navigator_per_call(test, profile.sim_config())
    tree_per_build(test, profile.sim_config())
    for physics in ("pybullet", "compiled"):
        cfg = dataclasses.replace(profile.sim_config(), physics=physics)
        (run,) = simulate(test, runs=1, config=cfg)
        one = _best(lambda: simulate(test, runs=1, config=cfg), 5)
        print(f"flight, physics={physics} ({run.status.value}): {run.duration:.1f} s simulated in {one * 1e3:.0f} ms "
              f"-> {run.duration / one:.0f}x real time")
    bare = _best(lambda: plain_pybullet(run.duration, 200.0), 5)
    print(f"bare PyBullet loop, {run.duration:.1f} s at 200 Hz: {bare * 1e3:.0f} ms -> {run.duration / bare:.0f}x")


if __name__ == "__main__":
    main()
