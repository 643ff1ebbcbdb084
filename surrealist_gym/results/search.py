"""What a search writes in its results folder: best test (Aerialist YAML + its files: :func:`export_test`, which the
suite export uses too), evaluations.csv, summary.json, and plots in the paper's style (Figure 1: real vs seed vs
best, top view and altitude, horizontal speed and distance to the goal over time; Figure 2: fitness over evaluations
and per-run minimum distances of seed and best).

Time base of the profiles: the real flight (``env.reference``) keeps its own times; the seed's and best's
trajectories (one run, or the DBA average of the runs, all from the paper's pipeline of 0.5 s window means) carry
no times and are taken as sampled every 0.5 s (:data:`~surrealist_gym.trajectory.WINDOW_S`).
"""
from __future__ import annotations

import csv
import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..aerialist import save_test
from ..errors import SurrealistError
from ..outcomes import UNSAFE_DISTANCE_M, Measure, judged_distance, outcomes
from ..sim.profiles import save_profile
from ..sim.uav import uav_settings
from ..store import EvaluationStore
from ..testcase import TestCase
from ..trajectory import Profile, profile

#: Where :func:`export_test` copies the files a test names (the folder the competition's own YAMLs name them in).
FILES_FOLDER = "case_studies"
_FILE_FIELDS = ("mission_file", "params_file", "commands_file", "reference_log")
README_TITLE = "# Aerialist test cases"


