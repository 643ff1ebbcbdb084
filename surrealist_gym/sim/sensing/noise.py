"""Reproducible noise: per-run seeds, estimator errors, wind (Gazebo wind-plugin fields plus turbulence) and timing
(when the planner's cycles run, when the mission starts).

Run ``i`` of a test draws everything from ``run_seed_sequence(test.key(), base_seed, i)``, so a run is
reproduced exactly from (test, base seed, index); with ``SimConfig.common_noise`` the key is empty, so run ``i``
of every test meets the same noise. Series are drawn in blocks at the outer-loop rate as the flight
needs them, so the per-step loop only indexes lists and a short flight draws only what it uses.
"""
from __future__ import annotations

import hashlib
import math

import numpy as np

from ..config import NoiseConfig


def run_seed_sequence(test_key: str, base_seed: int, index: int) -> np.random.SeedSequence:
    """The seed of run ``index`` of the test with key ``test_key`` under ``base_seed``."""
    digest = hashlib.sha256(test_key.encode("utf-8")).digest()
    words = [int.from_bytes(digest[i:i + 4], "little") for i in range(0, 16, 4)]
    return np.random.SeedSequence([int(base_seed) & 0xFFFFFFFF, int(base_seed) >> 32 & 0xFFFFFFFF, int(index),
                                   *words])


class _OU:
    """A stationary Ornstein-Uhlenbeck process (std, correlation time tau) drawn block by block."""

    def __init__(self, rng: np.random.Generator, dims: int, std: float, tau: float, dt: float):
        self.rng, self.dims, self.std = rng, dims, std
        self.a = math.exp(-dt / tau)
        self.state = rng.standard_normal(dims) * std if std > 0 else np.zeros(dims)  # stationary start

    def block(self, n: int) -> np.ndarray:
        if self.std <= 0:
            return np.zeros((n, self.dims))
        from scipy.signal import lfilter

        w = self.rng.standard_normal((n, self.dims)) * self.std * math.sqrt(1 - self.a * self.a)
        out, _ = lfilter([1.0], [1.0, -self.a], w, axis=0, zi=(self.a * self.state)[None, :])
        self.state = out[-1]
        return out


