"""The search tests fly the paper's missions, whose plans hold items the simulator skips with a warning."""
import warnings

import pytest


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def tiny_policy(folder, problem: str):
    """A PPO policy trained for 16 steps on ``problem`` (episodes of 3 evaluations): enough to load and roll out."""
    pytest.importorskip("stable_baselines3")
    from search.rl import train_policy

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return train_policy(16, folder / "ppo.zip", problem=problem, budget=3, n_steps=8, batch_size=8, n_epochs=1)
