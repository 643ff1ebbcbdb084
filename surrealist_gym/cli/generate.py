"""`surrealist generate TEST.yaml`: find nearby tests that make the UAV unsafe or crash (paper RQ2).

`surrealist generate --case-study mission2`: a suite of distinct failures for a UAV Testing Competition case study,
exported for Aerialist and re-flown to give each its failure probability.
"""
from __future__ import annotations

from ._search import run_search, search_folder, sim_config_of
from .options import GenerateOptions

CASE_STUDY_DEFAULTS = {"budget": 200, "runs": 1, "agent": "suite"}  # what --case-study changes, unless typed


def add_arguments(parser) -> None:
    GenerateOptions.add_arguments(parser)


def run(args) -> int:
    from .. import data_path
    from ..envs.generate import GenerateEnv
    from ..mutators import AUTHORS_ORDER, default_mutators
    from ..testcase import load_test

    if args.case_study and not args.resume:
        return _case_study(args)
    if args.uav is None and not args.resume:  # the seed test's default UAV, recorded in run.json
        from ..sim.profiles import default_profile
        args.uav = default_profile(load_test(args.test or data_path("rq2-seed.yaml"))).name
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
        env = GenerateEnv(seed_test=options.test, runs=options.runs, budget=options.budget, mutators=mutators,
                          aggregate=options.aggregate, executor=options.dask_scheduler,
                          store=out / "evaluations.sqlite", random_seed=options.random_seed,
                          workers=options.workers, sim_config=sim_config_of(options))
        return run_search(env, options, out, "generate")


def _case_study(args) -> int:
    """A new case-study search: the case study's defaults where the command line left them, then the search."""
    from pathlib import Path

    from ..competition import case_study_path

    path = case_study_path(args.case_study)  # a case study that does not exist fails here, before any folder
    if Path(args.case_study).suffix in (".yaml", ".yml"):
        args.case_study = str(path.resolve())
    for name, value in CASE_STUDY_DEFAULTS.items():
        if f"--{name}" not in getattr(args, "_flags", frozenset()):
            setattr(args, name, value)
    if args.uav is None:
        from ..envs.case_study import DEFAULT_UAV
        args.uav = DEFAULT_UAV
    with search_folder(args, GenerateOptions) as (out, options):
        return _case_study_search(out, options)


def _case_study_search(out, options) -> int:
    from ..envs.case_study import CaseStudyEnv
    from ..envs.suite import RecordSuite

    env = RecordSuite(CaseStudyEnv(case_study=options.case_study, obstacles=options.obstacles, runs=options.runs,
                                   budget=options.budget, aggregate=options.aggregate,
                                   executor=options.dask_scheduler, store=out / "evaluations.sqlite",
                                   random_seed=options.random_seed, workers=options.workers,
                                   sim_config=sim_config_of(options), wind=options.wind))
    code = run_search(env, options, out, "generate")
    if code == 0:
        _write_suite(out, env.suite, options)
    return code


def _write_suite(out, suite, options) -> None:
    """Export the suite, plot it, and re-fly each member ``--confirm`` times with fresh noise."""
    from ..suite import diversity
    from ..suite_export import export_suite, plot_suite

    folder = out / "suite"
    paths = export_suite(suite, folder)
    plot_suite(suite, folder / "suite.png")
    spread = diversity(suite.members)
    print(f"suite: {len(suite)} distinct failures (apart by >= {suite.min_flight_m:g} m in flight and >= "
          f"{suite.min_layout_m:g} m in the obstacle failed at)"
          + (f"; mean pairwise flight distance {spread['flight_mean_m']:.1f} m, layout {spread['layout_mean_m']:.1f} m"
             if len(suite) > 1 else ""))
    if not paths or options.confirm == 0:
        print(f"suite in {folder}/: failure-NN.yaml (robot/mission keys), legacy/ (drone/test keys), suite.csv, "
              f"suite.png")
        return
    import sys

    from tqdm import tqdm

    from ..reevaluation import evaluate, load_tests, write_report

    bar = tqdm(total=len(paths) * options.confirm, unit="run", desc="confirm", dynamic_ncols=True, file=sys.stderr,
               disable=None)

    def progress(done: int, total: int) -> None:
        bar.n = done
        bar.refresh()

    try:  # fresh noise: the re-runs draw from another base seed than the search's runs
        ev = evaluate(load_tests(paths), runs=options.confirm, seed=options.random_seed + 1, uav=options.uav,
                      workers=options.workers, progress=progress)
    finally:
        bar.close()
    write_report(ev, folder / "confirmation")
    confirmed = sum(s.p >= CONFIRMED_P for s in ev.tests)  # of the re-runs flown: those in error do not count
    errors = sum(s.errors for s in ev.tests)
    print(f"confirmation: {confirmed} of {len(suite)} fail in >= {CONFIRMED_P:.0%} of {options.confirm} re-runs "
          + (f"({errors} re-runs ended in error and are not counted) " if errors else "")
          + f"(report in {folder / 'confirmation'}/report.md)")
    print(f"suite in {folder}/: failure-NN.yaml (robot/mission keys), legacy/ (drone/test keys), suite.csv, "
          f"suite.png")


CONFIRMED_P = 0.6  # a failure probability at least this high over the re-runs: the failure is confirmed
