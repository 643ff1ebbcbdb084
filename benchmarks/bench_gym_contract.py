"""The envs as a new Gymnasium user meets them: refused actions, PPO's refusals, and the first simulation's wait.

    python benchmarks/bench_gym_contract.py [--samples 300] [--ppo-steps 2048] [--skip-ppo] [--skip-compile]

1. Flyable actions: of ``--samples`` ``action_space.sample()`` actions per env, how many the bare env
   (``flyable=False``) refuses, against ``gym.make``'s env (its test checked without flying it), and what the
   repair costs per action.
2. PPO (stable-baselines3, default settings but ``n_steps`` 256) for ``--ppo-steps`` steps on
   ``Surrealist-CaseStudy-v1`` (mission1, 1 run per evaluation, in process): the share of steps refused, with
   ``gym.make``'s env and with the bare one (the baseline).
3. The first ``surrealist simulate`` of a competition case study in a fresh numba cache (a new ``NUMBA_CACHE_DIR``),
   against the second run with that cache warm: wall seconds of each and their ratio.
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import gymnasium as gym

import surrealist_gym  # noqa: F401  (registers the envs)

ENV_IDS = ("Surrealist-Replicate-v0", "Surrealist-Generate-v0", "Surrealist-CaseStudy-v1")


def refusals(env_id: str, samples: int) -> tuple[int, int, float]:
    """(refused by the bare env, refused after gym.make's repair, repair milliseconds per action)."""
    env = gym.make(env_id, budget=1, runs=1, executor="inline")
    flyable = env.env.env  # gym.make: OrderEnforcing(PassiveEnvChecker(FlyableActions(env)))
    env.action_space.seed(0)
    actions = [env.action_space.sample() for _ in range(samples)]
    start = time.perf_counter()
    repaired = [flyable.repair(a) for a in actions]
    per_action = (time.perf_counter() - start) / samples * 1000
    env.close()
    return sum(not flyable.flies(a) for a in actions), sum(not flyable.flies(a) for a in repaired), per_action


def ppo_refusals(steps: int, flyable: bool) -> tuple[int, int, float]:
    """(steps refused, steps taken, wall seconds) of a PPO run on the case study."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback

    env = gym.make("Surrealist-CaseStudy-v1", flyable=flyable, budget=200, runs=1, executor="inline")
    refused: list[bool] = []

    class Count(BaseCallback):
        def _on_step(self) -> bool:
            refused.extend(info.get("invalid") is not None for info in self.locals["infos"])
            return True

    start = time.perf_counter()
    PPO("MlpPolicy", env, n_steps=256, seed=0, device="cpu").learn(steps, callback=Count())
    env.close()
    return sum(refused), len(refused), time.perf_counter() - start


def simulate_seconds(cache: str, out: Path) -> float:
    """Wall seconds of ``surrealist simulate mission1 --runs 1`` with numba's cache in ``cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    start = time.perf_counter()
    from surrealist_gym.competition.rules import case_study_path

    subprocess.run([sys.executable, "-m", "surrealist_gym.cli", "simulate", str(case_study_path("mission1")), "--runs",
                    "1", "--out", str(out)], env=env, check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=int, default=300)
    parser.add_argument("--ppo-steps", type=int, default=2048)
    parser.add_argument("--skip-ppo", action="store_true")
    parser.add_argument("--skip-compile", action="store_true")
    args = parser.parse_args()
    print(f"| env | refused of {args.samples} samples: bare env | gym.make's | repair per action |")
    print("|---|---|---|---|")
    for env_id in ENV_IDS:
        bare, made, ms = refusals(env_id, args.samples)
        print(f"| {env_id} | {bare} ({bare / args.samples:.0%}) | {made} ({made / args.samples:.0%}) | {ms:.1f} ms |")
    if not args.skip_ppo:
        print(f"\nPPO, {args.ppo_steps} steps on Surrealist-CaseStudy-v1 (mission1):")
        for flyable in (False, True):
            refused, taken, seconds = ppo_refusals(args.ppo_steps, flyable)
            name = "gym.make's env" if flyable else "bare env (flyable=False)"
            print(f"  {name}: {refused} of {taken} steps refused ({refused / max(taken, 1):.1%}), {seconds:.0f} s")
    if not args.skip_compile:
        with tempfile.TemporaryDirectory() as tmp:
            cold = simulate_seconds(str(Path(tmp) / "numba"), Path(tmp) / "cold")
            warm = simulate_seconds(str(Path(tmp) / "numba"), Path(tmp) / "warm")
        print(f"\nfirst `surrealist simulate mission1 --runs 1` in a fresh numba cache: {cold:.1f} s; "
              f"the second: {warm:.1f} s ({cold / warm:.1f}x)")


if __name__ == "__main__":
    main()
