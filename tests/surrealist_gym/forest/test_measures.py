"""preflight.py's measures from surrealist_gym.forest.measures, equal to the kit's preflight.py (and validate.py's
check_navigable, which preflight.py calls) to 1e-9 on the kit's generators' submissions, the train manifest's
scenarios and the flights' scenarios."""
from __future__ import annotations

import contextlib
import io
import json
import re
import statistics
import sys
from types import SimpleNamespace

import pytest

from surrealist_gym.forest.measures import (
    Band,
    band,
    factor_spread,
    free_lateral_width,
    nearest_pole_to_route,
    preflight,
    widest_gap,
)
from surrealist_gym.forest.records import read_flight, read_train_manifest
from surrealist_gym.forest.scenario import Scenario, read_submission
from surrealist_gym.forest.space import INPUT_DIV_FACTORS
from tests.surrealist_gym.forest.track_kit import FLIGHTS, GENERATED, MANIFEST, manifest_scenarios

TOLERANCE = 1e-9


def run_preflight(preflight_py, path, monkeypatch) -> tuple[list[float], float, str]:
    """preflight.py's main on ``path``: the per-factor spreads and input_div it computed (read off its call of
    statistics.mean, exact where its report prints 3 decimals) and its report."""
    means = []

    def mean(values):
        means.append((list(values), statistics.mean(values)))
        return means[-1][1]

    monkeypatch.setattr(preflight_py, "st", SimpleNamespace(pstdev=statistics.pstdev, median=statistics.median,
                                                            mean=mean))
    monkeypatch.setattr(sys, "argv", ["preflight.py", str(path)])
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        preflight_py.main()
    (spreads, input_div), = means
    return spreads, input_div, out.getvalue()


def report_figure(pattern: str, report: str, default=None):
    found = re.search(pattern, report)
    return found.groups() if found else default


def assert_measures_equal(oracle, path, monkeypatch) -> None:
    validate_py, preflight_py = oracle
    spreads, input_div, report = run_preflight(preflight_py, path, monkeypatch)
    raw = json.loads(path.read_text())["scenarios"]
    scenarios = [Scenario.from_json(obj) for obj in raw]
    ours = preflight(scenarios)
    assert list(ours.spreads) == list(INPUT_DIV_FACTORS)
    assert list(ours.spreads.values()) == pytest.approx(spreads, abs=TOLERANCE, rel=0)
    assert ours.input_div == pytest.approx(input_div, abs=TOLERANCE, rel=0)
    assert (str(ours.tight), str(ours.wide)) == report_figure(r"tight \(<= 4.5 m\)\s+(\d+) scenarios\n"
                                                              r"\s+wide\s+\(>\s+4.5 m\)\s+(\d+) scenarios", report)
    for obj, s in zip(raw, scenarios):
        assert band(s) is (Band.TIGHT if float(obj["corridor"]) <= preflight_py.BAND_CUT else Band.WIDE)
        theirs = preflight_py.nearest_to_route(obj)
        assert (nearest_pole_to_route(s) is None) == (theirs is None)
        assert theirs is None or nearest_pole_to_route(s) == pytest.approx(theirs, abs=TOLERANCE, rel=0)
        width = validate_py.check_navigable(s.id, obj["obstacle"]["xy"], obj["patrol"], obj["corridor"],
                                            obj["obstacle"]["radius"])
        assert (free_lateral_width(s) is None) == (width is None)
        assert width is None or free_lateral_width(s) == pytest.approx(width, abs=TOLERANCE, rel=0)
    if ours.tightest:
        width, sid = report_figure(r"tightest free lateral width: (\d+\.\d\d) m in (\S+) ", report)
        assert (f"{ours.tightest[0]:.2f}", ours.tightest[1]) == (width, sid)
    assert str(ours.blocked) == report_figure(r"lane fully blocked:\s+(\d+) of", report, ("0",))[0]
    assert str(ours.without_poles) == report_figure(r"(\d+) scenarios place no obstacle", report, ("0",))[0]


@pytest.mark.parametrize("generator", GENERATED, ids=lambda g: f"{g[0]}-{g[1]}")
def test_the_measures_of_a_generated_submission_are_preflight_pys(generator, generated, oracle, monkeypatch):
    assert_measures_equal(oracle, generated[generator], monkeypatch)


def test_the_measures_of_the_manifests_and_flights_scenarios_are_preflight_pys(oracle, monkeypatch, tmp_path):
    records = {r.scenario.id: r for r in read_train_manifest(MANIFEST)}
    flown = [read_flight(p) for p in FLIGHTS]
    flown = [f.scenario(records[f.id].scenario.seed, records[f.id].scenario.obstacle.height).to_json() for f in flown]
    everything = manifest_scenarios()
    path = tmp_path / "scenarios.json"
    for group in [flown] + [everything[k:k + 20] for k in range(0, len(everything), 20)] + [everything]:
        path.write_text(json.dumps({"submission": "manifest", "scenarios": group}))
        assert_measures_equal(oracle, path, monkeypatch)


def test_the_measures_reach_both_bands_blocked_lanes_and_scenarios_without_poles(kit, generated):
    """The comparisons above are not empty: the manifest has both bands, blocked lanes and lanes without poles."""
    everything = preflight([Scenario.from_json(obj) for obj in manifest_scenarios()])
    assert everything.tight == 153 and everything.wide == 98  # of 251 scenarios, as preflight.py counts them above
    assert everything.blocked == 3 and everything.without_poles == 37 and len(everything.free_width) == 214
    svm = preflight(read_submission(generated[("svm_generator", 7)]).scenarios)
    assert svm.wide == 0 and svm.blocked == 2 and svm.tightest[1] == "s000"


def test_a_single_scenario_has_no_spread():
    one = [Scenario.from_json(manifest_scenarios()[0])]
    assert factor_spread(one, "wind") is None and preflight(one).input_div == 0.0 and not preflight(one).spreads


def test_the_widest_gap_between_shadows():
    assert widest_gap([], 0.5) == 1.0
    assert widest_gap([(-0.1, 0.1)], 0.5) == pytest.approx(0.4)
    assert widest_gap([(-0.6, 0.2), (0.1, 0.3)], 0.5) == pytest.approx(0.2)
    assert widest_gap([(-0.6, 0.6)], 0.5) == 0.0
