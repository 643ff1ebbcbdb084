"""Greedy vs greedy with pre-screening: simulations needed to reach greedy's final fitness, and held-out accuracy.

    python benchmarks/bench_surrogates.py search --problem rq1-seed1 --repetitions 10 --mode pretrained --lowfi
    python benchmarks/bench_surrogates.py accuracy --problem rq1-seed1 [--lowfi]
    python benchmarks/bench_surrogates.py race-replay --problem rq2
    python benchmarks/bench_surrogates.py fresh --problem rq2 --common-noise --lowfi --first-runs 1 [--verify-stop]
    python benchmarks/bench_surrogates.py transfer --problem rq1-seed1 --common-noise
    python benchmarks/bench_surrogates.py plateau --problem rq1-seed1 --common-noise --from-rep 30
    python benchmarks/bench_surrogates.py path --problem rq1-seed1 --common-noise --rule none --first-runs 1,2,3,4 \
        --skips-spend-budget --verify-stop --from-rep 30 --repetitions 10

``search``: greedy alone is read from ``results/paper/<problem>-rep<N>.sqlite`` (benchmarks/reproduce_paper.py:
budget 100 (RQ2: 50), 5 runs (RQ2: 10), random seed N, authors' preset (RQ2: paper preset)). The pre-screened
greedy runs with the same settings; ``pretrained`` starts from an ensemble trained on the OTHER repetitions'
stores (never on repetition N) and retrains every 10 evaluations, ``online`` starts without a model. ``--rule``
picks the screening rule (default ``auto``: the low-fidelity incumbent rule with its margin calibrated on the
training stores when the model has low-fidelity features, else EI). Its store starts as a copy of repetition N's,
so a test greedy alone already simulated is read back instead of flown again (the simulation is deterministic
given test and seed, so the numbers are the same; the env still counts it as an evaluation). Simulations =
evaluations x runs. ``--lowfi`` adds the low-fidelity flight outcomes to the features (multi-fidelity
surrogate); the low-fidelity flights flown during each search are counted (those made while building the
training set are not) and their time is part of the search's wall time.

Two measures, each with the Mann-Whitney/ANOVA p-value and A12, then the final fitness of both:
* simulations until the best fitness reaches greedy alone's final fitness of the same repetition (a run that
  never reaches it counts all its simulations: censored, which favours the run that stopped early);
* simulations until the best fitness reaches a common level, greedy alone's mean final fitness, for both agents
  alike (censored the same way).
Both are printed again strictly censored: a run that never gets there counts the whole budget's simulations
(budget x runs = 500), as if it needed at least the budget. ``--verify-stop`` runs the pre-screened greedy
with ``PrescreenConfig.verify_stop`` (an early stop checked by an unscreened restart from the best).

``search --from-rep 10`` runs repetitions 10.. (``reproduce_paper.py --repetitions 20``) with models trained on
repetitions 0-9: a confirmation on repetitions no setting was chosen with (``--from-rep 20``: repetitions 20..,
models trained on 0-19; with ``--repetitions 30`` repetitions 20-49 pooled, each set of 10 printed as well).

``--common-noise`` runs every command on the stores of ``reproduce_paper.py --common-noise --out
results/paper-crn`` and flies the pre-screened greedy with the same common random numbers (run i of every test
under the same noise, ``SimConfig.common_noise``); results go to ``results/surrogates-crn``.

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

import surrealist_gym as sg
from search import AdaptiveGreedy
from surrealist_gym.envs.generate import GenerateEnv
from surrealist_gym.cli.options import race_stages
from surrealist_gym.envs.replicate import ReplicateEnv
from surrealist_gym.sim import SimConfig
from surrealist_gym.statistics import compare, vargha_delaney_a12
from surrealist_gym.store import EvaluationStore
from surrogates.config import RULES, SkipAccounting
from surrogates.dataset import Featurizer, load_dataset, stack_rows
from surrogates.models import evaluate_model, train_model
from surrogates.prescreen import PrescreenConfig, Prescreened
from surrogates.racing import race_verdict

PAPER = Path("results/paper")  # greedy alone's stores (--common-noise: results/paper-crn)
SIM_CONFIG = SimConfig()


def _stores(problem: str, reps) -> list[Path]:
    return [PAPER / f"{problem}-rep{r}.sqlite" for r in reps if (PAPER / f"{problem}-rep{r}.sqlite").is_file()]


_FEATURIZERS: dict = {}


def _featurizer(problem: str, lowfi: bool = False) -> Featurizer:
    """One featurizer per problem and kind, so the low-fidelity flights are cached across repetitions."""
    if (problem, lowfi) not in _FEATURIZERS:
        _FEATURIZERS[problem, lowfi] = Featurizer.for_problem(
            "generate" if problem == "rq2" else "replicate", None if problem == "rq2" else
            sg.data_path(f"{problem}.yaml"), lowfi=lowfi)
    return _FEATURIZERS[problem, lowfi]


def _lowfi_runs(featurizer) -> int:
    return featurizer.lowfi.runs if featurizer.lowfi is not None else 0


def greedy_alone(problem: str, rep: int) -> dict:
    """Greedy's curve from its store: (simulations, best fitness so far) after each evaluation."""
    with EvaluationStore(PAPER / f"{problem}-rep{rep}.sqlite") as store:
        fit, runs = zip(*[(-np.inf if e.fitness is None else e.fitness, len(e.runs)) for e in store])
    best, sims = np.maximum.accumulate(fit), np.cumsum(runs)
    return {"final": float(best[-1]), "simulations": int(sims[-1]),
            "curve": [(int(n), float(b)) for n, b in zip(sims, best)]}


