"""The model of PX4's verdict against our simulator alone, on rilast-mission1 (docs/predict.md).

    python benchmarks/bench_px4_verdict.py [--store results/rilast-runs3/evaluations.sqlite] [--runs 3] [--workers 2]
    python benchmarks/bench_px4_verdict.py --from-table benchmarks/data/px4-verdict-training.csv [--no-camba]

1. Flies rilast-mission1's 1,350 tests ``--runs`` times (seed 0, px4-v1.12-sitl-iris), or reads them from ``--store``
   (the ``evaluations.sqlite`` of ``surrealist fidelity TESTS.csv --runs 3 --out DIR``; it flies what the store
   lacks), and computes each test's features.
2. Chooses the model on the development half only (even run numbers): leave-one-search-run-out cross-validation over
   its 8 runs, for each feature set and ridge penalty (and, when scikit-learn is installed, a gradient-boosted
   classifier for comparison), scored by the close-region AUC (PX4 < 3 m) of the pooled out-of-fold predictions.
3. Fits the chosen one on the whole development half and measures it once on the held-out half (odd run numbers):
   close-region and all-test AUC for PX4 < 1.5 m, precision at the recall of our simulator alone (ours < 1.5 m), the
   same with the threshold matched on the development half; the under-1-m target's AUC; our simulator alone's
   figures from the same runs (the median of the runs, and run 0 alone as ``surrealist fidelity`` with 1 run).
4. The CAMBA collection (21 tests, all PX4 soft failures, never used to choose anything): recall of each.
"""
from __future__ import annotations

import argparse
import math
import re
import sys
import time
from pathlib import Path

import numpy as np

from surrealist_gym.fidelity.labels import load_labelled_set
from surrealist_gym.fidelity.measure import _auc, fly_labelled_set
from surrealist_gym.fidelity.verdict import fit_verdict, predict_runs, training_table
from surrealist_gym.fidelity.verdict_features import DISTANCE_FEATURES, FEATURES, RUN_FEATURES
from surrealist_gym.sim.uav import decide_uav

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "competition"
DISTANCE, RUNS = DISTANCE_FEATURES, RUN_FEATURES
LAYOUT = DISTANCE + ("obstacles", "path_clearance", "log_path_clearance", "blocks_path", "nearest_on_right", "gap_m",
                     "nearest_along", "footprint_area")
FEATURE_SETS = {"distance": DISTANCE, "runs": RUNS, "distance+layout": LAYOUT, "all": FEATURES}
PENALTIES = (0.1, 1.0, 10.0, 100.0, 1000.0, 10000.0)
NEAR = (None, 6.0)  # train on every test, or on those whose closest run of ours came within 6 m
CLOSE_M = 3.0


def search_run(test_id: str) -> str:
    """The search run a test came from (``random_run2``, ``ga_run4``): the cross-validation's groups."""
    return re.match(r"(.*run\d+)_", test_id).group(1)


def flown_rows(rows):
    return [r for r in rows if r["px4_result"] == "flown" and math.isfinite(r["px4_distance_m"])]


def auc_of(rows, scores, limit=1.5, close=CLOSE_M):
    """AUC for PX4 < ``limit`` of ``scores`` (higher = riskier), on rows with PX4 < ``close`` (None: all)."""
    theirs = np.array([r["px4_distance_m"] for r in rows])
    keep = theirs < close if close else np.ones(len(rows), bool)
    return _auc(theirs[keep] < limit, -np.asarray(scores)[keep])


def precision_at_recall(positive, scores, recall):
    """Precision of the smallest set of highest-scored tests whose recall reaches ``recall``, and that threshold."""
    order = np.argsort(-scores, kind="stable")
    tp = np.cumsum(positive[order])
    k = int(np.searchsorted(tp, recall * positive.sum() - 1e-9)) + 1
    k = min(k, len(order))
    return tp[k - 1] / k, float(scores[order][k - 1])


def cross_validate(dev, fit_predict):
    """Out-of-fold scores over the development half, one fold per search run."""
    groups = np.array([search_run(r["test"]) for r in dev])
    scores = np.zeros(len(dev))
    for g in sorted(set(groups)):
        held = groups == g
        scores[held] = fit_predict([r for r, h in zip(dev, held) if not h], [r for r, h in zip(dev, held) if h])
    return scores


