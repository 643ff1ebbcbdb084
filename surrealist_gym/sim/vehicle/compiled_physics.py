"""The world without PyBullet (``SimConfig(physics="compiled")``): the vehicles' rigid bodies
(:mod:`~surrealist_gym.sim.vehicle.rigid_body`) and their contacts (:mod:`~surrealist_gym.sim.vehicle.geometry_kernels`)
stepped by numba kernels, one call per vehicle and outer-loop period.

:class:`CompiledWorld` stands where :class:`~surrealist_gym.sim.vehicle.world.World` stands in the run loop (same frame:
NED; same vehicle at rest at the origin; same obstacle collision scale), and :func:`fly` is the run loop's
counterpart of ``runner._loop``: the estimator, navigator, planner and position control stay the runner's Python
(``outer``), while :func:`advance` runs the inner loop (attitude and rate control, mixer, motors, drag), the
physics sub-steps and the contact test for a whole outer period. The order of work per control step is the
PyBullet loop's, so both paths fly the same runs up to the physics' differences (tests/.../test_compiled_physics).

This was the first stage of the compiled flight loop (docs/compiled-loop.md): ``SimConfig(physics="compiled")`` now
flies :mod:`~surrealist_gym.sim.compiled.loop`, which calls :func:`advance` from its kernel; :func:`fly` with the
runner's ``_outer`` stays as its reference (``runner._fly_compiled_outer``).
"""
from __future__ import annotations

import math
from typing import Callable, Sequence

import numpy as np
from numba import njit

from ...outcomes import RunStatus
from ...testcase import Obstacle
from .. import run_end
from . import rigid_body as rb
from .airframe import VehicleParams
from .control import inner_step
from .geometry_kernels import GROUND, MISS, contact_threshold, scene_array, vehicle_axes_ned, vehicle_contact

__all__ = ["CompiledWorld", "advance", "fly"]


class CompiledWorld:
    """The vehicles' states and the obstacles' collision scene, in the role of :class:`World` (see there for the
    arguments). ``vehicles`` are the rows of ``states`` (n, 13), :mod:`~surrealist_gym.sim.vehicle.rigid_body`'s
    layout."""

    def __init__(self, obstacles: Sequence[Obstacle], vehicle: VehicleParams, n_vehicles: int, physics_hz: float,
                 control_hz: float | None = None, collision_scale: float = 1.0):
        control_hz = control_hz or physics_hz
        self.n_sub = int(round(physics_hz / control_hz))
        self.half = np.array([s / 2 for s in vehicle.size], dtype=np.float64)
        self.threshold = contact_threshold(self.half)
        self.scene = scene_array(obstacles, collision_scale)
        self.body = rb.body_params(vehicle)
        self.rest_z = -self.half[2]  # NED z of the vehicle's centre when it rests on the ground
        self.states = np.stack([rb.initial_state((0.0, 0.0, self.rest_z)) for _ in range(n_vehicles)]) \
            if n_vehicles else np.zeros((0, rb.STATE_SIZE))
        self.vehicles = list(range(n_vehicles))

    def set_yaw(self, body: int, yaw: float) -> None:
        """Turn a resting vehicle to a heading [rad] (before the run starts)."""
        self.states[body, 3:7] = (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))

    def pose(self, body: int):
        """(position, orientation, velocity, angular velocity) as PyBullet's getters return them (tuples, NED)."""
        s = self.states[body]
        return (s[0], s[1], s[2]), (s[3], s[4], s[5], s[6]), (s[7], s[8], s[9]), (s[10], s[11], s[12])

    def close(self) -> None:
        """Nothing to release (the interface of World)."""

    def __enter__(self) -> "CompiledWorld":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