def simulations_to_reach(curve, level: float, simulations: int) -> tuple[int, bool]:
    """Simulations until the best fitness first reaches ``level``; (all simulations, False) if it never does."""
    reach = [n for n, best in curve if best is not None and best >= level]
    return (reach[0], True) if reach else (simulations, False)


def _rule_label(rule: str, threshold: float, miss_rate: float) -> str:
    return f"{rule}{threshold:g}" if rule in ("ei", "pi") else f"{rule}-miss{miss_rate:g}"


def _paper_env(problem: str, random_seed: int, store=None, sim_config=None):
    """The env of greedy alone's runs in reproduce_paper.py (RQ2: budget 50, 10 runs; case0: budget 100, 5 runs),
    simulating in this process."""
    if problem == "rq2":
        return GenerateEnv(budget=50, runs=10, store=store, random_seed=random_seed, executor="inline",
                           sim_config=sim_config)
    return ReplicateEnv(seed_test=sg.data_path(f"{problem}.yaml"), budget=100, runs=5, store=store,
                        random_seed=random_seed, executor="inline", sim_config=sim_config)


def _stages_label(first_runs: tuple[int, ...]) -> str:
    return "-".join(map(str, first_runs))


def _search_label(mode, lowfi, also, rule, threshold, miss_rate, counted, first_runs, verify_stop,
                  spend: bool = False) -> str:
    return ((f"{mode}-lowfi" if lowfi else mode) + (f"-also-{also}" if also else "")
            + f"-{_rule_label(rule, threshold, miss_rate)}" + ("-counted" if counted else "")
            + (f"-race{_stages_label(first_runs)}" if first_runs else "") + ("-spend" if spend else "")
            + ("-verify" if verify_stop else ""))