def model_of(kind):
    """Fit the package's model (:func:`fit_verdict`) of ``kind`` on the training rows; P(PX4 < 1.5 m) of the rest."""
    def make(features, l2, near_m):
        def fit_predict(train, test):
            model = fit_verdict(train, kind=kind, l2=l2, features=features, near_m=near_m)
            return model.unsafe.probability(np.array([[r[f] for f in features] for r in test]))
        return fit_predict
    return make


def boosting(features):
    from sklearn.ensemble import HistGradientBoostingClassifier

    def fit_predict(train, test):
        model = HistGradientBoostingClassifier(max_depth=3, learning_rate=0.05, max_iter=200, random_state=0)
        model.fit([[r[f] for f in features] for r in train], [r["px4_distance_m"] < 1.5 for r in train])
        return model.predict_proba([[r[f] for f in features] for r in test])[:, 1]
    return fit_predict


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--store", default=None, help="evaluations.sqlite of surrealist fidelity --runs N")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--no-camba", action="store_true")
    parser.add_argument("--table", default=None, help="also write the training table (all 1,350 tests) here")
    parser.add_argument("--from-table", default=None, help="read the features from a training table instead of "
                        "flying (benchmarks/data/px4-verdict-training.csv; no run-0 baseline then)")
    args = parser.parse_args()
    config = decide_uav(uav="px4-v1.12-sitl-iris").config
    start = time.perf_counter()
    run0 = {}
    if args.from_table:
        from surrealist_gym.fidelity.verdict import read_table
        rows = read_table(args.from_table)
    else:
        lset = load_labelled_set(DATA / "rilast-mission1" / "tests.csv")
        outcomes = fly_labelled_set(lset, args.runs, 0, config, args.workers, store=args.store)
        rows = training_table(lset, outcomes)
        run0 = {label.test_id: o[0].distance if o[0].status != "timeout" else math.nan
                for label, o in zip(lset.labels, outcomes)}
    if args.table:
        from surrealist_gym.fidelity.verdict import write_table
        write_table(rows, args.table)
    print(f"rilast-mission1: {len(rows)} tests, {args.runs} runs each, features in {time.perf_counter() - start:.0f} s")
    dev = flown_rows([r for r in rows if r["half"] == "development"])
    held = flown_rows([r for r in rows if r["half"] == "held-out"])
    print(f"development: {len(dev)} tests PX4 flew, held-out: {len(held)}")

    # --- choice, on the development half only ---------------------------------------------------------------
    print("\ndevelopment half, leave-one-search-run-out CV (8 folds): close AUC / all-test AUC for PX4 < 1.5 m")
    print(f"  {'simulator alone (median of runs)':44} {auc_of(dev, [-r['d_median'] for r in dev]):.3f} / "
          f"{auc_of(dev, [-r['d_median'] for r in dev], close=None):.3f}")
    candidates = {}
    for near_m in NEAR:
        for name, features in FEATURE_SETS.items():
            for l2 in PENALTIES:
                for kind in ("logistic", "log-distance"):
                    oof = cross_validate(dev, model_of(kind)(features, l2, near_m))
                    key = (kind, name, l2, near_m)
                    candidates[key] = (auc_of(dev, oof), auc_of(dev, oof, close=None), oof)
                    where = "" if near_m is None else f", ours < {near_m:g} m"
                    print(f"  {f'{kind}, {name}, l2 {l2:g}{where}':50} {candidates[key][0]:.3f} / "
                          f"{candidates[key][1]:.3f}")
    try:
        for name in ("runs", "all"):
            oof = cross_validate(dev, boosting(FEATURE_SETS[name]))
            print(f"  {f'gradient boosting, {name} features (sklearn)':44} {auc_of(dev, oof):.3f} / "
                  f"{auc_of(dev, oof, close=None):.3f}   (comparison only)")
    except ImportError:
        print("  (scikit-learn not installed: no gradient-boosting comparison)")
    (kind, name, l2, near_m), (cv_close, cv_all, oof) = max(candidates.items(),
                                                            key=lambda kv: (round(kv[1][0], 3), kv[1][1]))
    print(f"chosen: {kind}, {name} features, l2 {l2:g}, trained on "
          + ("every test" if near_m is None else f"ours < {near_m:g} m") + f" (CV close AUC {cv_close:.3f}, all "
          f"{cv_all:.3f})")

    # --- the threshold matched on the development half ----------------------------------------------------------
    dev_pos = np.array([r["px4_distance_m"] < 1.5 for r in dev])
    dev_close = np.array([r["px4_distance_m"] < CLOSE_M for r in dev])
    sim_dev = np.array([r["d_median"] < 1.5 for r in dev])
    dev_recall = (sim_dev & dev_pos)[dev_close].sum() / dev_pos[dev_close].sum()
    _, dev_threshold = precision_at_recall(dev_pos[dev_close], oof[dev_close], dev_recall)

    # --- measured once on the held-out half ---------------------------------------------------------------------
    model = fit_verdict(dev, kind=kind, l2=l2, features=FEATURE_SETS[name], near_m=near_m)
    p_unsafe, p_hard = model.predict(held)
    theirs = np.array([r["px4_distance_m"] for r in held])
    close, positive = theirs < CLOSE_M, theirs < 1.5
    ours = np.array([r["d_median"] for r in held])
    ours0 = np.array([run0.get(r["test"], math.nan) for r in held])
    print(f"\nheld-out half ({len(held)} tests PX4 flew, {close.sum()} close, {positive.sum()} under 1.5 m), measured "
          "once:")
    print(f"  {'':40}{'close AUC':>11}{'all AUC':>9}{'precision':>11}{'recall':>8}")
    flagged_sim = ours < 1.5
    rec_sim = (flagged_sim & positive)[close].sum() / positive[close].sum()
    prec_sim = (flagged_sim & positive)[close].sum() / max(1, flagged_sim[close].sum())
    ok0 = np.isfinite(ours0)
    for label, score in ((("simulator alone, run 0 (1 run)", -np.where(ok0, ours0, 99.0)),) if run0 else ()) + (
            ("simulator alone, median of runs", -ours),):
        print(f"  {label:40}{auc_of(held, score):>11.3f}{auc_of(held, score, close=None):>9.3f}", end="")
        print(f"{prec_sim:>11.3f}{rec_sim:>8.3f}" if "median" in label else "")
    prec_eq, _ = precision_at_recall(positive[close], p_unsafe[close], rec_sim)
    print(f"  {'model, P(PX4 < 1.5 m)':40}{auc_of(held, p_unsafe):>11.3f}{auc_of(held, p_unsafe, close=None):>9.3f}"
          f"{prec_eq:>11.3f}{rec_sim:>8.3f}   (precision at the simulator's recall)")
    flagged = p_unsafe >= dev_threshold
    prec_dev = (flagged & positive)[close].sum() / max(1, flagged[close].sum())
    rec_dev = (flagged & positive)[close].sum() / positive[close].sum()
    print(f"  {f'model, threshold {dev_threshold:.3f} from development':40}{'':>20}{prec_dev:>11.3f}{rec_dev:>8.3f}")
    for kind in ("random", "ga"):
        part = [i for i, r in enumerate(held) if r["test"].startswith(kind + "_")]
        sub = [held[i] for i in part]
        print(f"  {kind} search's held-out tests ({len(part)}): close AUC simulator alone "
              f"{auc_of(sub, -ours[part]):.3f}, model {auc_of(sub, p_unsafe[part]):.3f}")
    print(f"  under 1 m ({(theirs < 1.0).sum()} tests): AUC of P(PX4 < 1 m) {_auc(theirs < 1.0, -p_hard):.3f}, of "
          f"our distance {_auc(theirs < 1.0, ours):.3f} (all tests)")

    if not args.no_camba:
        camba(args, config, model)
    return 0


