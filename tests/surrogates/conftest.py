"""Copies of real evaluation stores for the surrogate tests: tests/data/stores holds three stores made by
`python benchmarks/reproduce_paper.py` (RQ1 seed 1 repetitions 0 and 1, RQ2 repetition 0); tests work on copies."""
from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest

STORES = Path(__file__).resolve().parents[1] / "data" / "stores"


@pytest.fixture(autouse=True)
def _quiet():
    """The surrogate tests fly the paper's missions, whose plans hold items the simulator skips with a warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def _copy(tmp_path_factory, name: str) -> Path:
    source = STORES / name
    dest = tmp_path_factory.mktemp("stores") / name
    shutil.copy(source, dest)
    return dest


@pytest.fixture(scope="session")
def rq1_stores(tmp_path_factory) -> list[Path]:
    return [_copy(tmp_path_factory, f"rq1-seed1-rep{i}.sqlite") for i in (0, 1)]


@pytest.fixture(scope="session")
def rq2_store(tmp_path_factory) -> Path:
    return _copy(tmp_path_factory, "rq2-rep0.sqlite")


@pytest.fixture(scope="session")
def replicate_featurizer():
    from surrogates.dataset import Featurizer
    return Featurizer.for_problem("replicate")


@pytest.fixture(scope="session")
def generate_featurizer():
    import warnings

    from surrogates.dataset import Featurizer
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return Featurizer.for_problem("generate")


@pytest.fixture(scope="session")
def replicate_lowfi_featurizer():
    from surrogates.dataset import Featurizer
    return Featurizer.for_problem("replicate", lowfi=True)


@pytest.fixture(scope="session")
def rq1_lowfi_dataset(rq1_stores, replicate_lowfi_featurizer):
    """The two RQ1 stores with multi-fidelity features (one low-fidelity flight per stored test, cached)."""
    from surrogates.dataset import load_dataset
    return load_dataset(rq1_stores, replicate_lowfi_featurizer)
