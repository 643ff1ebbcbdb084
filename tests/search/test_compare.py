"""A tiny comparison (2 agents x 2 repetitions) writes its reports; running it again simulates nothing."""
import csv
import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from search.compare import compare, convergence_curves
from surrealist_gym.cli import main
from surrealist_gym.errors import SurrealistError, UnknownAgent

SETTINGS = dict(repetitions=2, budget=3, runs=1, executor="inline")


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    out = tmp_path_factory.mktemp("compare")
    events = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = compare("Surrealist-Generate-v0", ["greedy", "random"], out=out, progress=events.append,
                         **SETTINGS)
    return out, result, events


def test_reports_are_written(compared):
    out, result, events = compared
    for name in ("compare.md", "compare.csv", "pairwise.csv", "searches.csv", "convergence.png", "compare.json"):
        assert (out / name).is_file(), name
    assert len(result.searches) == 4 and result.new_simulations > 0
    rows = list(csv.DictReader(open(out / "compare.csv")))
    assert [r["agent"] for r in rows] == ["greedy", "random"]
    assert {"best_fitness_mean", "simulations_to_best_mean", "crash_rate_mean", "unsafe_rate_mean"} <= set(rows[0])
    pairs = list(csv.DictReader(open(out / "pairwise.csv")))
    assert len(pairs) == 1 and 0.0 <= float(pairs[0]["best_fitness_a12"]) <= 1.0
    assert pairs[0]["best_fitness_test"] == "n/a"  # two repetitions: too few for a significance test
    md = (out / "compare.md").read_text()
    assert "| greedy | 2 |" in md and "| greedy | random |" in md
    assert sum(e["done"] for e in events) == 4
    for record in result.searches:
        m = record.metrics
        assert m.evaluations == 3 and m.best_fitness >= m.seed_fitness
        assert m.trace[0][:2] == (1, 1) and m.trace[-1][1] == m.simulations


def test_same_problems_for_every_agent(compared):
    _, result, _ = compared
    by_rep = {}
    for record in result.searches:
        by_rep.setdefault(record.repetition, set()).add(record.metrics.seed_fitness)
    assert all(len(seeds) == 1 for seeds in by_rep.values())  # repetition r: the same seed evaluation


def test_resume_does_no_new_simulations(compared):
    out, first, _ = compared
    again = compare("Surrealist-Generate-v0", ["greedy", "random"], out=out, **SETTINGS)
    assert again.new_simulations == 0
    assert [s.metrics for s in again.searches] == [s.metrics for s in first.searches]


def test_interrupted_search_replays_from_its_store(compared, tmp_path):
    out, first, _ = compared
    copy = tmp_path / "copy"
    copy.mkdir()
    (copy / "compare.json").write_text((out / "compare.json").read_text())
    (copy / "searches").mkdir()
    sqlite = out / "searches" / "random-rep1.sqlite"
    (copy / "searches" / sqlite.name).write_bytes(sqlite.read_bytes())  # evaluations stored, no finished JSON
    again = compare("Surrealist-Generate-v0", ["random"], out=copy, **{**SETTINGS, "repetitions": 2})
    replayed = again.searches[1]
    assert replayed.new_simulations == 0 and replayed.metrics.trace == next(
        s.metrics.trace for s in first.searches if s.agent == "random" and s.repetition == 1)


def test_other_settings_in_the_same_folder_are_refused(compared):
    out, _, _ = compared
    with pytest.raises(SurrealistError, match="other settings"):
        compare("Surrealist-Generate-v0", ["greedy"], out=out, **{**SETTINGS, "budget": 4})
    with pytest.raises(UnknownAgent):
        compare("Surrealist-Generate-v0", ["greedy", "nope"], out=out, **SETTINGS)


def test_convergence_curves_are_monotone(compared):
    _, result, _ = compared
    grid, curves = convergence_curves(result.searches, "greedy")
    assert curves.shape == (2, grid.size) and np.isnan(curves[:, 0]).all()
    assert np.all(np.diff(curves[:, 1:], axis=1) >= 0)


def test_cli_compare(tmp_path, capsys):
    out = tmp_path / "cli"
    args = ["compare", "--env", "Surrealist-Generate-v0", "--agents", "random,cmaes", "--repetitions", "1",
            "--budget", "2", "--runs", "1", "--inline", "--out", str(out)]
    assert main(args) == 0
    printed = capsys.readouterr().out
    assert "| random | 1 |" in printed and "results in" in printed
    assert json.loads((out / "compare.json").read_text())["budget"] == 2
    assert main(args) == 0 and "(0 new simulations)" in capsys.readouterr().out
    assert main(args[:4] + ["random,grredy"] + args[5:]) == 2
    assert "did you mean 'greedy'" in capsys.readouterr().err


def test_agent_names_with_dots_keep_one_store_per_repetition():
    from search.compare import _slug

    stem = Path("searches") / f"{_slug('ppo:results/policies/ppo-replicate.zip')}-rep3"
    assert stem.with_suffix(".sqlite").name.endswith("-rep3.sqlite")


def _searches(out: Path) -> list[dict]:
    """searches.csv without its timings."""
    with open(out / "searches.csv", newline="") as f:
        return [{k: v for k, v in row.items() if "seconds" not in k and "wall" not in k} for row in csv.DictReader(f)]


def test_a_compare_killed_mid_run_resumes_with_the_same_out(tmp_path, capsys):
    """kill -9 of ``surrealist compare`` while it flies: the evaluations stored are kept, the killed run's lock does
    not stand in the way, and the same command gives the searches of an uninterrupted comparison."""
    from surrealist_gym.results import ResultsFolder
    from tests.conftest import killed_and_resumed

    def argv(out):
        return ["compare", "--env", "Surrealist-Generate-v0", "--agents", "random", "--repetitions", "2",
                "--budget", "4", "--runs", "1", "--inline", "--out", str(out)]

    def new_simulations() -> int:
        return int(capsys.readouterr().out.rsplit("searches (", 1)[1].split(" new simulations")[0])

    full = tmp_path / "full"
    assert main(argv(full)) == 0
    flown = new_simulations()
    out = tmp_path / "killed"
    stored = ResultsFolder(out, "compare", stores=(("searches/*.sqlite", "evaluations"),)).stored
    killed_and_resumed(argv(out), out, stored, at_least=2)
    kept = stored()
    assert kept >= 2 and not (out / "searches.csv").exists()
    assert main(argv(out)) == 0
    assert new_simulations() == flown - kept  # 1 run per evaluation: only those not stored are flown
    assert _searches(out) == _searches(full)
