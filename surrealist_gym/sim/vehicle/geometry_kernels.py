"""Closed-form geometry of a test's world for the compiled flight loop: rays and vehicle contacts against the
obstacles (boxes turned about the vertical, vertical cylinders) and the ground plane, with no physics engine.

Frame: x north, y east, z up [m] (the sensor's and the obstacles' frame); the ground is the plane z = 0, solid
below. A *scene* is a float64 array with one row per obstacle (:func:`scene_array`); the columns are named by the
``COL_*`` constants. Boxes keep their centre height and half height, cylinders their base and top, so that the
ray kernel computes exactly what :mod:`surrealist_gym.sim.sensing.sensor` computes.

What PyBullet (the reference, :mod:`surrealist_gym.sim.vehicle.world`) does, and what these kernels match:

- **Rays** (``rayTestBatch``): the first hit along the segment. Boxes are exact. PyBullet casts rays at convex
  shapes by a sub-simplex convex cast, so its cylinder hits lie up to 1 mm (its collision margin) off the exact
  surface; the kernel is exact. A ray that starts inside an obstacle: PyBullet ignores that obstacle, the kernel
  (like the depth sensor) reports :data:`INSIDE` at distance 0 (the camera sees nothing).
- **Contacts** (``getContactPoints`` after a step, what the run loop reads): PyBullet's box-box pairs (Bullet's
  ``btBoxBoxDetector``) touch only when the boxes overlap; box-cylinder and box-plane pairs (GJK) touch when
  their distance is below the contact breaking threshold, 0.02 x the vehicle box's half diagonal
  (:func:`contact_threshold`). :func:`vehicle_contact` follows those rules: the separating-axis test for boxes,
  the exact distance (GJK on the shapes' support maps) for cylinders, the lowest corner for the ground.

Example::

    >>> from surrealist_gym.testcase import Obstacle
    >>> scene = scene_array([Obstacle(2, 2, 4, 5.0, 0.0)])
    >>> t, hit = ray_cast(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 20.0, scene, False)
    >>> round(t, 9), hit
    (4.0, 0)
"""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from numba import njit

from ...testcase import Obstacle, Shape

__all__ = ["BOX", "CYLINDER", "MISS", "GROUND", "INSIDE", "scene_array", "ray_cast", "cast_rays", "ray_test_batch",
           "contact_threshold", "vehicle_axes_ned", "vehicle_contact", "vehicle_distance", "boxes_overlap",
           "ground_clearance"]

BOX, CYLINDER = 0, 1  # obstacle kinds (COL_KIND)
MISS, GROUND, INSIDE = -1, -2, -3  # ray results besides an obstacle's index
# scene columns: kind, footprint centre, base and top heights, box centre height and half height, the yaw's cosine
# and sine, half length along the obstacle's x axis (a cylinder's radius) and half width
COL_KIND, COL_X, COL_Y, COL_Z0, COL_Z1, COL_ZC, COL_HZ, COL_COS, COL_SIN, COL_HX, COL_HY = range(11)
N_COLS = 11
CONTACT_FACTOR = 0.02  # Bullet's gContactThresholdFactor: the breaking threshold per metre of a shape's half diagonal


def scene_array(obstacles: Sequence[Obstacle], scale: float = 1.0) -> np.ndarray:
    """The (n, 11) scene of a test's obstacles; ``scale`` shrinks the footprints about their centres (the collision
    shapes' ``SimConfig.obstacle_collision_scale``; the camera sees the full obstacles, scale 1)."""
    rows = []
    for o in obstacles:
        a = math.radians(o.r)
        kind = CYLINDER if o.shape == Shape.CYLINDER else BOX
        rows.append((kind, o.x, o.y, o.z, o.z + o.h, o.z + o.h / 2, o.h / 2, math.cos(a), math.sin(a),
                     scale * o.l / 2, scale * (o.l if kind == CYLINDER else o.w) / 2))
    return np.array(rows, dtype=np.float64).reshape(-1, N_COLS)