def write_results(out: Path, env, result, wall_seconds: float, problem: str) -> dict:
    """Write the results folder of a finished (or interrupted) search; returns the summary."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    env = env.unwrapped
    seed_eval, best_eval = env.seed_evaluation, env.best
    export_test(best_eval.test, out / "best.yaml")  # its files copied into the folder: Aerialist loads it from there
    measure = Measure(getattr(env, "distance_measure", Measure.PAPER))
    rows = write_evaluations_csv(env.evaluator.store, out / "evaluations.csv", measure)
    best_outcomes = outcomes(best_eval.runs, measure)
    summary = {
        "problem": problem,
        "uav": env.evaluator.sim_config.profile,
        "distance": measure.value,
        "seed_fitness": seed_eval.fitness, "best_fitness": best_eval.fitness,
        "seed_terms": seed_eval.terms, "best_terms": best_eval.terms,
        "evaluations": result.evaluations, "evaluations_to_best": result.evaluations_to_best,
        # flown by the whole search (a resumed one: before and after the interruption), and by this process
        "simulations": env.evaluator.search_simulations,
        "simulations_since_start": env.evaluator.simulations, "runs_per_evaluation": env.evaluator.runs,
        "budget": env.budget, "stop_reason": result.stop_reason,
        "wall_seconds": round(wall_seconds, 3),
        "seconds_per_evaluation": round(wall_seconds / max(1, rows), 3),
        "seed_obstacles": [o.to_dict() for o in seed_eval.test.obstacles],
        "best_obstacles": [o.to_dict() for o in best_eval.test.obstacles],
        "best_mutation": {m.name: float(v) for m, v in zip(env.mutators, env.values_for(result.best_action))},
        "seed_runs": [r.to_dict() for r in seed_eval.runs], "best_runs": [r.to_dict() for r in best_eval.runs],
        "best_unsafe_rate": best_outcomes.unsafe_rate, "best_crash_rate": best_outcomes.crash_rate,
        "best_stuck_rate": best_outcomes.blocked_rate,
    }
    settings = uav_settings(best_eval.test)
    summary["best_uav_settings"] = settings
    profile = env.uav.profile
    if settings and profile is not None:  # the UAV configuration the search found
        save_profile(profile.with_settings(settings, name=f"{profile.name}-found",
                                           description=f"{profile.name} with the UAV settings of "
                                                       f"the best test ({out.name})"),
                     out / "best-uav.yaml")
    reference = getattr(env, "reference", None)
    goal = search_goal(seed_eval, reference)
    summary["goal"] = None if goal is None else [round(float(v), 3) for v in goal]
    profiles = search_profiles(seed_eval, best_eval, reference, goal)
    summary["profiles"] = {k: p.summary() for k, p in profiles.items()}
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=_jsonable) + "\n")
    env.uav.write(out)
    plot_search(out, seed_eval, best_eval, result.history, reference, measure, goal=goal, profiles=profiles)
    return summary


def search_goal(seed_eval, reference=None):
    """The goal of the distance-to-goal profiles: the real flight's last point when replicating, else the last
    waypoint of the seed's mission, else the last point of the seed's trajectory (None: nothing to go by)."""
    if reference is not None and len(reference):
        return np.asarray(reference)[-1]
    mission = getattr(seed_eval.test, "mission", None)
    if mission is not None and mission.waypoints:
        return np.asarray(mission.waypoints[-1], dtype=np.float64)
    if seed_eval.trajectory is not None and len(seed_eval.trajectory):
        return np.asarray(seed_eval.trajectory)[-1]
    return None


def search_profiles(seed_eval, best_eval, reference=None, goal=None) -> dict[str, Profile]:
    """Profiles over time of ``real`` (when there is one), ``seed`` and ``best`` (those with a trajectory)."""
    named = {"real": reference, "seed": seed_eval.trajectory, "best": best_eval.trajectory}
    return {k: profile(v, goal) for k, v in named.items() if v is not None and len(v)}


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    return str(value)


def export_test(test: TestCase, path) -> None:
    """Save the test at ``path`` (:func:`~surrealist_gym.aerialist.save_test`) as a file that travels with its folder:
    every file it names (mission, parameters, commands, the assertion's flight log) is copied into ``FILES_FOLDER``
    beside it and named by a path relative to the YAML's folder, and the folder gets a README saying to run Aerialist
    from it (Aerialist opens relative paths from its working directory). Files of the same name and other content
    get ``-2``, ``-3``, ... A copy that fails is a one-line SurrealistError.

    Example::

        >>> export_test(load_test("seed.yaml"), "out/best.yaml")  # out/case_studies/auto1.plan, ...  # doctest: +SKIP
    """
    path = Path(path)
    folder = path.parent
    copies = {key: _copy_into(getattr(test, key), folder / FILES_FOLDER)
              for key in _FILE_FIELDS if getattr(test, key)}
    save_test(replace(test, **copies), path)
    _write_readme(folder)


def _copy_into(source: str, files: Path) -> str:
    """``source`` copied into the folder ``files`` under its own name (or ``NAME-2`` ... when another file holds
    it); the copy's absolute path. A file already there with the same bytes is the copy."""
    source_path = Path(source)
    try:
        data = source_path.read_bytes()
        files.mkdir(parents=True, exist_ok=True)
        target, n = files / source_path.name, 1
        while target.exists() and target.read_bytes() != data:
            n += 1
            target = files / f"{source_path.stem}-{n}{source_path.suffix}"
        if not target.exists():
            shutil.copyfile(source_path, target)
    except OSError as err:
        raise SurrealistError(f"{source}: cannot copy it into {files} ({err.strerror or err})") from None
    return str(target.resolve())


def _write_readme(folder: Path) -> None:
    """The folder's README (not written over one that is not ours)."""
    readme = folder / "README.md"
    if readme.exists() and not readme.read_text(encoding="utf-8", errors="replace").startswith(README_TITLE):
        return
    readme.write_text(
        f"{README_TITLE}\n\n"
        f"The YAML files in this folder load in Aerialist master (`robot`/`mission` keys), Aerialist 0.2.x "
        f"(`drone`/`test` keys) and surrealist-gym. They name their mission, parameter and command files (and any "
        f"flight log) by paths relative to this folder, in `{FILES_FOLDER}/`.\n\n"
        f"Aerialist opens relative paths from its working directory: run it from this folder, e.g.\n\n"
        f"    cd {folder.name}\n"
        f"    python3 -m aerialist exec --test NAME.yaml\n\n"
        f"surrealist-gym resolves them against the YAML's folder, from anywhere: "
        f"`surrealist simulate {folder.name}/NAME.yaml`. The folder moves as a whole.\n", encoding="utf-8")


def write_evaluations_csv(store: EvaluationStore | None, path: Path, measure: Measure | str = Measure.PAPER) -> int:
    """One row per stored evaluation, in order; ``unsafe`` and ``min_distance`` by ``measure``, ``flight_s`` the mean
    simulated time of its runs [s]; returns the number of rows."""
    rows = list(store) if store is not None else []
    n_obstacles = max((len(r.test.get("obstacles", [])) for r in rows), default=0)
    header = ["evaluation", "fitness", "runs", "collisions", "unsafe", "min_distance", "sim_seconds", "flight_s"]
    for i in range(n_obstacles):
        header += [f"o{i}_{k}" for k in ("l", "w", "h", "x", "y", "z", "r")]
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        for n, row in enumerate(rows, start=1):
            judged = outcomes(row.runs, measure)
            line = [n, row.fitness, len(row.runs), judged.crashes, judged.unsafe,
                    judged.closest if row.runs else "", round(row.sim_seconds, 4),
                    round(sum(r["duration"] for r in row.runs) / len(row.runs), 3) if row.runs else ""]
            for o in row.test.get("obstacles", []):
                line += [o["size"]["l"], o["size"]["w"], o["size"]["h"], o["position"]["x"], o["position"]["y"],
                         o["position"]["z"], o["position"]["r"]]
            writer.writerow(line)
    return len(rows)


def plot_search(out: Path, seed_eval, best_eval, history, reference=None,
                measure: Measure | str = Measure.PAPER, goal=None, profiles=None) -> None:
    """figure1.png (top view of trajectories and obstacles; altitude, horizontal speed and distance to ``goal``
    over time), fitness.png and min_distances.png. ``goal`` None: :func:`search_goal`; ``profiles`` None:
    :func:`search_profiles`."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon

    if goal is None:
        goal = search_goal(seed_eval, reference)
    fig = plt.figure(figsize=(14, 7))
    grid = fig.add_gridspec(3, 2, width_ratios=[1.2, 1])
    top = fig.add_subplot(grid[:, 0])
    alt = fig.add_subplot(grid[0, 1])
    speed = fig.add_subplot(grid[1, 1], sharex=alt)
    to_goal = fig.add_subplot(grid[2, 1], sharex=alt)
    if profiles is None:
        profiles = search_profiles(seed_eval, best_eval, reference, goal)
    lines = [("real", "real flight", reference, "k", 2.5), ("seed", "seed", seed_eval.trajectory, "tab:orange", 1.5),
             ("best", "best", best_eval.trajectory, "tab:blue", 1.5)]
    for key, label, traj, colour, width in lines:
        if key not in profiles:
            continue
        xyz = np.asarray(traj)
        top.plot(xyz[:, 1], xyz[:, 0], color=colour, lw=width, label=label)
        p = profiles[key]
        alt.plot(p.t, p.altitude, color=colour, lw=width, label=label)
        speed.plot(p.t, p.horizontal_speed, color=colour, lw=width, label=label)
        to_goal.plot(p.t, p.distance_to_goal, color=colour, lw=width, label=label)
    if goal is not None:
        top.plot([goal[1]], [goal[0]], "*", color="tab:green", ms=12, label="goal")
    for evaluation, colour, style in ((seed_eval, "tab:orange", "--"), (best_eval, "tab:blue", "-")):
        for o in evaluation.test.obstacles:
            if o.shape.value == "cylinder":
                patch = Circle((o.y, o.x), o.l / 2, fill=False, ec=colour, ls=style)
            else:
                patch = Polygon([(y, x) for x, y in o.footprint()], closed=True, fill=False, ec=colour, ls=style)
            top.add_patch(patch)
    top.set_xlabel("east [m]")
    top.set_ylabel("north [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.legend(loc="best", fontsize=8)
    top.set_title("top view (obstacles: seed dashed, best solid)")
    alt.set_ylabel("altitude [m]")
    alt.set_title("over time (simulated: 0.5 s samples)")
    alt.legend(loc="best", fontsize=8)
    speed.set_ylabel("horizontal speed [m/s]")
    to_goal.set_ylabel("distance to goal [m]")
    to_goal.set_xlabel("time [s]")
    for ax in (alt, speed):
        ax.tick_params(labelbottom=False)
    fig.tight_layout()
    fig.savefig(out / "figure1.png", dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 4))
    values = np.array(history, dtype=float)
    finite = np.isfinite(values)
    ax.plot(np.flatnonzero(finite), values[finite], ".", color="0.5", label="evaluated")
    ax.plot(np.maximum.accumulate(np.where(finite, values, -np.inf)), color="tab:blue", label="best so far")
    ax.set_xlabel("step (0 = seed)")
    ax.set_ylabel("fitness")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "fitness.png", dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5, 4))
    data = [[judged_distance(r, measure) for r in e.runs] for e in (seed_eval, best_eval)]
    ax.boxplot(data)
    ax.set_xticks([1, 2], ["seed", "best"])
    for i, d in enumerate(data, start=1):
        ax.plot(np.full(len(d), i), d, "o", alpha=0.6)
    ax.axhline(UNSAFE_DISTANCE_M, color="tab:red", ls="--", label="unsafe (1.5 m)")
    ax.set_ylabel("competition distance per run [m]" if Measure(measure) is Measure.COMPETITION
                  else "minimum 2-D distance to obstacles per run [m]")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "min_distances.png", dpi=110)
    plt.close(fig)
