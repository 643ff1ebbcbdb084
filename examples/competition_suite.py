"""A suite of distinct failures for a UAV Testing Competition case study, then its failures re-flown.

    python examples/competition_suite.py ../shared/data/competition/case_studies/mission2.yaml --budget 200
    python examples/competition_suite.py CASE_STUDY.yaml --budget 6 --confirm 2 --inline   # a quick look (CI)

The same as ``surrealist generate --case-study mission2`` through the Python API (docs/suites.md): the case-study
env under the competition's rules, the suite wrapper around it, the suite search, the export for Aerialist and the
re-evaluation of ``surrealist evaluate``.
"""
import argparse

import gymnasium as gym

import surrealist_gym  # noqa: F401  (registers Surrealist-CaseStudy-v1)
from search.novelty import SuiteSearch
from surrealist_gym.competition.reevaluation import evaluate
from surrealist_gym.competition.suite import diversity
from surrealist_gym.competition.suite_env import RecordSuite
from surrealist_gym.competition.suite_export import export_suite
from surrealist_gym.competition.tool_output import load_tests

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("case_study", help="a case study's YAML (or mission1-3 when $SURREALIST_CASE_STUDIES is set)")
parser.add_argument("--budget", type=int, default=200, help="single-run evaluations")
parser.add_argument("--confirm", type=int, default=5, help="re-runs of each failure")
parser.add_argument("--out", default="suite")
parser.add_argument("--inline", action="store_true", help="simulate in this process")
args = parser.parse_args()

env = RecordSuite(gym.make("Surrealist-CaseStudy-v1", case_study=args.case_study, budget=args.budget,
                           executor="inline" if args.inline else None))
result = SuiteSearch(seed=0).run(env, seed=0)
suite = env.suite
print(f"{result.evaluations} evaluations, {result.simulations} simulations: {len(suite)} distinct failures")
print("diversity:", {k: round(v, 2) for k, v in diversity(suite.members).items()})
paths = export_suite(suite, args.out)
if paths and args.confirm:
    ev = evaluate(load_tests(paths), runs=args.confirm, seed=1, workers=1 if args.inline else None)
    for stats in ev.tests:
        print(f"{stats.name}: fails in {stats.failures} of {len(stats.runs)} re-runs "
              f"(95% interval {stats.ci_low:.2f}-{stats.ci_high:.2f}), {stats.points_mean:.1f} points per run")
print(f"suite in {args.out}/ (Aerialist YAMLs, legacy/ for the competition's keys, suite.csv)")
env.close()
