"""Shared fixtures of the simulator tests: the paper's seed tests on the real case0 mission."""
from __future__ import annotations

from dataclasses import replace

import pytest

from surrealist_gym import load_test
from tests.conftest import EXPERIMENTS

# the case0 landing point (case0.plan), metres from home: x north, y east
LAND_XY = (-16.645876487856597, 6.859186808331832)


@pytest.fixture(scope="session")
def seed1(shared_data):
    return load_test(EXPERIMENTS / "rq1-seed1.yaml")


@pytest.fixture(scope="session")
def blocked(seed1):
    """Seed 1 with its box moved onto the straight line from home to the landing point, 4 m tall (the 3-m box
    is level with the 3-m cruise altitude, so some runs skim over it)."""
    f = 0.52
    box = seed1.obstacles[0]
    return seed1.with_obstacles([replace(box, x=LAND_XY[0] * f, y=LAND_XY[1] * f, h=4.0)])


@pytest.fixture(scope="session")
def free(seed1):
    """The case0 mission without obstacles."""
    return seed1.with_obstacles([])

