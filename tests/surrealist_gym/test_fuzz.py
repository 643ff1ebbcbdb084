"""Property tests of the readers of files from anywhere: random mutations of real test YAMLs, mission plans and
flight logs give a value or one SurrealistError, never another exception (hypothesis, derandomised: the same
examples in every run)."""
from __future__ import annotations

import shutil
import warnings
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import surrealist_gym as sg
from surrealist_gym.errors import SurrealistError

DATA = Path(sg.data_path("case0.plan")).parent
FORMATS = Path(__file__).resolve().parents[3] / "shared" / "data" / "formats"

EDIT = st.tuples(st.floats(0.0, 1.0, allow_nan=False), st.sampled_from(("flip", "delete", "insert", "cut")),
                 st.integers(0, 255), st.booleans())
EDITS = st.lists(EDIT, min_size=1, max_size=6)
FUZZ = settings(max_examples=int(__import__("os").environ.get("FUZZ_EXAMPLES", 60)), deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def mutate(data: bytes, edits, head: int = 4096) -> bytes:
    """Apply byte edits; an edit's flag puts it in the first ``head`` bytes (where headers and definitions are)."""
    out = bytearray(data)
    for where, kind, value, in_head in edits:
        if not out:
            break
        span = min(head, len(out)) if in_head else len(out)
        i = min(int(where * span), len(out) - 1)
        if kind == "flip":
            out[i] ^= value or 1
        elif kind == "delete":
            del out[i:i + 1 + value % 8]
        elif kind == "insert":
            out[i:i] = bytes([value]) * (1 + value % 8)
        else:
            del out[i:]
    return bytes(out)


def _holds(read, path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            read(path)
        except SurrealistError as err:
            assert "\n" not in str(err).strip(), f"a multi-line error: {err}"


@pytest.mark.parametrize("name", ["rq1-seed1.yaml", "rq2-seed.yaml"])
@FUZZ
@given(edits=EDITS)
def test_a_mutated_test_yaml_is_read_or_refused_in_one_line(tmp_path, name, edits):
    for companion in ("case0.plan", "case0-params.csv", "case0-commands.csv", "auto1.plan", "auto1-params.csv",
                      "auto-commands.csv"):
        shutil.copy(DATA / companion, tmp_path / companion)
    path = tmp_path / name
    path.write_bytes(mutate((DATA / name).read_bytes(), edits, head=600))
    _holds(sg.load_test, path)


@pytest.mark.parametrize("name", ["case0.plan", "auto1.plan"])
@FUZZ
@given(edits=EDITS)
def test_a_mutated_plan_is_read_or_refused_in_one_line(tmp_path, name, edits):
    from surrealist_gym.mission import read_mission

    path = tmp_path / name
    path.write_bytes(mutate((DATA / name).read_bytes(), edits))
    _holds(read_mission, path)


@pytest.mark.parametrize("name", ["ulog/px4tools_19_56_46.ulg", "tlog/dronekit_log_upload_test.tlog",
                                  "dataflash/pymavlink_test.BIN"])
@settings(max_examples=int(__import__("os").environ.get("FUZZ_EXAMPLES", 40)), deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(edits=EDITS)
def test_a_mutated_flight_log_is_read_or_refused_in_one_line(tmp_path, name, edits):
    source = FORMATS / name
    if not source.is_file():
        pytest.skip(f"{source} not found (../shared/data beside the project)")
    path = tmp_path / Path(name).name
    path.write_bytes(mutate(source.read_bytes(), edits))
    _holds(sg.read_flight, path)


@settings(max_examples=int(__import__("os").environ.get("FUZZ_EXAMPLES", 40)), deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(edits=EDITS)
def test_a_damaged_store_is_read_or_refused_in_one_line(tmp_path, edits):
    from surrealist_gym.store import EvaluationStore

    source = Path(__file__).resolve().parents[1] / "data" / "stores" / "rq2-rep0.sqlite"
    path = tmp_path / "evaluations.sqlite"
    path.write_bytes(mutate(source.read_bytes(), edits, head=8192))

    def read(store_path):
        store = EvaluationStore(store_path)
        try:
            len(store), store.identity, [e.fitness for e in store]
        finally:
            store.close()
    _holds(read, path)
