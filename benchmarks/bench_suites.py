"""Suites of distinct failures on the competition's case studies: the suite search against random search, the paper's
greedy and CMA-ES under the same budget.

Each search flies ``--budget`` single-run evaluations of ``Surrealist-CaseStudy-v1`` (PX4 SITL profile, the
competition's rules and distance, the feasibility check) behind
:class:`~surrealist_gym.competition.suite_env.RecordSuite`; then every member of its suite is re-flown ``--confirm``
times with fresh noise (base seed + 1). A member is *confirmed* when it fails in at least 60% of the re-runs. A suite
larger than ``--confirm-max`` is confirmed on a random sample of that many members, and its confirmed count estimated as
its size times the sample's confirmed share (the count in the sample is a lower bound). Per case study and agent the
table gives the median (min-max) of distinct failures found and confirmed, with the two-sided Mann-Whitney p-value and
Vargha-Delaney A12 of the suite search against each other agent on the (estimated) confirmed count.

Each repetition is cached in ``--out`` (its evaluations in SQLite, its figures in JSON): a rerun reads finished
ones back and resumes an interrupted one.

Usage::

    python benchmarks/bench_suites.py                         # missions 1-3, 4 agents, 5 repetitions, budget 200
    python benchmarks/bench_suites.py --missions mission1 --agents suite random --repetitions 2 --budget 50
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
CASE_STUDIES = ROOT.parent / "shared" / "data" / "competition" / "case_studies"
CONFIRMED_P = 0.6


def one_search(mission: str, agent: str, rep: int, budget: int, confirm: int, out: Path,
               confirm_max: int | None = None) -> dict:
    """One repetition: the search, its suite and the suite's confirmation (cached in out/STEM.json)."""
    warnings.simplefilter("ignore")
    stem = out / f"{mission}-{agent}-{rep}"
    if stem.with_suffix(".json").is_file():
        return json.loads(stem.with_suffix(".json").read_text())
    from search.registry import make_agent
    from surrealist_gym.competition.case_study_env import CaseStudyEnv
    from surrealist_gym.competition.reevaluation import evaluate
    from surrealist_gym.competition.suite import diversity
    from surrealist_gym.competition.suite_env import RecordSuite
    from surrealist_gym.competition.suite_export import export_suite

    start = time.perf_counter()
    env = RecordSuite(CaseStudyEnv(CASE_STUDIES / f"{mission}.yaml", budget=budget, runs=1, random_seed=rep,
                                   executor="inline", store=stem.with_suffix(".sqlite")))
    invalid = []
    result = make_agent(agent, seed=rep).run(env, seed=rep, callback=lambda i: invalid.append(bool(i["invalid"])))
    env.close()
    search_s = time.perf_counter() - start
    suite = env.suite
    paths = export_suite(suite, out / "suites" / stem.name)
    ps = []
    checked = paths
    if confirm_max is not None and len(paths) > confirm_max:  # a random sample of the members, drawn from rep
        import numpy as np

        picked = np.random.default_rng(rep).choice(len(paths), confirm_max, replace=False)
        checked = [paths[i] for i in sorted(picked)]
    if checked and confirm:
        from surrealist_gym.competition.tool_output import load_tests

        ev = evaluate(load_tests(checked), runs=confirm, seed=rep + 1, workers=1)
        ps = [s.p for s in ev.tests]
    record = {"mission": mission, "agent": agent, "rep": rep, "evaluations": result.evaluations,
              "steps": len(invalid), "invalid": sum(invalid), "search_s": round(search_s, 1),
              "wall_s": round(time.perf_counter() - start, 1), "found": len(suite),
              "checked": len(ps), "confirmed": sum(p >= CONFIRMED_P for p in ps),
              "confirmed_estimate": round(len(suite) * sum(p >= CONFIRMED_P for p in ps) / len(ps), 1) if ps else 0,
              "p": ps,
              "distances": [m.distance for m in suite.members], "diversity": diversity(suite.members)}
    stem.with_suffix(".json").write_text(json.dumps(record, indent=1, default=float) + "\n")
    return record