def prescreened(problem: str, rep: int, mode: str, out: Path, reps: int, lowfi: bool = False,
                also: str | None = None, rule: str = "auto", threshold: float = 0.01, miss_rate: float = 0.02,
                counted: bool = True, first_runs: tuple[int, ...] = (), verify_stop: bool = False,
                spend: bool = False) -> dict:
    label = _search_label(mode, lowfi, also, rule, threshold, miss_rate, counted, first_runs, verify_stop, spend)
    label += f"-train{reps}" if reps != 10 else ""  # models trained on repetitions 0..reps-1
    cached = out / f"{problem}-{label}-rep{rep}.json"
    if cached.is_file():
        return json.loads(cached.read_text())
    store = out / f"{problem}-{label}-rep{rep}.sqlite"
    config = PrescreenConfig(rule=rule, threshold=threshold, miss_rate=miss_rate, min_points=10, retrain_every=10,
                             lowfi=lowfi, skips=_skips(counted, spend), first_runs=first_runs,
                             verify_stop=verify_stop)
    env, agent, featurizer = _screened_search(problem, rep, mode, store, reps, config, also)
    curve: list[float] = []
    lowfi_before = _lowfi_runs(featurizer)  # an online model featurizes with a featurizer of its own
    start = time.perf_counter()
    result = agent.run(env, seed=rep, callback=lambda info: curve.append(
        (info["simulations"], info["best_fitness"])))
    row = {"final": result.best_fitness, "evaluations": result.evaluations,
           "to_best": result.evaluations_to_best, "skipped": len(agent.skipped), "retrains": agent.retrains,
           "curve": curve, "new_simulations": env.unwrapped.evaluator.simulations,
           "simulations": env.unwrapped.simulations, "raced": agent.dropped,
           "wall_s": time.perf_counter() - start, "stop": result.stop_reason,
           "lowfi_runs": _lowfi_runs(agent._featurizer) - (lowfi_before if agent._featurizer is featurizer else 0),
           "rule": agent.rule, "margin": agent.margin, "race_margin": agent.race_margin,
           "race_margins": list(agent.race_margins.values()),
           "verified_at": agent.verified_at, "budget_simulations": env.unwrapped.budget * env.unwrapped.evaluator.runs,
           "best_key": env.unwrapped.best.test.key()}
    env.close()
    cached.write_text(json.dumps(row))
    return row


def _skips(counted: bool, spend: bool) -> SkipAccounting:
    """The skip accounting of the benchmark's flags (--skips-as-memo, --skips-spend-budget)."""
    if spend and not counted:
        raise SystemExit("--skips-spend-budget needs skips told as evaluations (not --skips-as-memo)")
    return SkipAccounting.BUDGET if spend else SkipAccounting.EVALUATION if counted else SkipAccounting.MEMO


def _screened_search(problem: str, rep: int, mode: str, store: Path, reps: int, config: PrescreenConfig,
                     also: str | None = None):
    """The env (its store a copy of greedy alone's repetition ``rep``), the pre-screened greedy (its model trained
    on repetitions 0..reps-1 other than ``rep``, or online) and the featurizer of one benchmark search."""
    shutil.copy(PAPER / f"{problem}-rep{rep}.sqlite", store)
    featurizer = _featurizer(problem, config.lowfi)
    if mode == "pretrained":
        others = _stores(problem, [r for r in range(reps) if r != rep]) + (_stores(also, range(reps)) if also else [])
        model = train_model(load_dataset(others, featurizer), featurizer, seed=rep)
    else:
        model = "online"
    env = _paper_env(problem, rep, store, SIM_CONFIG)
    agent = Prescreened(AdaptiveGreedy("paper" if problem == "rq2" else "authors"), model, config, seed=rep)
    return env, agent, featurizer