# --- rays --------------------------------------------------------------------------------------------------------
@njit(cache=True)
def ray_cast(px, py, pz, dx, dy, dz, tmax, scene, ground):  # pragma: no cover - compiled
    """The first obstacle (or ground) along the ray ``p + t d``, ``0 <= t <= tmax``, in units of ``|d|``.

    Args:
        px, py, pz: origin [m]. dx, dy, dz: direction (any length; t is measured in multiples of it).
        tmax: farthest t. scene: :func:`scene_array`. ground: whether the ground plane is a hit (it always
            occludes what lies behind it).

    Returns:
        (t, what): ``what`` is the obstacle's row, :data:`GROUND`, :data:`MISS` (t = tmax) or :data:`INSIDE`
        (the origin is inside an obstacle: t = 0, nothing seen).
    """
    best = tmax
    what = MISS
    if dz < -1e-12:  # the ground occludes (and is a hit when it counts)
        tg = -pz / dz
        if 0.0 <= tg < best:
            best = tg
            what = GROUND if ground else MISS
    for j in range(scene.shape[0]):
        if scene[j, COL_KIND] == BOX:
            ox, oy, oz = px - scene[j, COL_X], py - scene[j, COL_Y], pz - scene[j, COL_ZC]
            c, s = scene[j, COL_COS], scene[j, COL_SIN]
            lo0, lo1, lo2 = c * ox + s * oy, -s * ox + c * oy, oz
            ld0, ld1, ld2 = c * dx + s * dy, -s * dx + c * dy, dz
            tn, tf = -1e300, 1e300
            miss = False
            for ax in range(3):
                if ax == 0:
                    o, d, h = lo0, ld0, scene[j, COL_HX]
                elif ax == 1:
                    o, d, h = lo1, ld1, scene[j, COL_HY]
                else:
                    o, d, h = lo2, ld2, scene[j, COL_HZ]
                if abs(d) < 1e-12:
                    if abs(o) > h:
                        miss = True
                        break
                else:
                    t1, t2 = (-h - o) / d, (h - o) / d
                    if t1 > t2:
                        t1, t2 = t2, t1
                    if t1 > tn:
                        tn = t1
                    if t2 < tf:
                        tf = t2
                    if tn > tf:
                        miss = True
                        break
            if miss or tf < 0.0:
                continue
            if tn < 0.0:
                return 0.0, INSIDE
            if tn < best:
                best = tn
                what = j
        else:
            ox, oy = px - scene[j, COL_X], py - scene[j, COL_Y]
            r, z0, z1 = scene[j, COL_HX], scene[j, COL_Z0], scene[j, COL_Z1]
            cc = ox * ox + oy * oy - r * r
            if cc <= 0.0 and z0 <= pz <= z1:
                return 0.0, INSIDE
            t = 1e300
            aa = dx * dx + dy * dy
            if aa > 1e-18:  # the side
                bb = ox * dx + oy * dy
                disc = bb * bb - aa * cc
                if disc >= 0.0:
                    t1 = (-bb - math.sqrt(disc)) / aa
                    if t1 >= 0.0:
                        z = pz + t1 * dz
                        if z0 <= z <= z1:
                            t = t1
            if abs(dz) > 1e-12:  # the caps
                for zc in (z0, z1):
                    tc = (zc - pz) / dz
                    if 0.0 <= tc < t:
                        x, y = ox + tc * dx, oy + tc * dy
                        if x * x + y * y <= r * r:
                            t = tc
            if t < best:
                best = t
                what = j
    return best, what


