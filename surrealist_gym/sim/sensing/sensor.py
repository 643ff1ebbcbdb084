"""A forward-looking depth camera by analytic ray casting against box and cylinder obstacles.

World frame: x north, y east, z up [m]; yaw [rad] from north toward east, heading ``(cos yaw, sin yaw, 0)``.
The camera is level (the UAV's roll and pitch are ignored) and looks along the yaw heading; its rays go through
a regular pixel grid of a pinhole image (``rays_h`` x ``rays_v``), like a subsampled depth image.

The ground (z = 0) hides what lies behind it. It is returned as a hit only with ``returns_ground`` (a Gazebo depth
camera sees the ground plane, and PX4-Avoidance treats those points as obstacles); by default :meth:`DepthSensor.scan`
returns obstacle points only.

Example::

    >>> from surrealist_gym.testcase import Obstacle
    >>> sensor = DepthSensor([Obstacle(3, 3, 3, 5.0, 0.0)])
    >>> hits = sensor.scan((0.0, 0.0, 1.5), 0.0)
    >>> bool(abs(hits[:, 0].min() - 3.5) < 1e-9)
    True
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numba import njit

from ...testcase import Obstacle, Shape

__all__ = ["DepthSensorConfig", "DepthSensor"]


@dataclass(frozen=True, slots=True)
class DepthSensorConfig:
    """Depth camera parameters; defaults follow the PX4 Vision's Occipital Structure Core.

    Attributes:
        fov_h_deg: Horizontal field of view [deg] (Structure Core: ~59).
        fov_v_deg: Vertical field of view [deg] (Structure Core: ~46).
        range_min: Closest range returned [m] (PX4-Avoidance drops points nearer than 0.2 m).
        range_max: Farthest range returned [m]. The Structure Core gives usable depth to roughly 10 m outdoors
            at best (PX4-Avoidance accepts up to 15 m); 10 m lets the planner see an obstacle early enough for
            the smooth detours seen in the real flights.
        rays_h: Rays per image row (~1.9 deg apart with the defaults).
        rays_v: Rays per image column (~4.2 deg apart with the defaults).
        noise_std: Standard deviation of the Gaussian range noise [m], applied only when ``scan`` gets an rng.
        returns_ground: Whether points on the ground plane are returned too.
    """

    fov_h_deg: float = 59.0
    fov_v_deg: float = 46.0
    range_min: float = 0.2
    range_max: float = 10.0
    rays_h: int = 32
    rays_v: int = 12
    noise_std: float = 0.02
    returns_ground: bool = False

    def __post_init__(self):
        for name in ("fov_h_deg", "fov_v_deg"):
            value = getattr(self, name)
            if not 0.0 < value < 180.0:
                raise ValueError(f"DepthSensorConfig.{name}: expected a value in (0, 180) deg, got {value!r}")
        if not 0.0 <= self.range_min < self.range_max or not math.isfinite(self.range_max):
            raise ValueError(f"DepthSensorConfig: expected 0 <= range_min < range_max < inf, got "
                             f"{self.range_min!r}, {self.range_max!r}")
        for name in ("rays_h", "rays_v"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"DepthSensorConfig.{name}: expected a positive int, got {value!r}")
        if not self.noise_std >= 0.0:
            raise ValueError(f"DepthSensorConfig.noise_std: expected >= 0 m, got {self.noise_std!r}")


class DepthSensor:
    """Casts the camera's rays against a fixed set of obstacles.

    Args:
        obstacles: The obstacles (boxes and vertical cylinders); their geometry is precomputed once.
        config: Camera parameters.
    """

    def __init__(self, obstacles: Sequence[Obstacle], config: DepthSensorConfig = DepthSensorConfig()):
        self.config = config
        c = config
        th, tv = math.tan(math.radians(c.fov_h_deg) / 2), math.tan(math.radians(c.fov_v_deg) / 2)
        u = np.linspace(-th, th, c.rays_h) if c.rays_h > 1 else np.zeros(1)
        v = np.linspace(-tv, tv, c.rays_v) if c.rays_v > 1 else np.zeros(1)
        uu, vv = np.meshgrid(u, v, indexing="ij")
        rays = np.stack([np.ones(uu.size), uu.ravel(), vv.ravel()], axis=1)  # (forward, right, up) components
        self._rays = np.ascontiguousarray(rays / np.linalg.norm(rays, axis=1)[:, None])
        boxes, cyls = [], []
        for o in obstacles:
            if o.shape == Shape.CYLINDER:
                cyls.append((o.x, o.y, o.l / 2, o.z, o.z + o.h))
            else:
                a = math.radians(o.r)
                boxes.append((o.x, o.y, o.z + o.h / 2, math.cos(a), math.sin(a), o.l / 2, o.w / 2, o.h / 2))
        self._boxes = np.array(boxes, dtype=np.float64).reshape(-1, 8)
        self._cyls = np.array(cyls, dtype=np.float64).reshape(-1, 5)
        n = self._rays.shape[0]
        self._zeros = np.zeros(n)
        self._out = np.empty((n, 3))

    @property
    def n_rays(self) -> int:
        """Number of rays per scan."""
        return self._rays.shape[0]

    def scan(self, position, yaw: float, rng: np.random.Generator | None = None) -> np.ndarray:
        """World points where the rays hit an obstacle within ``[range_min, range_max]``.

        Args:
            position: Camera position (x, y, z) [m].
            yaw: Camera heading [rad] from north toward east.
            rng: When given (and ``noise_std > 0``), adds Gaussian range noise drawn from it (one draw per ray,
                so the rng advances by the same amount whatever is hit).

        Returns:
            A new ``(K, 3)`` float array of hit points (x, y, z) [m], K <= number of rays; ground hits excluded.
        """
        c = self.config
        if rng is not None and c.noise_std > 0.0:
            noise = rng.standard_normal(self._rays.shape[0]) * c.noise_std
        else:
            noise = self._zeros
        k = cast_scan(float(position[0]), float(position[1]), float(position[2]), math.cos(yaw), math.sin(yaw),
                  self._rays, self._boxes, self._cyls, c.range_min, c.range_max, noise, self._out,
                  bool(c.returns_ground))
        return self._out[:k].copy()


@njit(cache=True)
def cast_scan(px, py, pz, cy, sy, rays, boxes, cyls, rmin, rmax, noise, out, ground):  # pragma: no cover - compiled
    """Fill ``out`` with the obstacle hit points of every ray; return their count."""
    k = 0
    for i in range(rays.shape[0]):
        a, b, up = rays[i, 0], rays[i, 1], rays[i, 2]
        dx = a * cy - b * sy
        dy = a * sy + b * cy
        dz = up
        best = rmax
        hit = False
        if dz < -1e-12:  # the ground occludes (and is a hit when the camera returns it)
            tg = -pz / dz
            if tg < best:
                best = tg
                hit = ground
        for j in range(boxes.shape[0]):
            ox, oy, oz = px - boxes[j, 0], py - boxes[j, 1], pz - boxes[j, 2]
            c, s = boxes[j, 3], boxes[j, 4]
            lo = (c * ox + s * oy, -s * ox + c * oy, oz)
            ld = (c * dx + s * dy, -s * dx + c * dy, dz)
            half = (boxes[j, 5], boxes[j, 6], boxes[j, 7])
            tn, tf = -1e300, 1e300
            miss = False
            for ax in range(3):
                o, d, h = lo[ax], ld[ax], half[ax]
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
            if tn < 0.0:  # camera inside the box: it sees nothing along this ray
                best = 0.0
                hit = False
                continue
            if tn < best:
                best = tn
                hit = True
        for j in range(cyls.shape[0]):
            ox, oy = px - cyls[j, 0], py - cyls[j, 1]
            r, z0, z1 = cyls[j, 2], cyls[j, 3], cyls[j, 4]
            cc = ox * ox + oy * oy - r * r
            if cc <= 0.0 and z0 <= pz <= z1:  # camera inside the cylinder
                best = 0.0
                hit = False
                continue
            t = 1e300
            aa = dx * dx + dy * dy
            if aa > 1e-18:
                bb = ox * dx + oy * dy
                disc = bb * bb - aa * cc
                if disc >= 0.0:
                    t1 = (-bb - math.sqrt(disc)) / aa
                    if t1 >= 0.0:
                        z = pz + t1 * dz
                        if z0 <= z <= z1:
                            t = t1
            if abs(dz) > 1e-12:
                for zc in (z0, z1):
                    tc = (zc - pz) / dz
                    if 0.0 <= tc < t:
                        x, y = ox + tc * dx, oy + tc * dy
                        if x * x + y * y <= r * r:
                            t = tc
            if t < best:
                best = t
                hit = True
        if hit:
            tr = best + noise[i]
            if rmin <= tr <= rmax:
                out[k, 0] = px + tr * dx
                out[k, 1] = py + tr * dy
                out[k, 2] = pz + tr * dz
                k += 1
    return k