@njit(cache=True)
def advance(s, q_sp, thrust, wind, dt, armed, integrate, kp, ks, n_steps, n_sub, body, half, scene,
            threshold, held, rest):  # pragma: no cover - compiled
    """Up to ``n_steps`` control steps of one vehicle (state ``s``, in place): :func:`inner_step` with the held
    setpoints (``kp``/``ks`` its parameters and state), :func:`rigid_body.step` with ``n_sub`` sub-steps, then the
    contacts, as the PyBullet loop reads them after each ``stepSimulation``. While ``held`` (resting on the ground
    before the thrust first exceeds the weight) the vehicle is put back at its pose ``rest`` (the state's first 7
    values), still, after each step, as the PyBullet loop does.

    Returns:
        (what, steps, held): ``what`` the obstacle's row touched at step ``steps`` (the run ends there), else GROUND
        when the ground was touched after any step, else MISS; ``steps`` the control steps taken; ``held`` whether
        the vehicle is still held.
    """
    ground = False
    weight = body[0] * body[6]
    for k in range(n_steps):
        f = inner_step((s[3], s[4], s[5], s[6]), (s[7], s[8], s[9]), (s[10], s[11], s[12]), q_sp, thrust, wind, dt,
                       armed, integrate, kp, ks)
        if held and -f[2] > weight:
            held = False
        rb.step(s, (f[0], f[1], f[2]), (f[3], f[4], f[5]), dt, n_sub, body, half)
        axes = vehicle_axes_ned(s[3], s[4], s[5], s[6])
        what = vehicle_contact(np.array((s[0], s[1], -s[2])), axes, half, threshold, scene)
        if what >= 0:
            return what, k + 1, held
        if what == GROUND:
            ground = True
        if held:
            s[:7] = rest
            s[7:] = 0.0
    return (GROUND if ground else MISS), n_steps, held


def fly(world: CompiledWorld, runs: list, cfg, timeout: float, outer: Callable, record: Callable) -> None:
    """The run loop on a :class:`CompiledWorld`: per outer period, each active run's ``outer`` (the runner's
    ``_outer(r, k, t, pos, lin, orn)``, False when the run ended) and then :func:`advance` over the period;
    collisions, the time limit and the end of a run as in the PyBullet loop; ``record`` logs a run's last state."""
    dt = 1.0 / cfg.control_hz
    outer_div = int(round(cfg.control_hz / cfg.outer_hz))
    max_steps = int(math.ceil(timeout * cfg.control_hz))
    states, scene, half, body, thr, n_sub = world.states, world.scene, world.half, world.body, world.threshold, \
        world.n_sub
    rest = {r.body: states[r.body, :7].copy() for r in runs}  # each vehicle's pose on the ground
    active = list(runs)
    step = 0
    while active:
        k = step // outer_div
        t = step * dt
        n = min(outer_div, max_steps - step)
        ended = []
        for r in active:
            s = states[r.body]
            if not outer(r, k, t, (s[0], s[1], s[2]), (s[7], s[8], s[9]), (s[3], s[4], s[5], s[6])):
                # as in PyBullet's loop, the ended vehicle still takes this step (with no force) before its record
                rb.step(s, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), dt, n_sub, body, half)
                ended.append((r, r.end_t))
                continue
            what, taken, r.held = advance(s, r.q_sp, r.thrust, r.wind, dt, r.armed, r.integ, r.kp, r.ks, n, n_sub,
                                          body, half, scene, thr, r.held, rest[r.body])
            if what >= 0:
                r.status, r.end_t = RunStatus.COLLISION, (step + taken) * dt
                r.message = run_end.collided(what, (step + taken) * dt)
                ended.append((r, r.end_t))
            elif what == GROUND:
                r.ground = True
        step += n
        if step >= max_steps:
            for r in active:
                if r.status is None:
                    r.status, r.end_t = RunStatus.TIMEOUT, step * dt
                    r.message = run_end.timed_out(timeout, r.nav.phase.value)
                    ended.append((r, r.end_t))
        for r, end_t in ended:
            if r in active:
                r.active = False
                record(r, end_t, *world.pose(r.body), k)
                active.remove(r)