@njit(cache=True)
def cast_rays(origins, dirs, tmax, scene, ground, t_out, what_out):  # pragma: no cover - compiled
    """:func:`ray_cast` for each row of ``origins`` / ``dirs`` (n, 3), into ``t_out`` (n,) and ``what_out`` (n,)."""
    for i in range(origins.shape[0]):
        t_out[i], what_out[i] = ray_cast(origins[i, 0], origins[i, 1], origins[i, 2], dirs[i, 0], dirs[i, 1],
                                         dirs[i, 2], tmax, scene, ground)


def ray_test_batch(froms, tos, scene: np.ndarray, ground: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """PyBullet's ``rayTestBatch`` in closed form: per segment ``from -> to`` the hit fraction in [0, 1] (1 on a
    miss) and what was hit (:func:`ray_cast`'s codes). Points in this module's frame (z up)."""
    a = np.ascontiguousarray(froms, dtype=np.float64).reshape(-1, 3)
    d = np.ascontiguousarray(tos, dtype=np.float64).reshape(-1, 3) - a
    t = np.empty(len(a))
    what = np.empty(len(a), dtype=np.int64)
    cast_rays(a, d, 1.0, scene, ground, t, what)
    return t, what


# --- the vehicle's box against obstacles and ground --------------------------------------------------------------
def contact_threshold(half_extents) -> float:
    """Bullet's contact breaking threshold of a box with these half extents [m] (its half diagonal x 0.02): pairs
    tested by GJK (box-cylinder, box-plane) touch below this distance."""
    return CONTACT_FACTOR * math.sqrt(sum(h * h for h in half_extents))


@njit(cache=True)
def vehicle_axes_ned(qx, qy, qz, qw):  # pragma: no cover - compiled
    """The vehicle's body axes in this module's frame (z up) from its NED attitude quaternion (PyBullet's x, y, z,
    w order): a (3, 3) array whose rows are the body x, y, z axes (the z components negated)."""
    a = np.empty((3, 3))
    a[0, 0], a[0, 1], a[0, 2] = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy + qw * qz), -2 * (qx * qz - qw * qy)
    a[1, 0], a[1, 1], a[1, 2] = 2 * (qx * qy - qw * qz), 1 - 2 * (qx * qx + qz * qz), -2 * (qy * qz + qw * qx)
    a[2, 0], a[2, 1], a[2, 2] = 2 * (qx * qz + qw * qy), 2 * (qy * qz - qw * qx), -(1 - 2 * (qx * qx + qy * qy))
    return a


@njit(cache=True)
def ground_clearance(c, axes, half):  # pragma: no cover - compiled
    """Height of the box's lowest corner above the ground [m] (centre ``c``, rows of ``axes``, ``half`` extents)."""
    return c[2] - (abs(axes[0, 2]) * half[0] + abs(axes[1, 2]) * half[1] + abs(axes[2, 2]) * half[2])


