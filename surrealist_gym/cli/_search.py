"""What `surrealist replicate` and `surrealist generate` share: options, progress bar, results folder, resume."""
from __future__ import annotations

import dataclasses
import json
import sys
import time
from collections import Counter
from contextlib import contextmanager
from pathlib import Path

from ..errors import SurrealistError
from ..results import RUN_FILE, ResultsFolder
from .options import SearchOptions, check_writable, default_out


@contextmanager
def search_folder(args, options_type: type[SearchOptions]):
    """Yield (folder, options) from :func:`prepare`, the folder locked against a second writer until the search
    ends and kept on failure once it stores an evaluation (:meth:`ResultsFolder.keeping
    <surrealist_gym.results.ResultsFolder.keeping>`), with the ``--resume`` that finishes it."""
    folder, options = prepare(args, options_type)
    with folder.keeping(f"--resume {folder.path} flies the rest", "evaluation(s)"):
        yield folder.path, options


def stored_evaluations(out: Path) -> int:
    """How many evaluations the results folder's store holds (an unreadable store counts as holding some, so it
    is never removed)."""
    return ResultsFolder(out, "search").stored()


def _given(args, options_type: type[SearchOptions]) -> dict:
    """The options on the command line, their paths made absolute as a new search records them."""
    from ..envs.replicate import SEEDS
    from ..sim.profiles import PRESETS

    values = {f.name: getattr(args, f.name, f.default) for f in dataclasses.fields(options_type)}
    for key in ("log", "test", "seed", "uav", "case_study"):
        value = values.get(key)
        if isinstance(value, str) and value and not (key == "seed" and value in SEEDS) and \
                not (key == "uav" and value in PRESETS) and (key != "case_study" or value.endswith((".yaml", ".yml"))):
            values[key] = str(Path(value).resolve())
    return values


def prepare(args, options_type: type[SearchOptions]) -> tuple[ResultsFolder, SearchOptions]:
    """The results folder, claimed, and the options of this search: new, or read back from its run.json when it
    resumes (``--resume DIR``, or ``--out DIR`` naming a folder that holds this search: the same command again)."""
    command = options_type.command
    if args.resume or (args.out and (Path(args.out) / RUN_FILE).is_file()):
        flag = "--resume" if args.resume else "--out"
        out = check_writable(args.resume or args.out, flag)
        if args.resume and args.out and Path(args.out).absolute() != out.absolute():
            raise SurrealistError(f"--out {args.out}: --resume writes to the folder it resumes ({out})")
        folder = ResultsFolder.claim(out, command, None, resume_only=True, flag=flag)
        try:
            options = _resumed(args, options_type, out, flag)
        except BaseException:
            folder.release()
            raise
        return folder, options
    options = options_type.from_args(args)
    if options.agent not in (None, "greedy"):
        from search.registry import make_agent

        make_agent(options.agent)  # an unknown agent fails here, before any folder or worker exists
    changes = {}
    if options.uav is not None:  # a bad profile fails here, before any folder exists
        from ..sim.uav import recorded_choice

        changes["uav"] = recorded_choice(options.uav)
    from ..envs.replicate import SEEDS

    seed = getattr(options, "seed", None)
    if seed and seed not in SEEDS and not Path(seed).is_file():
        raise SurrealistError(f"--seed {seed}: not a test YAML file nor one of {', '.join(SEEDS)}")
    for key in ("log", "test", "seed"):
        if getattr(options, key, None) and not (key == "seed" and options.seed in SEEDS):
            changes[key] = str(Path(getattr(options, key)).resolve())
    options = measured_prescreen(dataclasses.replace(options, **changes))
    out = check_writable(args.out or default_out(command), "--out")
    settings = {k: v for k, v in options.to_json().items() if k != "command"}
    return ResultsFolder.claim(out, command, settings, free=("workers", "dask_scheduler")), options


def _resumed(args, options_type: type[SearchOptions], out: Path, flag: str) -> SearchOptions:
    """The options run.json records; an option typed again must be the one it was started with (only where it
    runs changes: --workers, --dask-scheduler)."""
    saved = out / RUN_FILE
    options = options_type.from_json(saved)
    flags = getattr(args, "_flags", frozenset())  # options typed on the command line, even at their defaults
    given = _given(args, options_type)
    for f in dataclasses.fields(options_type):  # what the command line changes: where it runs, nothing else
        value, typed = given[f.name], f.metadata.get("flag", "--" + f.name.replace("_", "-"))
        if f.name in ("workers", "dask_scheduler"):
            if value is not None:  # where it runs now: --workers alone leaves the cluster it ran on before
                other = {"workers": "dask_scheduler", "dask_scheduler": "workers"}[f.name]
                moved = {other: None} if getattr(args, other, None) is None else {}
                options = dataclasses.replace(options, **{f.name: value, **moved})
        elif f.name != "agent" and (typed in flags or value != f.default) and \
                _jsonish(value) != _jsonish(getattr(options, f.name)):
            raise SurrealistError(f"{typed}: the search in {out} was started with {getattr(options, f.name)!r}; "
                                  f"resuming ({flag} {out}) keeps its options (only --workers and --dask-scheduler "
                                  f"change)")
    from search.registry import POLICY_PREFIXES

    module = options.agent.split(":", 1)[0] if ":" in (options.agent or "") else None
    if module not in (None, *POLICY_PREFIXES) and args.agent != options.agent:
        raise SurrealistError(f"{saved}: the search's agent {options.agent!r} is code from module {module!r}; "
                              f"resuming would import it: give --agent {options.agent} to confirm")
    return options