def path(args) -> None:
    """Where a pre-screened search leaves greedy alone's path. Each repetition is flown again (the settings of
    ``search``, into a scratch store) while recording what the inner greedy is told before any verify pass; the
    tests it asks are compared, in order, with those greedy alone evaluated (memo answers aside). Printed: the
    first evaluation where they differ and what preceded it (one of greedy alone's improvements dropped or skipped,
    else a step after a pair of moves that did not improve), and the final fitness of both."""
    import tempfile

    config = PrescreenConfig(rule=args.rule, threshold=args.threshold, miss_rate=args.miss_rate, min_points=10,
                             retrain_every=10, lowfi=args.lowfi,
                             skips=_skips(not args.skips_as_memo, args.skips_spend_budget),
                             first_runs=args.first_runs, verify_stop=args.verify_stop)
    for rep in range(args.from_rep, args.from_rep + args.repetitions):
        with EvaluationStore(PAPER / f"{args.problem}-rep{rep}.sqlite") as store:
            seed, *alone = [(e.test_key, -np.inf if e.fitness is None else e.fitness) for e in store]
        with tempfile.TemporaryDirectory() as scratch:
            env, agent, _ = _screened_search(args.problem, rep, args.mode, Path(scratch) / "s.sqlite",
                                             max(args.from_rep, 10), config, args.also)
            told = []
            tell = agent.inner.tell

            def recording_tell(actions, fitnesses, infos, tell=tell, agent=agent, env=env):
                if agent.verified_at is None:
                    for info in infos:
                        if info.get("test") is not None and not info.get("memo") and not info.get("invalid"):
                            told.append((info["test"].key(), bool(info.get("skipped"))))
                return tell(actions, fitnesses, infos)

            agent.inner.tell = recording_tell
            result = agent.run(env, seed=rep)
            env.close()
        fitness = dict(alone)
        improvements, best = [], seed[1]
        for key, f in alone:
            if f > best:
                improvements.append(key)
                best = f
        missed = {s["test_key"]: s for s in agent.skipped}
        lost = [(n, missed[key]) for n, key in enumerate(improvements, 1) if key in missed]
        split = next((i for i, ((a, _), (b, _)) in enumerate(zip(alone, told)) if a != b), None)
        where = "never" if split is None else f"at greedy alone's evaluation {split + 1} of {len(alone)}"
        if lost:
            n, entry = lost[0]
            why = (f"its improvement {n} of {len(improvements)} was {entry['rule']}-"
                   f"{'dropped at stage ' + str(entry['first_runs']) if 'first_runs' in entry else 'skipped'}"
                   + (f" (shortfall {entry['race_shortfall']:.2f} over a margin of {entry['race_margin']:.2f})"
                      if entry.get("race_margin") is not None else ""))
        elif split is not None and split >= 2:
            pair = told[split - 2:split]
            why = (f"no improvement of it lost; the step before follows a pair of moves that did not improve "
                   f"({', '.join('dropped' if skipped else 'flown' for _, skipped in pair)}; true fitness "
                   f"{', '.join(format(fitness.get(key, np.nan), '.2f') for key, _ in pair)})")
        else:
            why = "no improvement of it lost"
        print(f"{args.problem} rep {rep}: leaves greedy alone's path {where}; {why}; final {result.best_fitness:.2f} "
              f"(greedy alone {best:.2f})", flush=True)


def search(args) -> None:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    reps = range(args.from_rep, args.from_rep + args.repetitions)
    greedy = [greedy_alone(args.problem, rep) for rep in reps]
    target = float(np.mean([g["final"] for g in greedy]))  # the common level: greedy alone's mean final fitness
    rows = []
    for rep, g in zip(reps, greedy):
        p = prescreened(args.problem, rep, args.mode, out, max(args.from_rep, 10), args.lowfi, args.also, args.rule,
                        args.threshold, args.miss_rate, not args.skips_as_memo, args.first_runs, args.verify_stop,
                        args.skips_spend_budget)
        full = p.get("budget_simulations", 500)  # strict censoring: a run that never gets there needs > budget
        g_own, _ = simulations_to_reach(g["curve"], g["final"], g["simulations"])
        p_own, reached = simulations_to_reach(p["curve"], g["final"], p["simulations"])
        g_common, g_hit = simulations_to_reach(g["curve"], target, g["simulations"])
        p_common, p_hit = simulations_to_reach(p["curve"], target, p["simulations"])
        row = {"rep": rep, "greedy_final": g["final"], "greedy_sims": g_own, "pre_final": p["final"],
               "pre_sims_to_reach": p_own, "reached": reached, "greedy_sims_to_target": g_common,
               "greedy_hit_target": g_hit, "pre_sims_to_target": p_common, "pre_hit_target": p_hit,
               "pre_sims_to_reach_strict": p_own if reached else full,
               "greedy_sims_to_target_strict": g_common if g_hit else full,
               "pre_sims_to_target_strict": p_common if p_hit else full, "verified_at": p.get("verified_at"),
               "pre_evaluations": p["evaluations"], "skipped": p["skipped"], "raced": p["raced"],
               "wall_s": p["wall_s"], "new_simulations": p["new_simulations"], "lowfi_runs": p.get("lowfi_runs", 0),
               "rule": p.get("rule"), "margin": p.get("margin"), "race_margin": p.get("race_margin"),
               "race_margins": p.get("race_margins")}
        rows.append(row)
        print(json.dumps(row), flush=True)
    _summary(args, rows, target)