@njit(cache=True)
def boxes_overlap(c, axes, half, scene, j):  # pragma: no cover - compiled
    """Separating-axis test of the vehicle's box against box obstacle ``j``: True when the solids intersect."""
    # the obstacle's frame: axes (c, s, 0), (-s, c, 0), (0, 0, 1)
    cs, sn = scene[j, COL_COS], scene[j, COL_SIN]
    b = np.empty((3, 3))
    b[0, 0], b[0, 1], b[0, 2] = cs, sn, 0.0
    b[1, 0], b[1, 1], b[1, 2] = -sn, cs, 0.0
    b[2, 0], b[2, 1], b[2, 2] = 0.0, 0.0, 1.0
    hb = (scene[j, COL_HX], scene[j, COL_HY], scene[j, COL_HZ])
    t = (scene[j, COL_X] - c[0], scene[j, COL_Y] - c[1], scene[j, COL_ZC] - c[2])
    # rotation between the frames and the centre offset in the vehicle's frame
    r = np.empty((3, 3))
    ar = np.empty((3, 3))
    for i in range(3):
        for k in range(3):
            r[i, k] = axes[i, 0] * b[k, 0] + axes[i, 1] * b[k, 1] + axes[i, 2] * b[k, 2]
            ar[i, k] = abs(r[i, k]) + 1e-12
    ta = np.empty(3)
    for i in range(3):
        ta[i] = t[0] * axes[i, 0] + t[1] * axes[i, 1] + t[2] * axes[i, 2]
    for i in range(3):  # the vehicle's face normals
        if abs(ta[i]) > half[i] + hb[0] * ar[i, 0] + hb[1] * ar[i, 1] + hb[2] * ar[i, 2]:
            return False
    for k in range(3):  # the obstacle's face normals
        proj = ta[0] * r[0, k] + ta[1] * r[1, k] + ta[2] * r[2, k]
        if abs(proj) > half[0] * ar[0, k] + half[1] * ar[1, k] + half[2] * ar[2, k] + hb[k]:
            return False
    for i in range(3):  # edge-edge cross products
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for k in range(3):
            k1, k2 = (k + 1) % 3, (k + 2) % 3
            ra = half[i1] * ar[i2, k] + half[i2] * ar[i1, k]
            rb = hb[k1] * ar[i, k2] + hb[k2] * ar[i, k1]
            if abs(ta[i2] * r[i1, k] - ta[i1] * r[i2, k]) > ra + rb:
                return False
    return True


@njit(cache=True)
def _support_vehicle(c, axes, half, d0, d1, d2):  # pragma: no cover - compiled
    x, y, z = c[0], c[1], c[2]
    for i in range(3):
        s = half[i] if axes[i, 0] * d0 + axes[i, 1] * d1 + axes[i, 2] * d2 >= 0.0 else -half[i]
        x += s * axes[i, 0]
        y += s * axes[i, 1]
        z += s * axes[i, 2]
    return x, y, z


@njit(cache=True)
def _support_obstacle(scene, j, d0, d1, d2):  # pragma: no cover - compiled
    cx, cy = scene[j, COL_X], scene[j, COL_Y]
    z = scene[j, COL_Z1] if d2 >= 0.0 else scene[j, COL_Z0]
    if scene[j, COL_KIND] == BOX:
        cs, sn = scene[j, COL_COS], scene[j, COL_SIN]
        sx = scene[j, COL_HX] if cs * d0 + sn * d1 >= 0.0 else -scene[j, COL_HX]
        sy = scene[j, COL_HY] if -sn * d0 + cs * d1 >= 0.0 else -scene[j, COL_HY]
        return cx + cs * sx - sn * sy, cy + sn * sx + cs * sy, z
    rho = math.sqrt(d0 * d0 + d1 * d1)
    if rho < 1e-15:
        return cx, cy, z
    r = scene[j, COL_HX] / rho
    return cx + r * d0, cy + r * d1, z


@njit(cache=True)
def _copy_rows(dst, d0, src, s0, n):  # pragma: no cover - compiled
    """``dst[d0:d0 + n, :3] = src[s0:s0 + n, :3]``, element by element (a slice assignment would compile numba's
    shape-mismatch error path, seconds of the first simulation's compile)."""
    for i in range(n):
        for k in range(3):
            dst[d0 + i, k] = src[s0 + i, k]