def _jsonish(value):
    return list(value) if isinstance(value, tuple) else value


def measured_prescreen(options: SearchOptions) -> SearchOptions:
    """``--surrogate MODEL`` with none of the expert pre-screening flags: the measured settings for the noise mode
    the model was trained in (surrogates.config.MEASURED_PRESCREEN; none for an online model or a model whose mode
    is unknown), said in one line."""
    expert = options.first_runs or options.screen != "auto" or options.skips_spend_budget or options.verify_stop
    if not options.surrogate or options.surrogate == "online" or expert:
        return options
    from surrogates.config import SkipAccounting, measured_prescreen as measured
    from surrogates.models import saved_noise_mode

    common = saved_noise_mode(options.surrogate)  # an unreadable model: its own loading says what is wrong
    settings = measured(common, options.command, options.runs)
    if not settings:
        return options
    flags = {"rule": "screen", "first_runs": "first_runs", "skips": "skips_spend_budget", "verify_stop": "verify_stop"}
    changes = {flags[k]: v is SkipAccounting.BUDGET if k == "skips" else v for k, v in settings.items()}
    mode = "common noise" if common else "each test's own noise"
    print(f"--surrogate {options.surrogate}: a model trained with {mode}; pre-screening as measured: "
          + ", ".join(f"{k}={v}" for k, v in changes.items()), file=sys.stderr)
    return dataclasses.replace(options, **changes)


def run_search(env, options: SearchOptions, out: Path, problem: str) -> int:
    """Run the greedy on env with a live progress bar, then write the results folder and print where."""
    from tqdm import tqdm

    from search import AdaptiveGreedy

    from ..outcomes import judged_distance
    from ..results import write_results

    name = options.agent or "greedy"
    if name == "greedy":
        agent = AdaptiveGreedy(options.preset)
    else:
        from search.registry import make_agent

        agent = make_agent(name, seed=options.random_seed)
    stages = options.first_runs
    if options.prescreened:
        from surrogates.config import PrescreenConfig, SkipAccounting
        from surrogates.prescreened import wrap

        skips = SkipAccounting.BUDGET if options.skips_spend_budget else SkipAccounting.EVALUATION
        config = PrescreenConfig.of(rule=options.screen or "auto", first_runs=stages, skips=skips,
                                    verify_stop=options.verify_stop)
        agent = wrap(agent, options.surrogate or "online", env, config)
    prescreener = getattr(agent, "prescreener", None)
    bar = tqdm(total=options.budget, unit="eval", desc=problem, dynamic_ncols=True, file=sys.stderr,
               disable=None)
    start = time.perf_counter()

    def progress(info: dict) -> None:
        bar.n = min(info["evaluations"], bar.total)
        bar.set_postfix(best=f"{info['best_fitness']:.2f}", memo=info.get("memo", False), refresh=False)
        bar.refresh()

    try:
        result = agent.run(env, seed=options.random_seed, callback=progress)
        bar.n = min(result.evaluations, bar.total)
        bar.close()
        summary = write_results(out, env, result, time.perf_counter() - start, problem)
        if prescreener is not None:
            (out / "skipped.json").write_text(json.dumps(prescreener.skipped, indent=1, default=str) + "\n")
    except KeyboardInterrupt:
        bar.close()
        env.close()
        stored = stored_evaluations(out)
        print(f"interrupted: {stored} evaluation(s) are stored in {out}; --resume {out} flies the rest",
              file=sys.stderr)
        return 130
    finally:
        bar.close()
        env.close()  # its pool's workers hold the folder's lock file (inherited) until they end
    if prescreener is not None:
        raced = prescreener.dropped
        ties = sum(bool(s.get("tie")) for s in prescreener.skipped)
        margin = "/".join("not calibrated" if m is None else f"{m:.2f}" for m in prescreener.race_margins.values())
        against = "fitness" if prescreener.calibration.race.against == "fitness" else "same first runs"
        print(f"pre-screening ({prescreener.rule}): {len(prescreener.skipped) - raced} candidates skipped without a "
              f"simulation"
              + (f", {raced} dropped after their first {'/'.join(map(str, stages))} runs ({ties} of them tied the "
                 f"best; racing margin {margin} below the best's {against})" if stages else "") + " (skipped.json)")
    print(f"{problem}: seed fitness {summary['seed_fitness']:.2f} -> best {summary['best_fitness']:.2f} "
          f"after {summary['evaluations_to_best']} of {summary['evaluations']} evaluations "
          f"({summary['simulations']} simulations, {summary['wall_seconds']:.1f} s)")
    for key, value in summary["best_terms"].items():
        if isinstance(value, float):
            print(f"  best {key}: {value:.2f} (seed {summary['seed_terms'].get(key, float('nan')):.2f})")
    for label in ("seed", "best"):
        runs = summary[f"{label}_runs"]
        statuses = Counter(r["status"] for r in runs)
        measure = summary.get("distance", "paper")
        closest = min((judged_distance(r, measure) for r in runs), default=float("nan"))
        print(f"  {label} runs: " + ", ".join(f"{n} {s}" for s, n in statuses.most_common())
              + f"; closest approach {closest:.2f} m ("
              + ("competition distance" if measure == "competition" else "2-D clearance") + ")")
    print(f"results in {out}/: best.yaml, evaluations.csv, summary.json, figure1.png, fitness.png, "
          f"min_distances.png")
    return 0
