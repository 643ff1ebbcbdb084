"""Greedy vs greedy with pre-screening: simulations needed to reach greedy's final fitness, and held-out accuracy.

    python benchmarks/bench_surrogates.py search --problem rq1-seed1 --repetitions 10 --mode pretrained --lowfi
    python benchmarks/bench_surrogates.py accuracy --problem rq1-seed1 [--lowfi] [--also rq1-seed2]

``search``: greedy alone is repetition N of ``benchmarks/reproduce_paper.py`` (budget 100 (RQ2: 50), 5 runs (RQ2:
10), random seed N, authors' preset (RQ2: paper preset)), read from ``results/paper/<problem>-rep<N>`` (flown there
first if missing). The pre-screened greedy runs with the same settings; ``pretrained`` starts from an ensemble
trained on the OTHER repetitions' stores (never on repetition N) and retrains every 10 evaluations, ``online`` starts
without a model. ``--rule`` picks the screening rule (default ``auto``: the low-fidelity incumbent rule with its
margin calibrated on the training stores when the model has low-fidelity features, else EI). Its store starts as a
copy of repetition N's, so a test greedy alone already simulated is read back instead of flown again (the simulation
is deterministic given test and seed, so the numbers are the same; the env still counts it as an evaluation).
``--lowfi`` adds the low-fidelity flight outcomes to the features (multi-fidelity surrogate); the low-fidelity
flights flown during a search are part of its wall time. Each search is one cached repetition
(``search.repetitions``) in ``results/surrogates/``.

Two measures, each with the Mann-Whitney/ANOVA p-value and A12, then the final fitness of both:
* simulations until the best fitness reaches greedy alone's final fitness of the same repetition (a run that
  never reaches it counts all its simulations: censored, which favours the run that stopped early);
* simulations until the best fitness reaches a common level, greedy alone's mean final fitness, for both agents
  alike (censored the same way).
Both are printed again strictly censored: a run that never gets there counts the whole budget's simulations
(budget x runs = 500), as if it needed at least the budget. ``--verify-stop`` runs the pre-screened greedy
with ``PrescreenConfig.verify_stop`` (an early stop checked by an unscreened restart from the best).

``search --from-rep 10`` runs repetitions 10.. with models trained on repetitions 0-9: a confirmation on
repetitions no setting was chosen with (``--from-rep 20``: repetitions 20.., models trained on 0-19; with
``--repetitions 30`` repetitions 20-49 pooled, each set of 10 printed as well).

``--common-noise`` reads greedy alone from ``results/paper-crn`` (``reproduce_paper.py --common-noise``) and flies
the pre-screened greedy with the same common random numbers (run i of every test under the same noise,
``SimConfig.common_noise``); results go to ``results/surrogates-crn``.

``accuracy``: leave-one-repetition-out over the 10 stores of the problem: for each repetition, a model trained on
the other nine predicts it; printed are the Spearman rank correlation per held-out repetition, their mean, and the
Spearman of all out-of-fold predictions pooled.
"""
from __future__ import annotations

import argparse
import json
import shutil
import time
import warnings
from pathlib import Path

import numpy as np
from reproduce_paper import paper_agent, paper_env, run_one

import surrealist_gym as sg
from search.metrics import SearchMetrics
from search.repetitions import run_repetition
from search.statistics import compare, vargha_delaney_a12
from surrealist_gym.cli.options import race_stages
from surrogates.config import RULES, PrescreenConfig, SkipAccounting
from surrogates.dataset import Featurizer, load_dataset
from surrogates.models import evaluate_model, train_model
from surrogates.prescreened import Prescreened

PROBLEMS = ["rq1-seed1", "rq1-seed2", "rq2"]
BUDGET_SIMULATIONS = 500  # budget x runs of every paper problem (100 x 5, 50 x 10): strict censoring


def _paper(args) -> Path:
    """Greedy alone's folder (reproduce_paper.py's --out)."""
    return Path("results/paper-crn" if args.common_noise else "results/paper")


def _stores(paper: Path, problem: str, reps) -> list[Path]:
    return [paper / f"{problem}-rep{r}.sqlite" for r in reps if (paper / f"{problem}-rep{r}.sqlite").is_file()]