class NoiseSource:
    """Noise series of one run at the outer-loop period ``dt``, drawn in blocks as the flight needs them.

    ``at(k)`` gives the estimator position error (NED, m), velocity error (NED, m/s), heading error (rad) and the
    wind (NED, m/s) of outer step ``k``; ``plans(k)`` whether the planner plans at step ``k`` (every ``plan_div``
    steps; with jitter, its cycles keep that period from a random phase and each plans U(0, planner_jitter_s) after
    its cycle starts, on the outer-step grid).
    ``start_offset`` [s] is added to the mission start (N(0, start_jitter_s), never before arming). ``rng`` is the
    depth sensor's generator (None when sensor noise is off). Blocks are drawn in order from the run's own
    generators, so a run is reproduced exactly whatever its length.
    """

    BLOCK = 250  # outer steps per block (5 s at 50 Hz); a multiple of the 0.1 s wind-plugin hold

    def __init__(self, seed: np.random.SeedSequence, config: NoiseConfig, wind, dt: float, plan_div: int = 5,
                 start_time: float = 0.0):
        self._est, self._wnd, sens, timing = (np.random.default_rng(s) for s in seed.spawn(4))
        self.config, self.plugin, self.dt = config, wind, dt
        c = config
        self._drift = _OU(self._est, 3, c.pos_drift_std, c.pos_drift_tau_s, dt)
        self._turbulence = _OU(self._wnd, 3, c.turbulence_std, c.turbulence_tau_s, dt)
        self.rng = sens if c.sensor else None
        self._timing, self._plan_div = timing, int(plan_div)
        # the planner's cycles start every plan_div steps from a phase of their own; each plans after U(0, jitter)
        jitter = c.planner_jitter_s / dt
        self._cycle = float(timing.uniform(0.0, plan_div)) if jitter > 0 else 0.0  # start of the next cycle [steps]
        self._next_plan = self._cycle + (timing.uniform(0.0, jitter) if jitter > 0 else 0.0)  # its planning instant
        self.start_offset = (max(-start_time, float(timing.normal(0.0, c.start_jitter_s)))
                             if c.start_jitter_s > 0 else 0.0)
        # plain lists: indexing them in the loop is several times cheaper than numpy rows
        self.pos_list, self.vel_list, self.yaw_list, self.wind_list, self.plan_list = [], [], [], [], []
        self._drawn = 0  # steps drawn so far

    def at(self, k: int):
        """Step ``k``'s position and velocity estimate errors, yaw error and wind (blocks drawn as needed)."""
        while k >= len(self.pos_list):
            pos, vel, yaw, wind, plan = self._draw()
            self.pos_list += pos.tolist()
            self.vel_list += vel.tolist()
            self.yaw_list += yaw.tolist()
            self.wind_list += [tuple(w) for w in wind.tolist()]
            self.plan_list += (plan != 0.0).tolist()
        return self.pos_list[k], self.vel_list[k], self.yaw_list[k], self.wind_list[k]

    def plans(self, k: int) -> bool:
        """Whether a planner cycle starts at outer step ``k`` (after :meth:`at` of the same step)."""
        return self.plan_list[k]

    def block(self) -> np.ndarray:
        """The next ``BLOCK`` steps as one (BLOCK, 11) array (the compiled loop's form of :meth:`at` and
        :meth:`plans`): position error (3), velocity error (3), yaw error, wind (3), planner cycle (1.0 or 0.0). Do
        not mix with :meth:`at` on one source."""
        pos, vel, yaw, wind, plan = self._draw()
        return np.concatenate((pos, vel, yaw[:, None], wind, plan[:, None]), axis=1)

    def _schedule(self, n: int) -> np.ndarray:
        """The planning flags of the next ``n`` outer steps: cycles every ``plan_div`` steps, each planning
        U(0, planner_jitter_s) after its start, at the first outer step at or after that instant."""
        out = np.zeros(n)
        jitter = self.config.planner_jitter_s / self.dt  # in outer steps
        first = self._drawn
        while (step := int(math.ceil(self._next_plan - 1e-9))) < first + n:
            out[step - first] = 1.0
            self._cycle += self._plan_div
            self._next_plan = max(self._next_plan + 1.0, self._cycle + (self._timing.uniform(0.0, jitter)
                                                                         if jitter > 0 else 0.0))
        return out

    def _draw(self):
        """The next block's series, drawn from the run's generators in their fixed order."""
        n, c, est = self.BLOCK, self.config, self._est
        pos = self._drift.block(n)
        if c.pos_noise_std > 0:
            pos += est.standard_normal((n, 3)) * c.pos_noise_std
        vel = est.standard_normal((n, 3)) * c.vel_noise_std if c.vel_noise_std > 0 else np.zeros((n, 3))
        yaw = est.standard_normal(n) * 0.01 if c.pos_noise_std > 0 else np.zeros(n)
        wind = self._turbulence.block(n)
        wind[:, 2] *= 0.3  # vertical turbulence is weaker near the ground
        if self.plugin is not None:
            wind += _plugin_wind(self._wnd, self.plugin, n, self.dt, self._drawn * self.dt)
        plan = self._schedule(n)
        self._drawn += n
        return pos, vel, yaw, wind, plan


def _plugin_wind(rng: np.random.Generator, wind, n: int, dt: float, t0: float = 0.0) -> np.ndarray:
    """Gazebo wind plugin semantics: speed ~ N(mean, variance) capped at max, direction ~ unit(dir + N(0, var));
    a gust adds the same kind of wind during [gust_start, gust_start + gust_duration]. Redrawn every 0.1 s."""
    hold = max(1, int(round(0.1 / dt)))
    m = (n + hold - 1) // hold
    out = _draw(rng, m, wind.velocity_mean, wind.velocity_max, wind.velocity_variance, wind.direction,
                wind.direction_variance)
    gust = _draw(rng, m, wind.gust_velocity_mean, wind.gust_velocity_max, wind.gust_velocity_variance,
                 wind.gust_direction, wind.gust_direction_variance)
    t = t0 + np.arange(m) * hold * dt
    active = (t >= wind.gust_start) & (t < wind.gust_start + wind.gust_duration)
    out[active] += gust[active]
    return np.repeat(out, hold, axis=0)[:n]


def _draw(rng, m, mean, vmax, var, direction, dir_var) -> np.ndarray:
    speed = mean + math.sqrt(var) * rng.standard_normal(m)
    speed = np.clip(speed, 0.0, vmax if vmax > 0 else max(mean, 0.0))
    d = np.asarray(direction, dtype=float)[None, :] + math.sqrt(dir_var) * rng.standard_normal((m, 3))
    norm = np.linalg.norm(d, axis=1, keepdims=True)
    d = np.divide(d, norm, out=np.zeros_like(d), where=norm > 1e-12)
    return d * speed[:, None]
