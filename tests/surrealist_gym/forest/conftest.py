"""Fixtures of the track's tests: the kit, its generators' output, and its validate.py and preflight.py as oracles
(imported from the kit's starter_kit folder, here in the tests only)."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

from tests.surrealist_gym.forest.track_kit import GENERATED, KIT, STARTER_KIT, run_generator


@pytest.fixture(scope="session")
def kit() -> Path:
    if not (STARTER_KIT / "validate.py").is_file():
        pytest.skip(f"needs the track's kit in {KIT}")
    return KIT


@pytest.fixture(scope="session")
def generated(kit, tmp_path_factory) -> dict[tuple[str, int], Path]:
    """The submissions the kit's generators write, by (generator, seed)."""
    root = tmp_path_factory.mktemp("generated")
    return {(name, seed): run_generator(name, seed, root / f"{name}-{seed}") for name, seed in GENERATED}


@pytest.fixture(scope="session")
def oracle(kit):
    """The kit's validate.py and preflight.py, imported from its starter_kit folder."""
    sys.path.insert(0, str(STARTER_KIT))
    import preflight
    import validate

    return validate, preflight


