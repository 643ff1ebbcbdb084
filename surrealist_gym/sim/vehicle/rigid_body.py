"""The vehicle's rigid body without PyBullet: the integration PyBullet (Bullet's ``btMultiBody``) applies to a
single free body, as numba kernels for the compiled flight loop.

Frame and conventions are PyBullet's in :mod:`surrealist_gym.sim.vehicle.world`: world NED (gravity +z), the attitude
quaternion in PyBullet's (x, y, z, w) order rotates body (FRD) to world, velocities and angular velocities are in
the world frame, the run loop's forces and torques too (``applyExternalForce`` in ``WORLD_FRAME`` at the centre of
mass). One :func:`step` is one ``stepSimulation``: ``n_sub`` sub-steps of ``dt / n_sub`` with the forces held, as
PyBullet's ``numSubSteps`` does.

What Bullet does per sub-step for a base without links (``btMultiBody::computeAccelerationsArticulatedBodyAlgorithm
MultiDof``, ``stepPositionsMultiDof``), and so this module:

1. accelerations from the held force and torque plus gravity, the gyroscopic term ``w x I w`` and the damping
   ``m v (k + k |v|)`` / ``I w (k + k |w|)`` (body frame; ``linearDamping`` / ``angularDamping``, which PyBullet
   defaults to 0.04 and the world sets to 0), all at the start-of-step state;
2. semi-implicit Euler: the velocities first, then the position with the new velocity and the attitude by the
   exponential map of the new angular velocity (Bullet's Taylor branch below 0.001 rad/s, its rotation cap of
   pi/4 per sub-step), renormalised.

State array (float64, 13): [0:3] position, [3:7] quaternion (x, y, z, w), [7:10] velocity, [10:13] angular
velocity. Body array (:func:`body_params`, float64): mass, inertia xx/yy/zz, linear and angular damping, gravity.

The ground: :func:`ground_contact` resolves the box against the plane z = 0 at the velocity level
(:func:`step` calls it when given the box's half extents): no penetration velocity (restitution 0), the
penetration pushed out at PyBullet's observed rate, Coulomb friction on the contact point's sliding velocity.
This is an approximation of Bullet's contact solver, which the free flight does not need.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .airframe import GRAVITY, VehicleParams

__all__ = ["STATE_SIZE", "body_params", "initial_state", "step", "ground_contact"]

STATE_SIZE = 13
_ANGULAR_MOTION_THRESHOLD = 0.25 * math.pi  # Bullet's cap on a sub-step's rotation [rad]
# Ground contact, fitted to PyBullet's box on its plane (200 Hz sub-steps, 10 solver iterations): a 1 m/s touchdown
# penetrates ~4 mm and the penetration shrinks by ~8 % per sub-step; friction coefficient of world.py
GROUND_ERP = 0.08
GROUND_FRICTION = 0.8


def body_params(vehicle: VehicleParams, linear_damping: float = 0.0, angular_damping: float = 0.0,
                gravity: float = GRAVITY) -> np.ndarray:
    """The float64 body array of :func:`step`: mass, principal inertia, damping (PyBullet's ``linearDamping`` and
    ``angularDamping``; the world sets both to 0) and gravity along +z (NED) [m/s^2]."""
    return np.array([vehicle.mass, vehicle.ixx, vehicle.iyy, vehicle.izz, linear_damping, angular_damping, gravity],
                    dtype=np.float64)


def initial_state(position=(0.0, 0.0, 0.0), yaw: float = 0.0) -> np.ndarray:
    """A state at rest at ``position`` (NED) [m] with heading ``yaw`` [rad]."""
    s = np.zeros(STATE_SIZE)
    s[0:3] = position
    s[5], s[6] = math.sin(yaw / 2), math.cos(yaw / 2)
    return s


@njit(cache=True)
def _sub_step(s, fx, fy, fz, tx, ty, tz, h, body):  # pragma: no cover - compiled
    m, ixx, iyy, izz, kl, ka, g = body[0], body[1], body[2], body[3], body[4], body[5], body[6]
    qx, qy, qz, qw = s[3], s[4], s[5], s[6]
    # body-to-world rotation R; body-frame quantities are R^T times world ones
    r00, r01, r02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)
    r10, r11, r12 = 2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)
    r20, r21, r22 = 2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)
    vx, vy, vz = s[7], s[8], s[9]
    wx, wy, wz = s[10], s[11], s[12]
    # linear: force and gravity, damping on the speed
    dl = kl + kl * math.sqrt(vx * vx + vy * vy + vz * vz)
    ax = fx / m - dl * vx
    ay = fy / m - dl * vy
    az = fz / m + g - dl * vz
    # angular, in the body frame: torque - damping - w x I w
    bx = r00 * wx + r10 * wy + r20 * wz
    by = r01 * wx + r11 * wy + r21 * wz
    bz = r02 * wx + r12 * wy + r22 * wz
    da = ka + ka * math.sqrt(bx * bx + by * by + bz * bz)
    lx, ly, lz = ixx * bx, iyy * by, izz * bz
    mx = r00 * tx + r10 * ty + r20 * tz - da * lx - (by * lz - bz * ly)
    my = r01 * tx + r11 * ty + r21 * tz - da * ly - (bz * lx - bx * lz)
    mz = r02 * tx + r12 * ty + r22 * tz - da * lz - (bx * ly - by * lx)
    ex, ey, ez = mx / ixx, my / iyy, mz / izz
    # velocities first (semi-implicit Euler)
    vx += h * ax
    vy += h * ay
    vz += h * az
    wx += h * (r00 * ex + r01 * ey + r02 * ez)
    wy += h * (r10 * ex + r11 * ey + r12 * ez)
    wz += h * (r20 * ex + r21 * ey + r22 * ez)
    s[7], s[8], s[9], s[10], s[11], s[12] = vx, vy, vz, wx, wy, wz


@njit(cache=True)
def _integrate_pose(s, h):  # pragma: no cover - compiled
    s[0] += h * s[7]
    s[1] += h * s[8]
    s[2] += h * s[9]
    wx, wy, wz = s[10], s[11], s[12]
    angle = math.sqrt(wx * wx + wy * wy + wz * wz)
    if angle * h > _ANGULAR_MOTION_THRESHOLD:
        angle = 0.5 * (0.5 * math.pi) / h
    if angle < 0.001:
        k = 0.5 * h - h * h * h * 0.020833333333 * angle * angle
    else:
        k = math.sin(0.5 * angle * h) / angle
    ax, ay, az, aw = wx * k, wy * k, wz * k, math.cos(0.5 * angle * h)
    qx, qy, qz, qw = s[3], s[4], s[5], s[6]
    # q <- exp(w h / 2) (x) q, world-frame angular velocity multiplies from the left
    nx = aw * qx + ax * qw + ay * qz - az * qy
    ny = aw * qy - ax * qz + ay * qw + az * qx
    nz = aw * qz + ax * qy - ay * qx + az * qw
    nw = aw * qw - ax * qx - ay * qy - az * qz
    n = math.sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
    s[3], s[4], s[5], s[6] = nx / n, ny / n, nz / n, nw / n


@njit(cache=True)
def ground_contact(s, h, body, half):  # pragma: no cover - compiled
    """Resolve the box (``half`` extents, body axes) against the ground plane z = 0 (NED: solid at z > 0) for a
    sub-step of ``h`` [s], on the velocities in ``s``: each penetrating or touching corner moving into the ground
    gets an impulse that stops it and pushes the penetration out by GROUND_ERP per sub-step, and friction up to
    GROUND_FRICTION times that impulse. Returns True when a corner touches (the position is not changed)."""
    m, ixx, iyy, izz = body[0], body[1], body[2], body[3]
    qx, qy, qz, qw = s[3], s[4], s[5], s[6]
    r = np.empty((3, 3))
    r[0, 0], r[0, 1], r[0, 2] = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)
    r[1, 0], r[1, 1], r[1, 2] = 2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)
    r[2, 0], r[2, 1], r[2, 2] = 2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)
    touched = False
    for it in range(4):  # a few sweeps over the corners (a small sequential-impulse solver)
        for c in range(8):
            px = half[0] if c & 1 else -half[0]
            py = half[1] if c & 2 else -half[1]
            pz = half[2] if c & 4 else -half[2]
            ox = r[0, 0] * px + r[0, 1] * py + r[0, 2] * pz  # corner offset, world frame
            oy = r[1, 0] * px + r[1, 1] * py + r[1, 2] * pz
            oz = r[2, 0] * px + r[2, 1] * py + r[2, 2] * pz
            depth = s[2] + oz  # > 0: below the ground (NED)
            if depth < 0.0:
                continue
            touched = True
            # contact point velocity v + w x o
            wx, wy, wz = s[10], s[11], s[12]
            cvx = s[7] + wy * oz - wz * oy
            cvy = s[8] + wz * ox - wx * oz
            cvz = s[9] + wx * oy - wy * ox
            target = -GROUND_ERP * depth / h  # push out (up = -z)
            if cvz <= target:
                continue
            # effective mass along z: 1/m + (o x n) . I^-1 (o x n), n = z, in the body frame
            kz = _inv_mass(r, ixx, iyy, izz, m, ox, oy, oz, 0.0, 0.0, 1.0)
            jn = (cvz - target) / kz  # impulse pushing up (applied along -z)
            _apply(s, r, ixx, iyy, izz, m, ox, oy, oz, 0.0, 0.0, -jn)
            # friction on the sliding velocity, capped by the normal impulse
            cvx = s[7] + s[11] * oz - s[12] * oy
            cvy = s[8] + s[12] * ox - s[10] * oz
            sl = math.sqrt(cvx * cvx + cvy * cvy)
            if sl > 1e-12:
                ux, uy = cvx / sl, cvy / sl
                kt = _inv_mass(r, ixx, iyy, izz, m, ox, oy, oz, ux, uy, 0.0)
                jt = min(sl / kt, GROUND_FRICTION * jn)
                _apply(s, r, ixx, iyy, izz, m, ox, oy, oz, -jt * ux, -jt * uy, 0.0)
    return touched


@njit(cache=True)
def _inv_mass(r, ixx, iyy, izz, m, ox, oy, oz, nx, ny, nz):  # pragma: no cover - compiled
    cx, cy, cz = oy * nz - oz * ny, oz * nx - ox * nz, ox * ny - oy * nx  # o x n, world
    bx = r[0, 0] * cx + r[1, 0] * cy + r[2, 0] * cz
    by = r[0, 1] * cx + r[1, 1] * cy + r[2, 1] * cz
    bz = r[0, 2] * cx + r[1, 2] * cy + r[2, 2] * cz
    return 1.0 / m + bx * bx / ixx + by * by / iyy + bz * bz / izz


@njit(cache=True)
def _apply(s, r, ixx, iyy, izz, m, ox, oy, oz, jx, jy, jz):  # pragma: no cover - compiled
    """Apply the world impulse (jx, jy, jz) at the world offset o from the centre of mass."""
    s[7] += jx / m
    s[8] += jy / m
    s[9] += jz / m
    cx, cy, cz = oy * jz - oz * jy, oz * jx - ox * jz, ox * jy - oy * jx
    bx = (r[0, 0] * cx + r[1, 0] * cy + r[2, 0] * cz) / ixx
    by = (r[0, 1] * cx + r[1, 1] * cy + r[2, 1] * cz) / iyy
    bz = (r[0, 2] * cx + r[1, 2] * cy + r[2, 2] * cz) / izz
    s[10] += r[0, 0] * bx + r[0, 1] * by + r[0, 2] * bz
    s[11] += r[1, 0] * bx + r[1, 1] * by + r[1, 2] * bz
    s[12] += r[2, 0] * bx + r[2, 1] * by + r[2, 2] * bz


@njit(cache=True)
def step(s, force, torque, dt, n_sub, body, half):  # pragma: no cover - compiled
    """One ``stepSimulation`` of the state ``s`` (in place): ``n_sub`` sub-steps of ``dt / n_sub`` [s] with the
    world-frame ``force`` [N] and ``torque`` [N m] (3-tuples) held. ``half``: the box's half extents for the ground
    contact, or an empty array for free flight. Returns True when the box touched the ground in a sub-step."""
    h = dt / n_sub
    fx, fy, fz = force
    tx, ty, tz = torque
    touched = False
    for _ in range(n_sub):
        _sub_step(s, fx, fy, fz, tx, ty, tz, h, body)
        if half.shape[0] == 3 and ground_contact(s, h, body, half):
            touched = True
        _integrate_pose(s, h)
    return touched
