"""SB3's vector env whose envs step at once on threads of this process.

The compiled loop releases the GIL while it flies (``fly_span`` is ``nogil``), so envs stepped on threads fly their
runs in parallel, as SB3's ``SubprocVecEnv`` does with one process per env, without the processes: no env is
pickled, the simulator is loaded once, and an env's state stays inspectable in this process. Each env steps on its own
thread, and the results are gathered in env order, so a step gives what SB3's ``DummyVecEnv`` gives for the same
envs (each env's runs draw their noise from its own seeds, never from another thread).
"""
from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from copy import deepcopy

import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv

__all__ = ["ThreadVecEnv"]


def _step(env, action):
    """One env's step as ``DummyVecEnv.step_wait`` takes it: an ended episode is reset, its last observation kept."""
    obs, reward, terminated, truncated, info = env.step(action)
    done = terminated or truncated
    info["TimeLimit.truncated"] = truncated and not terminated
    reset_info = None
    if done:
        info["terminal_observation"] = obs
        obs, reset_info = env.reset()
    return obs, reward, done, info, reset_info


class ThreadVecEnv(DummyVecEnv):
    """``DummyVecEnv`` with ``step_wait`` run on one thread per env (module docstring)."""

    def __init__(self, env_fns):
        super().__init__(env_fns)
        self._pool = ThreadPoolExecutor(max_workers=self.num_envs, thread_name_prefix="env")

    def step_wait(self):
        """Step every env on its thread with its action of ``step_async``; SB3's (obs, rewards, dones, infos)."""
        stepped = list(self._pool.map(_step, self.envs, self.actions))
        for i, (obs, reward, done, info, reset_info) in enumerate(stepped):
            self.buf_rews[i], self.buf_dones[i], self.buf_infos[i] = reward, done, info
            if reset_info is not None:
                self.reset_infos[i] = reset_info
            self._save_obs(i, obs)
        return self._obs_from_buf(), np.copy(self.buf_rews), np.copy(self.buf_dones), deepcopy(self.buf_infos)

    def close(self) -> None:
        """Let the steps in flight end (Ctrl-C stops the waiting, not the threads), then close the envs."""
        self._pool.shutdown(cancel_futures=True)
        super().close()
