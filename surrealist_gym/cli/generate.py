"""`surrealist generate --seed TEST.yaml`: find nearby tests that make the UAV unsafe or crash (paper RQ2).

`surrealist generate --case-study mission2`: a suite of distinct failures for a UAV Testing Competition case study,
exported for Aerialist and re-flown to give each its failure probability.
"""
from __future__ import annotations

from ._search import run_search, search_folder
from .options import CASE_STUDY_DEFAULTS, GenerateOptions, refuse_inapplicable, refuse_leftover, refuse_positional


def add_arguments(parser) -> None:
    """Arguments of ``surrealist generate``; a seed test given as a positional argument, as before, is refused."""
    GenerateOptions.add_arguments(parser)
    refuse_positional(parser, "seed", lambda value: f"the seed test is given as --seed {value}")


def run(args) -> int:
    """Search for unsafe tests near the seed (or a case study's suite of failures); returns the exit code."""
    from .. import data_path
    from ..aerialist import load_test
    from ..envs.generate import GenerateEnv
    from ..errors import InvalidTestCase
    from ..mutators import AUTHORS_ORDER, default_mutators

    refuse_leftover(args, "seed")
    if not args.resume:  # an option of the other problem, before any work
        refuse_inapplicable(args, GenerateOptions.inapplicable(args))
    if args.case_study and not args.resume:
        return _case_study(args)
    if args.uav is None and not args.resume:  # the seed test's default UAV, recorded in run.json
        from ..sim.uav import decide_uav
        args.uav = decide_uav(load_test(args.test or data_path("rq2-seed.yaml"))).name
    with search_folder(args, GenerateOptions) as (out, options):
        if options.case_study:
            return _case_study_search(out, options)
        seed = load_test(options.test or data_path("rq2-seed.yaml"))
        mutators = None
        if options.all_mutators:
            mutators = default_mutators(seed, AUTHORS_ORDER)
        if options.wind:
            from ..mutators import MOVE_KINDS, wind_mutators
            mutators = (mutators or default_mutators(seed, MOVE_KINDS, obstacles=[0])) + wind_mutators()
        try:
            env = GenerateEnv(seed_test=options.test, runs=options.runs, budget=options.budget, mutators=mutators,
                              aggregate=options.aggregate, executor=options.dask_scheduler,
                              store=out / "evaluations.sqlite", random_seed=options.random_seed,
                              workers=options.workers, uav=options.uav, sim_config=_overrides(options))
        except InvalidTestCase as err:  # a uav.* field of the seed test: name its file
            if options.test and not str(err).startswith(str(options.test)):
                raise InvalidTestCase(f"{options.test}: {err}") from None
            raise
        return run_search(env, options, out, "generate")


def _overrides(options) -> dict:
    """What the search sets of the SimConfig beyond its UAV: the noise mode and the competition distance's buffer."""
    return {"common_noise": options.common_noise, "competition_buffer_m": options.buffer}


def _case_study(args) -> int:
    """A new case-study search: the case study's defaults where the command line left them, then the search."""
    from pathlib import Path

    from ..competition.rules import case_study_path

    path = case_study_path(args.case_study)  # a case study that does not exist fails here, before any folder
    if Path(args.case_study).suffix in (".yaml", ".yml"):
        args.case_study = str(path.resolve())
    for name, value in CASE_STUDY_DEFAULTS.items():
        if f"--{name}" not in getattr(args, "_flags", frozenset()):
            setattr(args, name, value)
    if args.uav is None:  # recorded in run.json
        from ..sim.uav import DEFAULT_UAV
        args.uav = DEFAULT_UAV
    with search_folder(args, GenerateOptions) as (out, options):
        return _case_study_search(out, options)


def _case_study_search(out, options) -> int:
    from ..competition.case_study_env import CaseStudyEnv
    from ..competition.suite_env import RecordSuite

    env = RecordSuite(CaseStudyEnv(case_study=options.case_study, obstacles=options.obstacles, runs=options.runs,
                                   budget=options.budget, aggregate=options.aggregate,
                                   executor=options.dask_scheduler, store=out / "evaluations.sqlite",
                                   random_seed=options.random_seed, workers=options.workers,
                                   uav=options.uav, sim_config=_overrides(options), wind=options.wind))
    code = run_search(env, options, out, "generate")
    if code == 0:
        _write_suite(out, env.suite, options)
    return code