def _featurizer(problem: str, lowfi: bool) -> Featurizer:
    """The problem's featurizer; one per command, so its low-fidelity flights are cached across repetitions."""
    if problem == "rq2":
        return Featurizer.for_problem("generate", lowfi=lowfi)
    return Featurizer.for_problem("replicate", sg.data_path(f"{problem}.yaml"), lowfi=lowfi)


def _label(args) -> str:
    """The file stem of a pre-screened search's settings (skips are told as evaluations: "counted")."""
    rule = f"{args.rule}{args.threshold:g}" if args.rule in ("ei", "pi") else f"{args.rule}-miss{args.miss_rate:g}"
    parts = [args.mode, "lowfi" * args.lowfi, f"also-{args.also}" if args.also else "", rule, "counted",
             f"race{'-'.join(map(str, args.first_runs))}" if args.first_runs else "",
             f"vs-{args.race_against}" if args.race_against else "",
             "spend" * args.skips_spend_budget, "verify" * args.verify_stop,
             f"train{args.from_rep}" if args.from_rep > 10 else ""]  # models trained on repetitions 0..FROM_REP-1
    return "-".join(part for part in parts if part)


def prescreened(args, rep: int, featurizer: Featurizer) -> SearchMetrics:
    """Repetition ``rep`` of the pre-screened greedy (cached in OUT/<problem>-<label>-rep<N>)."""
    paper, training = _paper(args), max(args.from_rep, 10)
    config = PrescreenConfig.of(rule=args.rule, threshold=args.threshold, miss_rate=args.miss_rate, min_points=10,
                                retrain_every=10, lowfi=args.lowfi, first_runs=args.first_runs,
                                race_against=args.race_against,
                                skips=SkipAccounting.BUDGET if args.skips_spend_budget else SkipAccounting.EVALUATION,
                                verify_stop=args.verify_stop)

    def make_env(store: Path):
        if not store.is_file():  # greedy alone's evaluations, read back instead of flown again
            shutil.copy(paper / f"{args.problem}-rep{rep}.sqlite", store)
        return paper_env(args.problem, rep, store, args.common_noise, executor="inline")

    def make_agent() -> Prescreened:
        model = "online"
        if args.mode == "pretrained":
            others = _stores(paper, args.problem, [r for r in range(training) if r != rep])
            others += _stores(paper, args.also, range(training)) if args.also else []
            model = train_model(load_dataset(others, featurizer), featurizer, seed=rep)
        return Prescreened(paper_agent(args.problem), model, config, seed=rep)

    return run_repetition(Path(args.out) / f"{args.problem}-{_label(args)}-rep{rep}", make_env, make_agent,
                          rep).metrics


def simulations_to_reach(search: SearchMetrics, level: float) -> tuple[int, bool]:
    """Simulations until the best fitness first reaches ``level``; (all simulations, False) if it never does."""
    reach = next((s for _, s, best in search.trace if best >= level), None)
    return (search.simulations, False) if reach is None else (reach, True)


def search(args) -> None:
    reps = range(args.from_rep, args.from_rep + args.repetitions)
    greedy = [run_one(args.problem, rep, _paper(args), 1, args.common_noise) for rep in reps]
    target = float(np.mean([g.best_fitness for g in greedy]))  # the common level: greedy alone's mean final fitness
    featurizer = _featurizer(args.problem, args.lowfi)
    rows = []
    for rep, g in zip(reps, greedy):
        p = prescreened(args, rep, featurizer)
        g_own, _ = simulations_to_reach(g, g.best_fitness)
        p_own, reached = simulations_to_reach(p, g.best_fitness)
        g_common, g_hit = simulations_to_reach(g, target)
        p_common, p_hit = simulations_to_reach(p, target)
        row = {"rep": rep, "greedy_final": g.best_fitness, "greedy_sims": g_own, "pre_final": p.best_fitness,
               "pre_sims_to_reach": p_own, "reached": reached, "greedy_sims_to_target": g_common,
               "greedy_hit_target": g_hit, "pre_sims_to_target": p_common, "pre_hit_target": p_hit,
               "pre_sims_to_reach_strict": p_own if reached else BUDGET_SIMULATIONS,
               "greedy_sims_to_target_strict": g_common if g_hit else BUDGET_SIMULATIONS,
               "pre_sims_to_target_strict": p_common if p_hit else BUDGET_SIMULATIONS,
               "pre_evaluations": p.evaluations, "wall_s": p.wall_seconds}
        rows.append(row)
        print(json.dumps(row), flush=True)
    _summary(args, rows, target)