def _summary(args, rows, target: float) -> None:
    n = len(rows)
    skips = "skips told as memo" if args.skips_as_memo else "agent counts skips"
    stages = [[np.nan if m is None else m for m in r["race_margins"]] for r in rows if r.get("race_margins")]
    margins = (np.nanmean(np.array(stages, dtype=float), axis=0) if stages  # rows cached before race_margins
               else [np.nanmean([r["race_margin"] or np.nan for r in rows])])
    racing = (f"on the first {_stages_label(args.first_runs)} runs (margin {'/'.join(f'{m:.2f}' for m in margins)}, "
              f"dropped per search "
              f"{np.mean([r['raced'] for r in rows]):.0f})" if args.first_runs else "off")
    print(f"\n{args.problem}, {args.mode}{' + lowfi' if args.lowfi else ''}, rule "
          f"{_rule_label(args.rule, args.threshold, args.miss_rate)}, {skips} "
          f"(in force: {sorted({r['rule'] for r in rows})}, "
          f"margin {np.mean([r['margin'] or np.nan for r in rows]):.2f}), racing {racing}, "
          f"{n} repetitions; skipped per search {np.mean([r['skipped'] for r in rows]):.0f}, low-fidelity flights "
          f"per search {np.mean([r['lowfi_runs'] for r in rows]):.0f}")
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
    stores = _stores(args.problem, range(10))
    start = time.perf_counter()
    data = load_dataset(stores, featurizer)
    extra = load_dataset(_stores(args.also, range(10)), featurizer) if args.also else None
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


def _best_test(path: Path, row: dict | None = None):
    """The obstacles of a search's best test: the stored evaluation with the row's ``best_key``, else the first
    with the row's final fitness (rows cached before ``best_key`` was recorded; under common noise several tests can
    share it), or without a row the best of the store."""
    from surrealist_gym.testcase import _parse_obstacles

    with EvaluationStore(path) as store:
        rows = [e for e in store if e.fitness is not None]
    if row is None:
        best = max(rows, key=lambda e: e.fitness)
    elif row.get("best_key"):
        best = next(e for e in rows if e.test_key == row["best_key"])
    else:
        best = min(rows, key=lambda e: abs(e.fitness - row["final"]))
    return _parse_obstacles(best.test["obstacles"], str(path))


def fresh(args) -> None:
    """The best test of each search flown again under fresh noise (each test its own, base seed 1000 + repetition):
    greedy alone and pre-screened (the search of the given flags, from its cached store), and greedy alone from
    results/paper (each test's own noise) for reference. Tells whether what a search found holds up beyond the
    noise it was found under."""
    label = _search_label(args.mode, args.lowfi, args.also, args.rule, args.threshold, args.miss_rate,
                          not args.skips_as_memo, args.first_runs, args.verify_stop, args.skips_spend_budget)
    arms = {"greedy alone": [], "pre-screened": [], "greedy alone, own noise (results/paper)": []}
    for rep in range(args.repetitions):
        row = json.loads((Path(args.out) / f"{args.problem}-{label}-rep{rep}.json").read_text())
        tests = [_best_test(PAPER / f"{args.problem}-rep{rep}.sqlite"),
                 _best_test(Path(args.out) / f"{args.problem}-{label}-rep{rep}.sqlite", row),
                 _best_test(Path("results/paper") / f"{args.problem}-rep{rep}.sqlite")]
        env = _paper_env(args.problem, 1000 + rep)
        seed = env.unwrapped.seed_test
        for values, obstacles in zip(arms.values(), tests):
            values.append(env.unwrapped.evaluator.evaluate(seed.with_obstacles(obstacles)).fitness)
        env.close()
        print(f"rep {rep}: " + ", ".join(f"{name} {v[-1]:.2f}" for name, v in arms.items()), flush=True)
    pg, pp, po = [np.array(v) for v in arms.values()]
    print(f"\n{args.problem} ({label}{', common noise' if args.common_noise else ''}): fitness of the best tests "
          f"under fresh noise, mean over {args.repetitions} repetitions: " + ", ".join(
              f"{name} {np.mean(v):.2f}" for name, v in arms.items()))
    for name, other in (("greedy alone", pg), ("greedy alone with its own noise", po)):
        pv, test = compare(pp, other)
        print(f"  pre-screened vs {name}: p = {pv:.3g} ({test}), A12(pre-screened fitter) = "
              f"{vargha_delaney_a12(pp, other):.2f}")