def _write_suite(out, suite, options) -> None:
    """Re-fly each member ``--confirm`` times with fresh noise, rank the members by their expected test score (from
    those re-runs, else from the search's own runs), export and plot them in that order (the 2025 edition evaluates
    the first 20 a tool wrote), and say what the first 20 would score and the closest failure."""
    import sys

    from tqdm import tqdm

    from ..competition.reevaluation import evaluate, regroup, stored_runs
    from ..competition.reports.evaluation import write_report
    from ..competition.reports.plots import plot_suite
    from ..competition.scoring import EDITIONS, Draw, case_study_of, score_suite, test_score
    from ..competition.suite import diversity
    from ..competition.suite_export import export_suite, member_name

    folder = out / "suite"
    members, ev = suite.members, None
    if members and options.confirm > 0:  # fresh noise: another base seed than the search's runs
        bar = tqdm(total=len(members) * options.confirm, unit="run", desc="confirm", dynamic_ncols=True,
                   file=sys.stderr, disable=None)
        try:  # named by member order until they are ranked
            ev = evaluate([(folder / f"{member_name(i)}.yaml", m.test) for i, m in enumerate(members)],
                          runs=options.confirm, seed=options.random_seed + 1, uav=options.uav,
                          workers=options.workers, progress=lambda done, total: bar.update(done - bar.n),
                          buffer=options.buffer)
        finally:
            bar.close()
    runs = ([t.runs for t in ev.tests] if ev is not None
            else stored_runs(out / "evaluations.sqlite", [m.test for m in members]))
    expected = [test_score([r.points for r in rs if r.flown], [r.duration for r in rs if r.flown],
                           len(m.test.obstacles)) for m, rs in zip(members, runs)]
    order = sorted(range(len(members)), key=lambda i: (-expected[i], i))  # the best first, then as found
    verdicts = None
    if getattr(options, "px4_verdict", False) and members:  # PX4's verdict first (docs/predict.md)
        from ..fidelity.verdict import rank_by_verdict
        order, verdicts = rank_by_verdict([m.test for m in members], runs, expected)
    paths = export_suite(suite, folder, order, expected)
    if verdicts is not None:
        from ..fidelity.verdict import write_ranking
        table = write_ranking(folder / "px4-verdict.csv", [paths[order.index(i)] for i in range(len(members))],
                              verdicts, expected, order)
        print(f"ranked by the model of PX4's verdict (P(PX4 < 1.5 m) x expected test score): the first, "
              f"{paths[0].name}, P {verdicts[order[0]].p_unsafe:.2f}; all in {table}")
    plot_suite(suite, folder / "suite.png", order)
    spread = diversity(members)
    print(f"suite: {len(suite)} distinct failures (apart by >= {suite.min_flight_m:g} m in flight and >= "
          f"{suite.min_layout_m:g} m in the obstacle failed at)"
          + (f"; mean pairwise flight distance {spread['flight_mean_m']:.1f} m, layout {spread['layout_mean_m']:.1f} m"
             if len(suite) > 1 else ""))
    if members:
        i = min(order, key=lambda i: (members[i].status != "collision", members[i].distance))
        print(f"closest failure: {members[i].distance:.2f} m ({members[i].status}) in {paths[order.index(i)]}")
        ed = EDITIONS["2025"]
        first = order[:ed.tests]
        score = score_suite(ed, Draw(str(folder), case_study_of(members[0].test), len(members),
                                     tuple(str(p) for p in paths[:ed.tests])),
                            [(members[i].test, runs[i], "") for i in first])
        source = f"{options.confirm} re-runs each" if ev is not None else "the search's own runs"
        print(f"expected 2025 scores of the first {len(first)} (from {source}): failure {score.failure:.2f} (the "
              f"sum of failure probability x points x 10 / (boxes^2 x flight minutes); the best, {member_name(0)}, "
              f"{expected[order[0]]:.2f}), diversity " + ("-" if len(first) < 2 else f"{score.diversity:.2f}")
              + " (1 - mean area IoU)")
    if ev is not None:
        ev = regroup(ev, order, paths)
        write_report(ev, folder / "confirmation")
        confirmed = sum(s.p >= CONFIRMED_P for s in ev.tests)  # of the re-runs flown: those in error do not count
        errors = sum(s.errors for s in ev.tests)
        print(f"confirmation: {confirmed} of {len(suite)} fail in >= {CONFIRMED_P:.0%} of {options.confirm} re-runs "
              + (f"({errors} re-runs ended in error and are not counted) " if errors else "")
              + f"(report in {folder / 'confirmation'}/report.md)")
    print(f"suite in {folder}/: failure-NN.yaml (the best first; Aerialist master and 0.2.x load them, run from "
          f"{folder.name}/: README.md), case_studies/, suite.csv, suite.png")


CONFIRMED_P = 0.6  # a failure probability at least this high over the re-runs: the failure is confirmed