def _summary(args, rows, target: float) -> None:
    n = len(rows)
    racing = f"on the first {','.join(map(str, args.first_runs))} runs" if args.first_runs else "off"
    print(f"\n{args.problem}, {args.mode}{' + lowfi' if args.lowfi else ''}, rule {args.rule}, racing {racing}"
          f"{', skips spend budget' if args.skips_spend_budget else ''}, {n} repetitions")
    for label, gk, pk, hits in (
            ("simulations to reach greedy's final fitness of the same repetition", "greedy_sims", "pre_sims_to_reach",
             f"pre-screened reached it in {sum(r['reached'] for r in rows)}/{n}"),
            (f"simulations to reach greedy alone's mean final fitness ({target:.2f})", "greedy_sims_to_target",
             "pre_sims_to_target", f"reached by greedy in {sum(r['greedy_hit_target'] for r in rows)}/{n}, by "
             f"pre-screened in {sum(r['pre_hit_target'] for r in rows)}/{n}"),
            ("strict (never reached = the whole budget's simulations): to greedy's own final", "greedy_sims",
             "pre_sims_to_reach_strict", ""),
            ("strict: to the common level", "greedy_sims_to_target_strict", "pre_sims_to_target_strict", "")):
        gs, ps = [r[gk] for r in rows], [r[pk] for r in rows]
        print(f"{label}: greedy {np.mean(gs):.0f}, pre-screened {np.mean(ps):.0f} "
              f"({1 - np.mean(ps) / np.mean(gs):.0%} fewer)" + (f"; {hits}" if hits else ""))
        if n >= 3:
            p, test = compare(gs, ps)
            print(f"  p = {p:.3g} ({test}), A12(greedy needs more) = {vargha_delaney_a12(gs, ps):.2f}")
    if n > 10:  # a long run: each set of 10 repetitions too, as a 10-repetition run would print it
        for block in range(0, n, 10):
            part = rows[block:block + 10]
            gs, ps = [r["greedy_sims"] for r in part], [r["pre_sims_to_reach"] for r in part]
            strict = 1 - np.mean([r["pre_sims_to_reach_strict"] for r in part]) / np.mean(gs)
            p, test = compare(gs, ps)
            print(f"  repetitions {part[0]['rep']}-{part[-1]['rep']}: to greedy's own final: greedy {np.mean(gs):.0f}, "
                  f"pre-screened {np.mean(ps):.0f} ({1 - np.mean(ps) / np.mean(gs):.0%} fewer), reached "
                  f"{sum(r['reached'] for r in part)}/{len(part)}; p = {p:.3g} ({test}), A12 = "
                  f"{vargha_delaney_a12(gs, ps):.2f}; strict {strict:.0%} fewer")
    gf, pf = [r["greedy_final"] for r in rows], [r["pre_final"] for r in rows]
    if n >= 3:
        p, test = compare(pf, gf)
        print(f"final fitness: greedy {np.mean(gf):.2f}, pre-screened {np.mean(pf):.2f}; p = {p:.3g} ({test}), "
              f"A12(pre-screened fitter) = {vargha_delaney_a12(pf, gf):.2f}")