def race_replay(args) -> None:
    """Racing replayed on greedy alone's stores: for each repetition, margins calibrated on the other repetitions
    (:func:`replay_margin` of the first-k fitness); a candidate is dropped when the incumbent's first-k fitness
    exceeds its own by more than the margin, or, under common noise, equals it (a tie,
    ``PrescreenConfig.drop_ties``). Printed per k, then for racing in stages 1..k (each stage at an equal share of
    the miss rate, as ``PrescreenConfig(first_runs=(1, ..., k))``): the share of simulations saved and of real
    improvements missed. An estimate only: a real search that drops a candidate walks on differently."""
    stores = _stores(args.problem, range(args.repetitions))
    searches = []
    for path in stores:
        with EvaluationStore(path) as store:
            rows = [(e.fitness, len(e.runs), ((e.info or {}).get("terms") or {}).get("first_runs_fitness"))
                    for e in store if e.fitness is not None]
        if any(first is None for *_, first in rows):
            raise SystemExit(f"{path}: evaluations without first_runs_fitness; rerun benchmarks/reproduce_paper.py")
        searches.append(rows)
    runs = max(n for rows in searches for _, n, _ in rows)
    print(f"{args.problem}: {len(searches)} stores, {sum(map(len, searches))} evaluations of {runs} runs; "
          f"margins at miss rate {args.miss_rate:g}, leave-one-repetition-out")
    for stages in [(k,) for k in range(1, runs)] + [tuple(range(1, k + 1)) for k in range(2, runs)]:
        saved, total, missed, improvements, ties, margins, reach = _replay_racing(searches, stages, args.miss_rate,
                                                                                  args.common_noise)
        if margins:
            label = f"first {stages[0]} runs" if len(stages) == 1 else f"stages 1..{stages[-1]}"
            kept = [r for r in reach if r[2]]
            print(f"{label}: margin {'/'.join(f'{m:.2f}' for m in np.mean(margins, axis=0))}, simulations saved "
                  f"{saved / total:.0%}, improvements missed {missed}/{improvements}; {ties} of the drops tied the "
                  f"incumbent; searches missing none {len(kept)}/{len(reach)}, to greedy's final "
                  f"{1 - sum(r[1] for r in reach) / sum(r[0] for r in reach):.0%} fewer (a search missing one "
                  f"counted at greedy's whole search)")


def transfer(args) -> None:
    """Do the screening margins hold on new repetitions? For the low-fidelity fitness and the first run's fitness,
    the margin calibrated on repetitions 0..R-1 (R = ``--repetitions``, 2% miss rate by default) and the share of
    real improvements of greedy alone on repetitions R..2R-1 whose shortfall exceeds it (in-sample on 0..R-1 for
    comparison), with the largest shortfall seen."""
    from surrogates.lowfi import FITNESS
    from surrogates.replay import improvement_shortfalls, replay_margin

    reps = args.repetitions
    featurizer = _featurizer(args.problem, lowfi=True)
    data = load_dataset(_stores(args.problem, range(2 * reps)), featurizer)
    if len(np.unique(data.groups)) < 2 * reps:
        raise SystemExit(f"{args.problem}: needs {2 * reps} stores in {PAPER} (reproduce_paper.py --repetitions "
                         f"{2 * reps})")
    fitness, groups = data.targets["fitness"], data.groups
    early = groups < reps
    for name, proxy in (("low-fidelity fitness", data.X[:, featurizer.names.index(FITNESS)]),
                        ("first run's fitness", data.first_runs[:, 0])):
        margin = replay_margin(proxy[early], fitness[early], groups[early], args.miss_rate)
        if margin is None:
            print(f"{args.problem}, {name}: too few improvements in repetitions 0-{reps - 1} to calibrate a margin")
            continue
        for label, rows in (("in-sample", early), ("new repetitions", ~early)):
            shortfalls = np.array(improvement_shortfalls(proxy[rows], fitness[rows], groups[rows]) or [np.nan])
            print(f"{args.problem}, {name}: margin {margin:.2f} (repetitions 0-{reps - 1}); {label}: "
                  f"{np.sum(shortfalls > margin)}/{len(shortfalls)} improvements beyond it "
                  f"({np.mean(shortfalls > margin):.1%}), largest shortfall {shortfalls.max():.1f}")


