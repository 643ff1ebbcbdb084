"""Reinforcement learning on a competition case study: how much of the action space is a legal test, and whether a
PPO policy trained on ``Surrealist-CaseStudy-v1`` finds more soft failures per simulation than random search.

Part 1 (always, no flight): ``--samples`` actions drawn by ``action_space.sample()`` (seeded) are decoded into boxes;
it prints the share within the rules' ranges (x, y, l, w, h, r; must be 1.0: the action box is the rules' box), the
share also valid (no overlap, clear of the take-off and landing points, feasible: what the env flies) with the reasons
of the refusals, and, as a baseline in the same run, the share the former encoding put within the rules (each field
moved from the seed layout by up to the rule's width either way, ``seed + a x width``).

Part 2 (the study, unless ``--sample-only``): PPO trained for ``--steps`` env steps on the case study
(``search.rl.train_policy``, noise seed 0, episodes of ``--episode-budget`` evaluations), then every agent of
``--agents`` (``ppo``, ``ppo-sample`` are the trained policy rolled out by ``search.PPOAgent``, deterministic first or
sampled at every step; any other name goes to ``search.make_agent``) searches the case study with ``--budget``
single-run evaluations on each held-out noise seed (``--seeds`` from each of ``--first-seed``; training never flew with
them), the agent seeded with the same number. Per search: the soft failures among the runs flown (a collision, or a
competition distance below 1.5 m; the seed's flight, the same for every agent, not counted), per simulation, and the
distinct failures a ``RecordSuite`` keeps (the seed's, when it fails, not counted either). The table gives each agent's
mean and standard deviation, and the paper's test (Shapiro-Wilk, then ANOVA or Mann-Whitney U;
``search.statistics.compare``) with the Vargha-Delaney A12 of the first agent against each other agent on soft failures
per simulation.

``--policy FILE.zip`` (or ``pretrained``, the policy for every mission that ships with the package) skips training
and searches with that policy: zero-shot, on a case study it never trained on, with ``--obstacles`` boxes. The agent
``random-frame`` is random search in the mission's frame (uniform frame actions,
:class:`~surrealist_gym.competition.mission_frame.MissionFrame`): what the frame gives without any learning.
``--mission drawn`` (or ``drawn-calm``, the same without wind) searches, on each seed, a case study drawn as the
policy's training draws them but never drawn there.

Everything is kept in ``--out``: the policy, trained in parts of ``--part`` steps (``ppo-STEPS-partKofN.zip``, each
with its record ``.json``; ``ppo-STEPS.zip`` when one part), each search's evaluations (``searches/AGENT-seedN.sqlite``)
and figures (``.json``), and ``summary.md``/``summary.json``. A rerun with the same ``--out`` reads back the parts
trained with the same settings and trains on from the last (its weights; the optimiser starts afresh), reads finished
searches back and resumes an interrupted one from its store (answered without simulating).

Usage::

    python benchmarks/bench_rl.py --sample-only                     # part 1 only (~5 s)
    python benchmarks/bench_rl.py                                   # short study: 256 steps, 3 seeds, budget 20
    python benchmarks/bench_rl.py --steps 50000 --seeds 5 --first-seed 300 --agents ppo-sample,random --budget 100 \
        --envs 2 --out results/rl                                   # the study
    python benchmarks/bench_rl.py ... --hyper gamma=0.95 --out results/rl-discounted   # another SB3 setting
    python benchmarks/bench_rl.py --policy pretrained --mission mission1 --obstacles 2 --seeds 5 --first-seed 300 \
        --agents ppo-sample,random,random-frame --budget 50 --out results/rl-pretrained/mission1-2   # zero-shot
    python benchmarks/bench_rl.py --policy pretrained --mission drawn-calm --obstacles 2 --seeds 5 --first-seed 300 \
        --agents ppo-sample,random-frame,random --budget 30 --out results/rl-pretrained/drawn-calm-2  # unseen draws
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
CASE_STUDIES = ROOT.parent / "shared" / "data" / "competition" / "case_studies"


DRAWN = {"drawn": True, "drawn-calm": False}  #: drawn case studies, with their drawn wind / without wind
DRAWN_SEED = 8700  #: search on seed N flies the case study drawn on seed DRAWN_SEED + N (300-304: 9000-9004)


def case_study(name: str, seed: int = 0):
    """A case study's YAML: the shared data's when it holds it, else the name (looked up by the rules); for
    ``drawn``/``drawn-calm``, the case study drawn (:func:`random_case_study`) on ``DRAWN_SEED + seed``, which the
    training of the shipped policy never drew (its draws come from its envs' own seeded generators)."""
    if name in DRAWN:
        from dataclasses import replace

        from surrealist_gym.competition.missions import random_case_study
        drawn = random_case_study(np.random.default_rng(DRAWN_SEED + seed))
        return drawn if DRAWN[name] else replace(drawn, wind=None)
    path = CASE_STUDIES / f"{name}.yaml"
    return str(path) if path.is_file() else name


def hyper_setting(text: str) -> tuple[str, object]:
    """``KEY=VALUE`` of ``--hyper``: the value read as JSON (``gamma=0`` -> 0, ``n_steps=128`` -> 128)."""
    key, sep, value = text.partition("=")
    try:
        if sep and key.strip():
            return key.strip(), json.loads(value)
    except json.JSONDecodeError:
        pass
    raise argparse.ArgumentTypeError(f"expected KEY=VALUE with a number or JSON value, got {text!r}")


def seed_starts(text: str) -> tuple[int, ...]:
    """``--first-seed``: one non-negative seed or several, comma-separated."""
    try:
        starts = tuple(int(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected N or N,N,...; got {text!r}") from None
    if any(start < 0 for start in starts):
        raise argparse.ArgumentTypeError(f"expected non-negative seeds, got {text!r}")
    return starts


def action_space_figures(mission: str, samples: int, seed: int = 0) -> dict:
    """Part 1: shares of sampled actions within the rules, and valid; the former encoding's share within the rules."""
    import gymnasium as gym

    import surrealist_gym  # noqa: F401  (registers the envs)
    from surrealist_gym.competition.rules import LAYOUT_FIELDS, RULES
    from surrealist_gym.errors import InvalidTestCase

    env = gym.make("Surrealist-CaseStudy-v1", case_study=case_study(mission), executor="inline").unwrapped
    env.action_space.seed(seed)
    actions = [env.action_space.sample() for _ in range(samples)]

    def within(values) -> bool:
        return all(RULES.bounds(f)[0] <= v <= RULES.bounds(f)[1] for f, v in zip(LAYOUT_FIELDS, values))

    start = time.perf_counter()
    inside = sum(all(within([getattr(b, f) for f in LAYOUT_FIELDS]) for b in env.boxes_for(a)) for a in actions)
    valid, refused = 0, {}
    for a in actions:
        try:
            env.test_for(a)
            valid += 1
        except InvalidTestCase as err:
            kind = "overlap" if "overlap" in str(err) else str(err).split(":")[0]
            refused[kind] = refused.get(kind, 0) + 1
    seconds = time.perf_counter() - start
    widths = np.array([RULES.bounds(f)[1] - RULES.bounds(f)[0] for f in LAYOUT_FIELDS])
    seeds = [np.array([getattr(b, f) for f in LAYOUT_FIELDS]) for b in env.seed_test.obstacles]
    former = sum(all(within(s + a[6 * i:6 * i + 6] * widths) for i, s in enumerate(seeds)) for a in actions)
    env.close()
    return {"mission": mission, "samples": samples, "within_rules": inside / samples, "valid": valid / samples,
            "refused": refused, "former_within_rules": former / samples, "decode_ms": 1e3 * seconds / samples}


def train(args, out: Path) -> Path:
    """The PPO policy of the study, trained in parts of ``--part`` steps, each saved (``ppo-STEPS-partKofN.zip`` and
    its ``.json``) and started from the weights of the one before (``train_policy(init=...)``): a rerun reads back
    the parts trained with the same settings and goes on after the last. Part k flies with noise seed k - 1, which
    stays below the held-out seeds."""
    from search.rl import algorithm_settings, recorded_settings, train_policy

    parts = -(-args.steps // args.part)
    if parts > min(args.first_seed):
        raise SystemExit(f"--steps {args.steps} in parts of {args.part}: part seeds would reach the held-out seeds "
                         f"from --first-seed {min(args.first_seed)}; raise --part or --first-seed")
    previous, total, simulated = None, 0.0, 0.0
    for k in range(parts):
        steps = min(args.part, args.steps - k * args.part)
        policy = out / (f"ppo-{args.steps}.zip" if parts == 1 else f"ppo-{args.steps}-part{k + 1}of{parts}.zip")
        settings = {"case_study": case_study(args.mission), "steps": steps, "budget": args.episode_budget,
                    "envs": args.envs, "seed": k, "init": None if previous is None else str(previous),
                    "hyper": recorded_settings(algorithm_settings("ppo", steps, args.envs, "case-study",
                                                                  **args.hyper))}
        record = policy.with_suffix(".json")
        if policy.is_file() and record.is_file():
            saved = json.loads(record.read_text())
            if {key: saved.get(key) for key in settings} == settings:
                previous, total = policy, total + saved["wall_seconds"]
                simulated += saved["record"].get("simulated_s", math.nan)
                print(f"policy part {k + 1}/{parts}: {policy} (read back)")
                continue
        train_policy(steps, policy, problem="case-study", case_study=settings["case_study"],
                     budget=args.episode_budget, envs=args.envs, seed=k, init=previous, **args.hyper,
                     progress=lambda n, k=k: print(f"\rtraining part {k + 1}/{parts}: {n}/{steps} steps", end="",
                                                   file=sys.stderr))
        print(file=sys.stderr)
        saved = json.loads(record.read_text())
        previous, total = policy, total + saved["wall_seconds"]
        simulated += saved["record"]["simulated_s"]
        print(f"policy part {k + 1}/{parts}: {policy} ({saved['wall_seconds']:.0f} s; "
              f"{saved['record']['soft_failures']} soft failures in {saved['record']['simulations']} simulations)")
    print(f"policy: {previous} (trained for {args.steps} steps in {total:.0f} s)")
    print(training_speed(args.steps, total, simulated))
    return previous


def training_speed(steps: int, wall: float, simulated: float, bare_s: float = 100.0) -> str:
    """Training's throughput: steps a second, and the simulated time flown a second of wall time (real time x)
    against the bare PyBullet loop's (``bench_sim.plain_pybullet``, measured now over ``bare_s`` simulated seconds at
    the profile's physics rate; its speed does not depend on how long it runs)."""
    from bench_sim import plain_pybullet

    from surrealist_gym.sim.profiles import load_profile

    if not math.isfinite(simulated):
        return f"training: {steps} steps in {wall:.0f} s ({steps / wall:.2f} steps/s); simulated time not recorded"
    bare = bare_s / plain_pybullet(bare_s, load_profile("px4-v1.12-sitl-iris").sim_config().physics_hz)
    return (f"training: {steps} steps in {wall:.0f} s ({steps / wall:.2f} steps/s), {simulated:.0f} s simulated: "
            f"{simulated / wall:.0f}x real time; the bare PyBullet loop {bare:.0f}x in this run: "
            f"{simulated / wall / bare:.2f} of its speed")


def frame_random(seed: int):
    """Random search in the mission's frame: uniform frame actions, each the case study's layout it stands for."""
    from search.base import Agent
    from surrealist_gym.competition.mission_frame import FRAME_ACTION_SIZE, MissionFrame

    class FrameRandom(Agent):
        name = "random-frame"

        def _setup(self, info):
            self.frame = MissionFrame.of(self._env)

        def _ask(self):
            return [self.frame.env_action(self.rng.uniform(-1.0, 1.0, FRAME_ACTION_SIZE))]

        def _tell(self, actions, fitnesses, infos):
            pass

    return FrameRandom(seed=seed)


def one_search(agent: str, seed: int, policy: Path, args, out: Path) -> dict:
    """One search on a held-out noise seed, cached in ``out/searches/AGENT-seedN.json`` (its store beside it)."""
    from search.registry import POLICY_PREFIXES, make_agent
    from search.rl import TrainingRecord
    from surrealist_gym.competition.case_study_env import flyable_case_study
    from surrealist_gym.competition.suite_env import RecordSuite

    stem = out / "searches" / f"{agent}-seed{seed}"
    cached = stem.with_suffix(".json")
    if cached.is_file():
        return json.loads(cached.read_text())
    stem.parent.mkdir(parents=True, exist_ok=True)
    # the env the policy trained on: the registered one, whose actions are made flyable (FlyableActions)
    env = RecordSuite(flyable_case_study(case_study=case_study(args.mission, seed), obstacles=args.obstacles,
                                         budget=args.budget, runs=1, random_seed=seed, executor="inline",
                                         store=stem.with_suffix(".sqlite")))
    counts = TrainingRecord()  # counts a search's steps as it counts a training's
    start = time.perf_counter()
    name = f"{agent}:{policy}" if agent in POLICY_PREFIXES else agent
    try:
        searcher = frame_random(seed) if agent == "random-frame" else make_agent(name, seed=seed)
        result = searcher.run(env, seed=seed, callback=lambda info: counts.add(info, False))
    finally:
        env.close()
    kept = ("steps", "refused", "memo", "simulations", "soft_failures")
    record = {"agent": agent, "seed": seed, **{key: getattr(counts, key) for key in kept},
              "evaluations": result.evaluations,
              "per_simulation": counts.soft_failures / counts.simulations if counts.simulations else 0.0,
              "distinct_failures": sum(m.evaluation > 1 for m in env.suite.members),  # not the seed's own
              "best_fitness": result.best_fitness,
              "wall_s": round(time.perf_counter() - start + env.unwrapped.evaluator.replayed_seconds, 1)}
    cached.write_text(json.dumps(record, indent=1) + "\n")
    return record


def summarise(records: list[dict], agents: list[str]) -> str:
    """The study's table (markdown): per agent mean ± sd, and the first agent against each other agent."""
    from search.statistics import compare, vargha_delaney_a12

    first = agents[0]
    lines = ["| agent | searches | simulations | soft failures | soft failures per simulation | distinct failures | "
             f"refused steps | p-value, {first} vs agent | A12 ({first} more) |", "|---" * 9 + "|"]
    ours = [r["per_simulation"] for r in records if r["agent"] == first]
    for agent in agents:
        rows = [r for r in records if r["agent"] == agent]
        if not rows:
            continue
        per = [r["per_simulation"] for r in rows]

        def mean_sd(key: str, digits: int = 1) -> str:
            values = [r[key] for r in rows]
            return f"{np.mean(values):.{digits}f} ± {np.std(values, ddof=1) if len(values) > 1 else 0:.{digits}f}"

        test = a12 = "-"
        if agent != first and len(ours) >= 3 and len(per) >= 3:
            p, name = compare(ours, per)
            test, a12 = f"{p:.3g} ({name})", f"{vargha_delaney_a12(ours, per):.2f}"
        elif agent != first and ours:
            test = "needs 3 seeds"
        lines.append(f"| {agent} | {len(rows)} | {mean_sd('simulations')} | {mean_sd('soft_failures')} | "
                     f"{np.mean(per):.3f} ± {np.std(per, ddof=1) if len(per) > 1 else 0:.3f} | "
                     f"{mean_sd('distinct_failures')} | {mean_sd('refused')} | {test} | {a12} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mission", default="mission2", help="case study (default mission2), or drawn / "
                        "drawn-calm: one drawn per seed")
    parser.add_argument("--obstacles", type=int, default=3, help="boxes per test (default 3)")
    parser.add_argument("--policy", default=None, metavar="FILE.zip|pretrained",
                        help="search with this policy instead of training one (pretrained: the shipped policy for "
                             "every mission)")
    parser.add_argument("--samples", type=int, default=2000, help="actions sampled in part 1 (default 2000)")
    parser.add_argument("--sample-only", action="store_true", help="part 1 only: no training, no flight")
    parser.add_argument("--steps", type=int, default=256, help="PPO training steps (default 256; the study: 50000)")
    parser.add_argument("--episode-budget", type=int, default=15, help="evaluations per training episode (15)")
    parser.add_argument("--envs", type=int, default=1, help="training envs stepped together, on threads (default 1)")
    parser.add_argument("--hyper", type=hyper_setting, action="append", default=[], metavar="KEY=VALUE",
                        help="a setting of SB3's PPO (repeatable), e.g. gamma=0.95; a part is read back only when it "
                             "was trained with the same")
    parser.add_argument("--part", type=int, default=5000, help="training steps per saved part (default 5000)")
    parser.add_argument("--agents", default="ppo-sample,ppo,random",
                        help="agents compared, the first against each other (default ppo-sample,ppo,random)")
    parser.add_argument("--seeds", type=int, default=3, help="held-out noise seeds (default 3; the study: 5)")
    parser.add_argument("--first-seed", type=seed_starts, default=(100,), metavar="N[,N...]",
                        help="the first held-out seed, or several (100,200: --seeds from each; default 100)")
    parser.add_argument("--budget", type=int, default=20, help="evaluations per search (default 20; the study: 100)")
    parser.add_argument("--out", type=Path, default=Path("results/bench-rl"), help="results folder (resumable)")
    args = parser.parse_args(argv)
    from surrealist_gym.competition.rules import RULES
    if not 1 <= args.obstacles <= RULES.max_obstacles:
        parser.error(f"--obstacles: expected 1 to {RULES.max_obstacles} (the rules), got {args.obstacles}")
    args.hyper = dict(args.hyper)
    if args.hyper:
        import inspect

        from stable_baselines3 import PPO
        known = inspect.signature(PPO).parameters
        if unknown := sorted(set(args.hyper) - set(known)):
            parser.error(f"--hyper {unknown[0]}: not a setting of stable_baselines3.PPO")
    warnings.simplefilter("ignore")

    figures = action_space_figures(args.mission, args.samples)
    print(f"{args.mission}: {args.samples} sampled actions, decoded without flying ({figures['decode_ms']:.2f} ms "
          f"each)")
    print(f"  within the rules' ranges:              {figures['within_rules']:.4f}")
    print(f"  also valid (no overlap, feasible):     {figures['valid']:.4f}   refused: {figures['refused']}")
    print(f"  former encoding, within the rules:     {figures['former_within_rules']:.4f}")
    if args.sample_only:
        return 0 if figures["within_rules"] == 1.0 else 1

    args.out.mkdir(parents=True, exist_ok=True)
    policy = args.policy or train(args, args.out)
    agents = [a.strip() for a in args.agents.split(",") if a.strip()]
    seeds = [start + i for start in args.first_seed for i in range(args.seeds)]
    records = []
    for seed in seeds:
        for agent in agents:
            record = one_search(agent, seed, policy, args, args.out)
            records.append(record)
            print(f"  {agent} seed {seed}: {record['soft_failures']} soft failures in {record['simulations']} "
                  f"simulations, {record['distinct_failures']} distinct ({record['wall_s']:.0f} s)")
    table = summarise(records, agents)
    trained = f"policy {args.policy}" if args.policy else f"PPO trained for {args.steps} steps"
    head = (f"{args.mission}, {args.obstacles} boxes: {trained}; {agents[0]} against "
            f"{', '.join(agents[1:])}"
            f"; held-out seeds {', '.join(f'{s}-{s + args.seeds - 1}' for s in args.first_seed)}, "
            f"budget {args.budget} single-run evaluations")
    print(head)
    print(table)
    (args.out / "summary.md").write_text(f"{head}\n\n{table}\n")
    (args.out / "summary.json").write_text(json.dumps({"action_space": figures, "searches": records,
                                                       "settings": {k: str(v) for k, v in vars(args).items()}},
                                                      indent=1) + "\n")
    return 0 if figures["within_rules"] == 1.0 else 1


if __name__ == "__main__":
    sys.exit(main())