def summarise(records: list[dict], missions, agents) -> str:
    import numpy as np
    from scipy.stats import mannwhitneyu

    from search.statistics import vargha_delaney_a12

    lines = ["| case study | agent | searches | distinct failures found | confirmed among those re-flown | "
             "confirmed, estimated for the whole suite | p-value vs suite | A12 suite vs agent | search time [s] |",
             "|---|---|---|---|---|---|---|---|---|"]
    for mission in missions:
        by_agent = {a: [r for r in records if r["mission"] == mission and r["agent"] == a] for a in agents}
        ours = [r["confirmed_estimate"] for r in by_agent.get("suite", [])]
        for agent in agents:
            rows = by_agent[agent]
            if not rows:
                continue
            found, confirmed = [r["found"] for r in rows], [r["confirmed_estimate"] for r in rows]
            counted = ", ".join(f"{r['confirmed']}/{r['checked']}" for r in rows)
            test = "-"
            a12 = "-"
            if agent != "suite" and ours and len(ours) > 1 and len(confirmed) > 1:
                test = f"{mannwhitneyu(ours, confirmed, alternative='two-sided').pvalue:.3f}"
                a12 = f"{vargha_delaney_a12(ours, confirmed):.2f}"
            lines.append(f"| {mission} | {agent} | {len(rows)} | {np.median(found):g} ({min(found)}-{max(found)}) | "
                         f"{counted} | {np.median(confirmed):g} ({min(confirmed):g}-{max(confirmed):g}) | {test} | "
                         f"{a12} | "
                         f"{np.median([r['search_s'] for r in rows]):.0f} |")
    if len(missions) > 1:  # every search of an agent, over the case studies: more searches, a test with power
        ours = [r["confirmed_estimate"] for r in records if r["agent"] == "suite"]
        lines += ["", "| all case studies | searches | confirmed, estimated (median) | p-value vs suite | "
                      "A12 suite vs agent |", "|---|---|---|---|---|"]
        for agent in agents:
            theirs = [r["confirmed_estimate"] for r in records if r["agent"] == agent]
            if not theirs:
                continue
            test = a12 = "-"
            if agent != "suite" and len(ours) > 1 and len(theirs) > 1:
                test = f"{mannwhitneyu(ours, theirs, alternative='two-sided').pvalue:.4f}"
                a12 = f"{vargha_delaney_a12(ours, theirs):.2f}"
            lines.append(f"| {agent} | {len(theirs)} | {np.median(theirs):g} | {test} | {a12} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--missions", nargs="+", default=["mission1", "mission2", "mission3"])
    parser.add_argument("--agents", nargs="+", default=["suite", "random", "greedy", "cmaes"])
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--budget", type=int, default=200)
    parser.add_argument("--confirm", type=int, default=5)
    parser.add_argument("--confirm-max", type=int, default=20,
                        help="re-fly at most this many members of a suite, drawn at random (default 20)")
    parser.add_argument("--agent-repetitions", default="",
                        help="fewer repetitions for some agents, e.g. greedy=1,cmaes=1 (the rest: --repetitions)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", default="results/bench-suites")
    parser.add_argument("--summary-only", action="store_true", help="summarise the finished searches in --out")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.summary_only:
        records = [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]
        print(summarise(records, args.missions, args.agents))
        return 0
    reps = {a: args.repetitions for a in args.agents}
    reps.update({k: int(v) for k, v in (item.split("=") for item in args.agent_repetitions.split(",") if item)})
    jobs = [(m, a, r) for r in range(args.repetitions) for m in args.missions for a in args.agents if r < reps[a]]
    records = []
    start = time.perf_counter()
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {pool.submit(one_search, m, a, r, args.budget, args.confirm, out, args.confirm_max): (m, a, r)
                   for m, a, r in jobs}
        for future in as_completed(futures):
            record = future.result()
            records.append(record)
            print(f"[{len(records)}/{len(jobs)} {time.perf_counter() - start:.0f} s] {record['mission']} "
                  f"{record['agent']} rep {record['rep']}: {record['found']} distinct failures, "
                  f"{record['confirmed']} confirmed ({record['search_s']:.0f} s search)", flush=True)
    table = summarise(records, args.missions, args.agents)
    print(table)
    (out / "summary.md").write_text(f"budget {args.budget} single-run evaluations per search, "
                                    f"{args.repetitions} repetitions ({args.agent_repetitions or 'all'}), "
                                    f"{args.confirm} re-runs per member, at most {args.confirm_max} members\n\n"
                                    + table + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