def camba(args, config, model) -> None:
    """The CAMBA collection: recall of our simulator (ours < 1.5 m) and of the model (P >= 0.5)."""
    from surrealist_gym.fidelity.verdict import load_verdict

    folder = DATA / "camba-collection"
    lset = load_labelled_set(folder, Path(__file__).resolve().parent / "data" / "camba-px4-flights.csv")
    outcomes = fly_labelled_set(lset, args.runs, 0, config, args.workers)
    names = [label.test_id for label in lset.labels]
    for label, verdict in (("model fitted on development", None), ("shipped model", load_verdict())):
        if verdict is None:
            from surrealist_gym.fidelity.verdict import PX4Verdict
            verdict = PX4Verdict(model.unsafe, model.hard, {"runs": args.runs})
        predictions = predict_runs(verdict, names, lset.tests, outcomes)
        p = np.array([x.p_unsafe for x in predictions])
        ours = np.array([x.our_distance_m for x in predictions])
        print(f"CAMBA ({len(p)} tests, all PX4 < 1.5 m), {label}: P >= 0.5 on {np.mean(p >= 0.5):.2f}, mean P "
              f"{p.mean():.2f}; simulator alone ours < 1.5 m on {np.mean(np.nan_to_num(ours, nan=99) < 1.5):.2f}")


if __name__ == "__main__":
    sys.exit(main())
