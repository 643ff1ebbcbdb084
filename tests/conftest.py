"""Shared fixtures: the real data in ../shared/data (beside the project root)."""
from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data"
EXPERIMENTS = SHARED_DATA / "surrealist" / "experiments"
FORMATS = SHARED_DATA / "formats"
CASE0_ULG = EXPERIMENTS / "case0.ulg"
REFERENCE_CSV = SHARED_DATA / "reference" / "case0_reference_trajectory.csv"


@pytest.fixture(scope="session")
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.fail(f"the shared data folder {SHARED_DATA} is missing: clone the project beside ../shared")
    return SHARED_DATA