def accuracy(args) -> None:
    from scipy.stats import spearmanr

    featurizer = _featurizer(args.problem, args.lowfi)
    stores = _stores(_paper(args), args.problem, range(10))
    start = time.perf_counter()
    data = load_dataset(stores, featurizer)
    extra = load_dataset(_stores(_paper(args), args.also, range(10)), featurizer) if args.also else None
    print(f"{args.problem}: {len(data)} evaluations, {data.X.shape[1]} features"
          f"{f', plus {len(extra)} evaluations of {args.also} in every training set' if extra else ''}, featurized "
          f"in {time.perf_counter() - start:.1f} s", flush=True)
    y = data.targets["fitness"]
    for kind in ("ensemble", "knn"):
        rhos, pooled = [], np.full(len(data), np.nan)
        for fold in range(min(args.folds, len(stores))):
            held = np.isin(data.groups, [len(stores) - 1 - fold])
            train = data.subset(~held) if extra is None else data.subset(~held).concat(extra)
            model = train_model(train, featurizer, kind, seed=fold)
            m = evaluate_model(model, data.subset(held))
            pooled[held] = model.predict_fitness(data.X[held])
            rhos.append(m["spearman"])
            print(kind, f"held-out {stores[len(stores) - 1 - fold].name}:", {k: round(v, 3) for k, v in m.items()},
                  flush=True)
        ok = np.isfinite(pooled) & np.isfinite(y)
        print(f"{kind}: mean held-out Spearman {np.mean(rhos):.3f} (per repetition, {len(rhos)} folds); "
              f"pooled out-of-fold Spearman {spearmanr(pooled[ok], y[ok]).statistic:.3f} ({ok.sum()} evaluations)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=["search", "accuracy"])
    parser.add_argument("--problem", default="rq1-seed1", choices=PROBLEMS)
    parser.add_argument("--repetitions", type=int, default=10)
    parser.add_argument("--from-rep", type=int, default=0,
                        help="search: run repetitions FROM_REP.. (models train on repetitions 0..max(FROM_REP, 10)-1 "
                             "other than the one run; --from-rep 10 or 20 is a held-out confirmation on new "
                             "repetitions)")
    parser.add_argument("--mode", default="pretrained", choices=["pretrained", "online"])
    parser.add_argument("--rule", default="auto", choices=RULES,
                        help="screening rule (default auto: lowfi with a calibrated margin, else ei)")
    parser.add_argument("--threshold", type=float, default=0.01, help="ei/pi threshold (default 0.01)")
    parser.add_argument("--miss-rate", type=float, default=0.02,
                        help="lowfi: share of past improvements the calibrated margin may miss (default 0.02)")
    parser.add_argument("--skips-spend-budget", action="store_true",
                        help="the greedy's budget counts skipped and dropped candidates as whole evaluations, so it "
                             "plans and stops as greedy alone (SkipAccounting.BUDGET)")
    parser.add_argument("--verify-stop", action="store_true",
                        help="when the inner greedy stops with budget left, restart it unscreened from the best")
    parser.add_argument("--first-runs", type=lambda text: tuple(race_stages(text)), default=(),
                        help="racing: fly this many runs of a candidate first, the rest only if they do not fall "
                             "short; K1,K2,... races in stages")
    parser.add_argument("--race-against", choices=["paired", "fitness"], default=None,
                        help="racing: the incumbent's same first runs (paired) or its fitness over all runs (fitness); "
                             "default: paired under --common-noise, else fitness")
    parser.add_argument("--folds", type=int, default=10, help="accuracy: held-out repetitions, one per fold")
    parser.add_argument("--lowfi", action="store_true", help="multi-fidelity features (a low-fidelity flight)")
    parser.add_argument("--also", default=None, choices=PROBLEMS[:2],
                        help="add every store of this problem (same flight and mission) to each training set")
    parser.add_argument("--common-noise", action="store_true",
                        help="common random numbers: greedy alone from results/paper-crn, the same noise for the "
                             "pre-screened greedy")
    parser.add_argument("--out", default=None,
                        help="default results/surrogates (--common-noise: results/surrogates-crn)")
    args = parser.parse_args()
    args.out = args.out or ("results/surrogates-crn" if args.common_noise else "results/surrogates")
    if args.also == args.problem:
        parser.error("--also must name the OTHER seed (the held-out repetition would leak into training)")
    warnings.simplefilter("ignore")
    {"search": search, "accuracy": accuracy}[args.what](args)


if __name__ == "__main__":
    main()