def _replay_racing(searches, stages, miss_rate: float, common_noise: bool):
    """One racing setting replayed on every search (margins from the other searches): simulations saved and in
    all, improvements missed and in all, drops that were ties (as ``PrescreenConfig.drop_ties``: under common noise,
    where no improvement on the other searches tied its incumbent), each search's margins per stage, and per search
    (greedy's simulations to its final, racing's simulations to that final, whether racing missed none of its
    improvements; a search that missed one is counted at greedy's whole search, as if it never came back to greedy's
    path: the replay cannot follow it)."""
    from surrogates.racing import tie_improvements
    from surrogates.replay import replay_margin

    saved = total = missed = improvements = ties = 0
    margins, reach = [], []
    for held, rows in enumerate(searches):
        others = [r for i, s in enumerate(searches) if i != held for r in s]
        groups = [i for i, s in enumerate(searches) if i != held for _ in s]
        ours = [replay_margin([r[2][k - 1] for r in others], [r[0] for r in others], groups,
                              miss_rate / len(stages)) for k in stages]
        drop_ties = common_noise and not tie_improvements(stack_rows([r[2] for r in others]),
                                                          [r[0] for r in others], groups)  # as the wrapper decides
        if any(m is None for m in ours):
            continue
        margins.append(ours)
        best, incumbent = -np.inf, None
        spent = spent_raced = to_final = to_final_raced = 0
        missed_before = missed
        final = max(f for f, _, _ in rows)
        for fitness, n, first in rows:
            total += n
            spent += n
            improves = fitness > best
            improvements += improves
            dropped_at = None
            for k, margin in zip(stages, ours) if incumbent is not None else ():
                verdict = race_verdict(incumbent[k - 1], first[k - 1], margin, drop_ties)
                if verdict:
                    dropped_at, ties = k, ties + (verdict == "tie")
                    break
            spent_raced += n if dropped_at is None else dropped_at
            if fitness == final and not to_final:
                to_final, to_final_raced = spent, spent_raced
            if dropped_at is not None:
                saved += n - dropped_at
                missed += improves
                continue
            if improves:
                best, incumbent = fitness, first
        kept = missed == missed_before
        reach.append((to_final, to_final_raced if kept else spent, kept))
    return saved, total, missed, improvements, ties, margins, reach


