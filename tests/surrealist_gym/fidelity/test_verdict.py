"""The model of PX4's verdict on real data: features of real flights, the shipped model refitted from its real training
table (deterministic, the same file), a bad model file, and the ranking the pre-screen makes."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from surrealist_gym.errors import SurrealistError
from surrealist_gym.fidelity.labels import load_labelled_set
from surrealist_gym.fidelity.measure import fly_labelled_set
from surrealist_gym.fidelity.verdict import (
    SHIPPED,
    fit_verdict,
    half_of,
    load_verdict,
    rank_by_verdict,
    read_table,
    training_table,
    write_ranking,
)
from surrealist_gym.fidelity.verdict_features import FEATURES
from surrealist_gym.sim.uav import decide_uav
from tests.conftest import SHARED_DATA

ROOT = Path(__file__).resolve().parents[3]
TABLE = ROOT / "benchmarks" / "data" / "px4-verdict-training.csv"
RILAST = SHARED_DATA / "competition" / "rilast-mission1" / "tests.csv"


@pytest.fixture(scope="module")
def flown(shared_data):
    """Three rilast tests (PX4: 0.79 m, 4.23 m and a far one), flown once each in this process."""
    lset = load_labelled_set(RILAST)
    wanted = {"random_run0_0", "random_run0_100"}
    close = min(range(len(lset)), key=lambda i: lset.labels[i].distance if lset.labels[i].result == "flown" else 99)
    keep = [i for i, label in enumerate(lset.labels) if label.test_id in wanted] + [close]
    from dataclasses import replace
    lset = replace(lset, labels=tuple(lset.labels[i] for i in keep), tests=tuple(lset.tests[i] for i in keep))
    config = decide_uav(uav="px4-v1.12-sitl-iris").config
    return lset, fly_labelled_set(lset, 1, 0, config, workers=1)


def test_features_of_real_flights_are_finite_and_describe_the_layout(flown):
    lset, outcomes = flown
    rows = training_table(lset, outcomes)
    assert [r["test"] for r in rows][:2] == ["random_run0_0", "random_run0_100"]
    for row in rows:
        assert all(math.isfinite(row[f]) for f in FEATURES), row
        assert 0.0 <= row["share_unsafe"] <= 1.0 and row["d_min"] <= row["d_median"] <= row["d_max"]
        assert row["obstacles"] == len(lset.tests[rows.index(row)].obstacles)
        assert row["half"] == "development" if row["test"].startswith("random_run0") else True
    assert rows[0]["path_clearance"] < rows[1]["path_clearance"]  # run0_0's boxes stand nearer the line
    assert half_of("ga_run3_17") == "held-out" and half_of("x") == "-"


def _same_model(a, b, path: str = "") -> None:
    """Two models' JSON values alike: text and whole numbers exactly, floats within 1e-9 (relative; a refit's sums
    depend on the machine's BLAS and summation order in their last digits)."""
    if isinstance(a, dict):
        assert sorted(a) == sorted(b), path
        for key in a:
            _same_model(a[key], b[key], f"{path}.{key}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b)):
            _same_model(x, y, f"{path}[{i}]")
    elif isinstance(a, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-12), path
    else:
        assert a == b, path


def test_the_shipped_model_is_what_a_refit_of_its_training_table_gives(tmp_path):
    from surrealist_gym.cli import main

    shipped = json.loads(SHIPPED.read_text())
    rows = read_table(TABLE)
    assert len(rows) == 1350 and sum(r["px4_result"] == "flown" for r in rows) == 1176
    expected = load_verdict().predict(rows)
    fits = []
    for k in range(2):  # deterministic on this machine: twice the same bytes; the shipped file's within 1e-9
        out = tmp_path / f"m{k}.json"
        assert main(["predict", "--fit", str(TABLE), "--model", str(out), "--l2", str(shipped["unsafe"]["l2"])]) == 0
        fits.append(out.read_bytes())
        refit = json.loads(fits[-1])
        _same_model(refit["unsafe"], shipped["unsafe"], "unsafe")
        _same_model(refit["hard"], shipped["hard"], "hard")
        for p, q in zip(load_verdict(out).predict(rows), expected):  # the same verdicts on every training row
            np.testing.assert_allclose(p, q, rtol=1e-9, atol=1e-12)
    assert fits[0] == fits[1]
    p_unsafe, p_hard = expected
    assert ((0 <= p_unsafe) & (p_unsafe <= 1) & (0 <= p_hard) & (p_hard <= 1)).all()


def test_a_bad_model_file_is_one_line(tmp_path):
    bad = tmp_path / "m.json"
    bad.write_text('{"unsafe": {"features": ["wingspan"]}}')
    with pytest.raises(SurrealistError, match=r"m.json: not a PX4 verdict model"):
        load_verdict(bad)
    with pytest.raises(SurrealistError, match="cannot read the model"):
        load_verdict(tmp_path / "none.json")


def test_the_ranking_puts_the_likeliest_px4_failure_first(flown, tmp_path):
    lset, outcomes = flown
    expected = [1.0, 1.0, 1.0]  # the same expected score: the model's probability alone orders them
    order, predictions = rank_by_verdict(lset.tests, outcomes, expected)
    p = [predictions[i].p_unsafe for i in order]
    assert p == sorted(p, reverse=True) and order[0] == 2  # the closest PX4 flight is the likeliest
    order2, _ = rank_by_verdict(lset.tests, outcomes, [0.0, 0.0, 5.0])
    assert order2[0] == 2 and sorted(order2) == [0, 1, 2]
    table = write_ranking(tmp_path / "r.csv", [f"t{i}.yaml" for i in range(3)], predictions, expected, order)
    lines = table.read_text().splitlines()
    assert lines[0].startswith("rank,test,p_px4_under_1_5m") and lines[1].startswith(f"1,t{order[0]}.yaml,")


def test_a_fit_on_one_half_differs_from_the_other():
    rows = read_table(TABLE)
    dev, held = fit_verdict(rows, halves=["development"]), fit_verdict(rows, halves=["held-out"])
    both = fit_verdict(rows)  # the tests PX4 flew whose closest run of ours came within 6 m
    assert dev.trained_on["tests"] + held.trained_on["tests"] == both.trained_on["tests"] == 835
    assert both.trained_on["near_m"] == 6.0 and both.unsafe.features == both.hard.features
    assert not np.allclose(dev.unsafe.coef, held.unsafe.coef)
