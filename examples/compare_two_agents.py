"""Compare two agents on the RQ2 generation problem: Table 2 metrics, p-values, A12 and a convergence plot.

    python examples/compare_two_agents.py --repetitions 10 --budget 50 --out results/greedy-vs-cmaes
    python examples/compare_two_agents.py --repetitions 2 --budget 3 --runs 1 --inline     # CI

Same as ``surrealist compare --env Surrealist-Generate-v0 --agents greedy,cmaes ...``; run it again with the same
--out to resume.
"""
import argparse

from search import compare

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--agents", default="greedy,cmaes")
parser.add_argument("--repetitions", type=int, default=3)
parser.add_argument("--budget", type=int, default=10)
parser.add_argument("--runs", type=int, default=1)
parser.add_argument("--out", default="results/compare-example")
parser.add_argument("--inline", action="store_true", help="simulate in this process")
args = parser.parse_args()

result = compare("Surrealist-Generate-v0", args.agents.split(","), repetitions=args.repetitions, budget=args.budget,
                 runs=args.runs, out=args.out, executor="inline" if args.inline else "process")
for row in result.summary:
    print(f"{row['label']:>8}: best fitness {row['best_fitness_mean']:.2f} +/- {row['best_fitness_std']:.2f}, "
          f"simulations to best {row['simulations_to_best_mean']:.1f}")
for row in result.pairwise:
    print(f"{row['agent_a']} vs {row['agent_b']}: fitness A12 {row['best_fitness_a12']:.2f} "
          f"(p {row['best_fitness_p']:.3g})")
print(f"tables and convergence.png in {result.out}/")