def plateau(args) -> None:
    """The authors' plateau test (averaged trajectories within DTW 10 of the best's) on a candidate judged on its
    first k runs: how often it agrees with the test on all runs, replayed on greedy alone's stores (each
    non-improving evaluation against the best so far). Like for like compares the first k runs of both (what a
    dropped candidate is judged by now); mismatched compares the candidate's first k runs with the best's all runs
    (before). Needs stores that keep the first runs' trajectories (``reproduce_paper.py`` from this version on)."""
    from search.greedy import PRESETS
    from surrealist_gym.metrics import dtw

    same_dtw = PRESETS["authors"].same_dtw
    stores = [path for path in _stores(args.problem, range(args.from_rep, args.from_rep + args.repetitions))]
    rows = []  # per non-improving evaluation: DTW on all runs, then (like for like, mismatched) per k
    for path in stores:
        with EvaluationStore(path) as store:
            evaluations = [e for e in store if e.fitness is not None]
        if not all("first_runs_trajectories" in e.info for e in evaluations):
            raise SystemExit(f"{path}: evaluations without first runs' trajectories; fly it again with "
                             f"benchmarks/reproduce_paper.py (a new --out or repetitions)")
        best = None
        for e in evaluations:
            if best is None or e.fitness > best.fitness:
                best = e
                continue
            ours, theirs = np.asarray(best.info["trajectory"]), np.asarray(e.info["trajectory"])
            firsts = [(np.asarray(a), np.asarray(b)) for a, b in zip(best.info["first_runs_trajectories"],
                                                                    e.info["first_runs_trajectories"])]
            rows.append((dtw(ours, theirs), [(dtw(a, b), dtw(ours, b)) for a, b in firsts]))
    same = np.array([full < same_dtw for full, _ in rows])
    print(f"{args.problem}: {len(stores)} stores, {len(rows)} non-improving evaluations, {same.mean():.0%} of them "
          f"'the same' as the best on all runs (DTW < {same_dtw:g})")
    for k in range(1, len(rows[0][1]) + 1):
        like = np.array([parts[k - 1][0] < same_dtw for _, parts in rows])
        mismatched = np.array([parts[k - 1][1] < same_dtw for _, parts in rows])
        print(f"first {k} runs: agreement with all runs, like for like {np.mean(like == same):.1%} "
              f"({np.sum(like & ~same)} called the same wrongly, {np.sum(~like & same)} missed), mismatched "
              f"{np.mean(mismatched == same):.1%} ({np.sum(mismatched & ~same)} / {np.sum(~mismatched & same)})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=["search", "accuracy", "race-replay", "fresh", "transfer", "plateau", "path"])
    parser.add_argument("--problem", default="rq1-seed1", choices=["rq1-seed1", "rq1-seed2", "rq2"])
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
    parser.add_argument("--skips-as-memo", action="store_true",
                        help="tell skips to the greedy as memo answers (not charged to its local budgets; "
                             "SkipAccounting.MEMO)")
    parser.add_argument("--skips-spend-budget", action="store_true",
                        help="the greedy's budget counts skipped and dropped candidates as whole evaluations, so it "
                             "plans and stops as greedy alone (SkipAccounting.BUDGET)")
    parser.add_argument("--verify-stop", action="store_true",
                        help="when the inner greedy stops with budget left, restart it unscreened from the best")
    parser.add_argument("--first-runs", type=lambda text: tuple(race_stages(text)), default=(),
                        help="racing: fly this many runs of a candidate first, the rest only if they do not fall "
                             "short; K1,K2,... races in stages")
    parser.add_argument("--folds", type=int, default=10, help="held-out repetitions, one per fold (default 10)")
    parser.add_argument("--lowfi", action="store_true", help="multi-fidelity features (a low-fidelity flight)")
    parser.add_argument("--also", default=None, choices=["rq1-seed1", "rq1-seed2"],
                        help="add every store of this problem (same flight and mission) to each training set")
    parser.add_argument("--common-noise", action="store_true",
                        help="common random numbers: greedy alone from results/paper-crn, the same noise for the "
                             "pre-screened greedy")
    parser.add_argument("--out", default=None,
                        help="default results/surrogates (--common-noise: results/surrogates-crn)")
    args = parser.parse_args()
    global PAPER, SIM_CONFIG
    if args.common_noise:
        PAPER, SIM_CONFIG = Path("results/paper-crn"), SimConfig(common_noise=True)
    args.out = args.out or ("results/surrogates-crn" if args.common_noise else "results/surrogates")
    if args.also == args.problem:
        parser.error("--also must name the OTHER seed (the held-out repetition would leak into training)")
    warnings.simplefilter("ignore")
    {"search": search, "accuracy": accuracy, "race-replay": race_replay, "fresh": fresh,
     "transfer": transfer, "plateau": plateau,
     "path": path}[args.what](args)


if __name__ == "__main__":
    main()
