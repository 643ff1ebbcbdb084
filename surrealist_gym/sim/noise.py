"""Reproducible noise: per-run seeds, estimator errors and wind (Gazebo wind-plugin fields plus turbulence).

Run ``i`` of a test draws everything from ``run_seed_sequence(test.key(), base_seed, i)``, so a run is
reproduced exactly from (test, base seed, index). All series are drawn up front as arrays at the outer-loop rate,
so the per-step loop only indexes them.
"""
from __future__ import annotations

import hashlib
import math

import numpy as np

from .config import NoiseConfig


def run_seed_sequence(test_key: str, base_seed: int, index: int) -> np.random.SeedSequence:
    """The seed of run ``index`` of the test with key ``test_key`` under ``base_seed``."""
    digest = hashlib.sha256(test_key.encode("utf-8")).digest()
    words = [int.from_bytes(digest[i:i + 4], "little") for i in range(0, 16, 4)]
    return np.random.SeedSequence([int(base_seed) & 0xFFFFFFFF, int(base_seed) >> 32 & 0xFFFFFFFF, int(index),
                                   *words])


def _ou(rng: np.random.Generator, n: int, dims: int, std: float, tau: float, dt: float) -> np.ndarray:
    """An (n, dims) stationary Ornstein-Uhlenbeck series with standard deviation std and correlation time tau."""
    if std <= 0 or n == 0:
        return np.zeros((n, dims))
    from scipy.signal import lfilter

    a = math.exp(-dt / tau)
    w = rng.standard_normal((n, dims)) * std * math.sqrt(1 - a * a)
    zi = rng.standard_normal((1, dims)) * std * a  # start in the stationary distribution
    return lfilter([1.0], [1.0, -a], w, axis=0, zi=zi)[0]


class NoiseSource:
    """Noise series of one run, sampled at the outer-loop period ``dt`` for ``n`` steps.

    Attributes:
        pos_err: (n, 3) estimator position error, NED [m].
        vel_err: (n, 3) estimator velocity error, NED [m/s].
        yaw_err: (n,) estimator heading error [rad].
        wind: (n, 3) wind velocity, NED [m/s].
        rng: generator for the depth sensor's noise (None when sensor noise is off).
    """

    def __init__(self, seed: np.random.SeedSequence, config: NoiseConfig, wind, n: int, dt: float):
        est, wnd, sens = (np.random.default_rng(s) for s in seed.spawn(3))
        c = config
        self.pos_err = _ou(est, n, 3, c.pos_drift_std, c.pos_drift_tau_s, dt)
        if c.pos_noise_std > 0:
            self.pos_err += est.standard_normal((n, 3)) * c.pos_noise_std
        self.vel_err = est.standard_normal((n, 3)) * c.vel_noise_std if c.vel_noise_std > 0 else np.zeros((n, 3))
        self.yaw_err = est.standard_normal(n) * 0.01 if c.pos_noise_std > 0 else np.zeros(n)
        self.wind = _ou(wnd, n, 3, c.turbulence_std, c.turbulence_tau_s, dt)
        self.wind[:, 2] *= 0.3  # vertical turbulence is weaker near the ground
        if wind is not None:
            self.wind += _plugin_wind(wnd, wind, n, dt)
        self.rng = sens if c.sensor else None
        # plain lists: indexing them in the loop is several times cheaper than numpy rows
        self.pos_list, self.vel_list = self.pos_err.tolist(), self.vel_err.tolist()
        self.yaw_list, self.wind_list = self.yaw_err.tolist(), [tuple(w) for w in self.wind.tolist()]


def _plugin_wind(rng: np.random.Generator, wind, n: int, dt: float) -> np.ndarray:
    """Gazebo wind plugin semantics: speed ~ N(mean, variance) capped at max, direction ~ unit(dir + N(0, var));
    a gust adds the same kind of wind during [gust_start, gust_start + gust_duration]. Redrawn every 0.1 s."""
    hold = max(1, int(round(0.1 / dt)))
    m = (n + hold - 1) // hold
    out = _draw(rng, m, wind.velocity_mean, wind.velocity_max, wind.velocity_variance, wind.direction,
                wind.direction_variance)
    gust = _draw(rng, m, wind.gust_velocity_mean, wind.gust_velocity_max, wind.gust_velocity_variance,
                 wind.gust_direction, wind.gust_direction_variance)
    t = np.arange(m) * hold * dt
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