@njit(cache=True)
def _closest_on_simplex(w, n):  # pragma: no cover - compiled
    """Closest point to the origin on the simplex of the first ``n`` rows of ``w``; keeps only the vertices that
    support it (reordered to the front of ``w``) and returns (x, y, z, new n). n == 4 with the origin inside
    returns n = 4 and the origin."""
    if n == 1:
        return w[0, 0], w[0, 1], w[0, 2], 1
    if n == 2:
        ax, ay, az = w[0, 0], w[0, 1], w[0, 2]
        ex, ey, ez = w[1, 0] - ax, w[1, 1] - ay, w[1, 2] - az
        ee = ex * ex + ey * ey + ez * ez
        t = -(ax * ex + ay * ey + az * ez) / ee if ee > 0.0 else 0.0
        if t <= 0.0:
            return ax, ay, az, 1
        if t >= 1.0:
            _copy_rows(w, 0, w, 1, 1)
            return w[0, 0], w[0, 1], w[0, 2], 1
        return ax + t * ex, ay + t * ey, az + t * ez, 2
    if n == 3:
        return _closest_on_triangle(w, 0, 1, 2)
    # tetrahedron: the best face whose plane separates the origin from the opposite vertex
    best = 1e300
    bx = by = bz = 0.0
    bn = 0
    keep = np.empty((4, 3))
    tmp = np.empty((4, 3))
    outside_any = False
    for f in range(4):
        i0, i1, i2, io = (f + 1) % 4, (f + 2) % 4, (f + 3) % 4, f
        ux, uy, uz = w[i1, 0] - w[i0, 0], w[i1, 1] - w[i0, 1], w[i1, 2] - w[i0, 2]
        vx, vy, vz = w[i2, 0] - w[i0, 0], w[i2, 1] - w[i0, 1], w[i2, 2] - w[i0, 2]
        nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
        s_o = -(nx * w[i0, 0] + ny * w[i0, 1] + nz * w[i0, 2])
        s_v = nx * (w[io, 0] - w[i0, 0]) + ny * (w[io, 1] - w[i0, 1]) + nz * (w[io, 2] - w[i0, 2])
        if s_o * s_v > 0.0:  # origin strictly on the vertex's side of this face
            continue
        outside_any = True
        _copy_rows(tmp, 0, w, i0, 1)
        _copy_rows(tmp, 1, w, i1, 1)
        _copy_rows(tmp, 2, w, i2, 1)
        x, y, z, m = _closest_on_triangle(tmp, 0, 1, 2)
        d = x * x + y * y + z * z
        if d < best:
            best, bx, by, bz, bn = d, x, y, z, m
            _copy_rows(keep, 0, tmp, 0, m)
    if not outside_any:
        return 0.0, 0.0, 0.0, 4
    _copy_rows(w, 0, keep, 0, bn)
    return bx, by, bz, bn


@njit(cache=True)
def _closest_on_triangle(w, ia, ib, ic):  # pragma: no cover - compiled
    """Closest point to the origin on triangle (w[ia], w[ib], w[ic]) by its Voronoi regions (Ericson, Real-Time
    Collision Detection 5.1.5); the supporting vertices are moved to the front of ``w``."""
    ax, ay, az = w[ia, 0], w[ia, 1], w[ia, 2]
    bx, by, bz = w[ib, 0], w[ib, 1], w[ib, 2]
    cx, cy, cz = w[ic, 0], w[ic, 1], w[ic, 2]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    d1 = -(abx * ax + aby * ay + abz * az)
    d2 = -(acx * ax + acy * ay + acz * az)
    if d1 <= 0.0 and d2 <= 0.0:
        w[0, 0], w[0, 1], w[0, 2] = ax, ay, az
        return ax, ay, az, 1
    d3 = -(abx * bx + aby * by + abz * bz)
    d4 = -(acx * bx + acy * by + acz * bz)
    if d3 >= 0.0 and d4 <= d3:
        w[0, 0], w[0, 1], w[0, 2] = bx, by, bz
        return bx, by, bz, 1
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        w[0, 0], w[0, 1], w[0, 2], w[1, 0], w[1, 1], w[1, 2] = ax, ay, az, bx, by, bz
        return ax + v * abx, ay + v * aby, az + v * abz, 2
    d5 = -(abx * cx + aby * cy + abz * cz)
    d6 = -(acx * cx + acy * cy + acz * cz)
    if d6 >= 0.0 and d5 <= d6:
        w[0, 0], w[0, 1], w[0, 2] = cx, cy, cz
        return cx, cy, cz, 1
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        v = d2 / (d2 - d6)
        w[0, 0], w[0, 1], w[0, 2], w[1, 0], w[1, 1], w[1, 2] = ax, ay, az, cx, cy, cz
        return ax + v * acx, ay + v * acy, az + v * acz, 2
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        v = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        w[0, 0], w[0, 1], w[0, 2], w[1, 0], w[1, 1], w[1, 2] = bx, by, bz, cx, cy, cz
        return bx + v * (cx - bx), by + v * (cy - by), bz + v * (cz - bz), 2
    den = 1.0 / (va + vb + vc)
    v, u = vb * den, vc * den
    w[0, 0], w[0, 1], w[0, 2] = ax, ay, az
    w[1, 0], w[1, 1], w[1, 2] = bx, by, bz
    w[2, 0], w[2, 1], w[2, 2] = cx, cy, cz
    return ax + abx * v + acx * u, ay + aby * v + acy * u, az + abz * v + acz * u, 3


@njit(cache=True)
def vehicle_distance(c, axes, half, scene, j):  # pragma: no cover - compiled
    """Distance [m] between the vehicle's box (centre ``c``, body axes as the rows of ``axes``, ``half`` extents)
    and obstacle ``j``, 0 when they intersect: GJK on the Minkowski difference of their support maps."""
    w = np.empty((4, 3))
    # start from the difference of the centres
    vx, vy, vz = c[0] - scene[j, COL_X], c[1] - scene[j, COL_Y], c[2] - 0.5 * (scene[j, COL_Z0] + scene[j, COL_Z1])
    n = 0
    for _ in range(64):
        ax, ay, az = _support_vehicle(c, axes, half, -vx, -vy, -vz)
        bx, by, bz = _support_obstacle(scene, j, vx, vy, vz)
        wx, wy, wz = ax - bx, ay - by, az - bz
        vv = vx * vx + vy * vy + vz * vz
        if n > 0 and vv - (vx * wx + vy * wy + vz * wz) <= 1e-12 * max(vv, 1e-12):
            break  # no support point comes closer: v is the closest point
        dup = False
        for k in range(n):
            if w[k, 0] == wx and w[k, 1] == wy and w[k, 2] == wz:
                dup = True
        if dup:
            break
        w[n, 0], w[n, 1], w[n, 2] = wx, wy, wz
        n += 1
        vx, vy, vz, n = _closest_on_simplex(w, n)
        if n == 4 or vx * vx + vy * vy + vz * vz < 1e-24:
            return 0.0
    return math.sqrt(vx * vx + vy * vy + vz * vz)


@njit(cache=True)
def vehicle_contact(c, axes, half, threshold, scene):  # pragma: no cover - compiled
    """What the vehicle's box touches, as PyBullet reports contacts: the first obstacle's row (a box when they
    overlap, a cylinder closer than ``threshold``), else :data:`GROUND` when the lowest corner is closer than
    ``threshold`` to the ground, else :data:`MISS`. Obstacles far from the box are skipped by bounding spheres."""
    reach = math.sqrt(half[0] * half[0] + half[1] * half[1] + half[2] * half[2]) + threshold
    for j in range(scene.shape[0]):
        if c[2] + reach < scene[j, COL_Z0] or c[2] - reach > scene[j, COL_Z1]:
            continue
        dx, dy = c[0] - scene[j, COL_X], c[1] - scene[j, COL_Y]
        foot = math.sqrt(scene[j, COL_HX] ** 2 + scene[j, COL_HY] ** 2) if scene[j, COL_KIND] == BOX \
            else scene[j, COL_HX]
        if dx * dx + dy * dy > (foot + reach) ** 2:
            continue
        if scene[j, COL_KIND] == BOX:
            if boxes_overlap(c, axes, half, scene, j):
                return j
        elif vehicle_distance(c, axes, half, scene, j) < threshold:
            return j
    if ground_clearance(c, axes, half) < threshold:
        return GROUND
    return MISS
