"""A low-fidelity simulator whose outcomes are features for the surrogate models (multi-fidelity surrogates).

Our own simulator at coarse rates (position loop 10 Hz, planner and log 5 Hz, attitude loop 50 Hz) with no noise
flies a test once. Its flight does not replace the real simulation: the models learn how the real fitness follows
from it (and from the obstacles' geometry).

Outcomes (``NAMES``): the problem's fitness of the low-fidelity flight (replication: -DTW to the reference;
generation: paper eq. 2 of the one run), DTW and Fréchet distance of the trajectory to the reference (0 without a
reference) and their logarithms, the smallest 2-D and 3-D distance to the obstacles, collision, the
flight's duration and its highest point and lateral extent. Results are cached by test key.

Example:
    >>> import surrealist_gym as sg
    >>> from surrealist_gym.aerialist import load_test
    >>> lowfi = LowFidelity(load_test(sg.data_path("rq2-seed.yaml")))
    >>> len(lowfi.outcomes(lowfi.seed_test.obstacles)) == len(NAMES)
    True
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from surrealist_gym.fitness import generation_fitness, replication_fitness
from surrealist_gym.metrics import frechet
from surrealist_gym.outcomes import RunStatus, run_status
from surrealist_gym.sim import NoiseConfig, SimConfig
from surrealist_gym.sim.config import resolve_params
from surrealist_gym.testcase import TestCase

NAMES = ("lowfi_fitness", "lowfi_dtw", "lowfi_frechet", "lowfi_log_dtw", "lowfi_log_frechet", "lowfi_min_dist_2d",
         "lowfi_min_dist", "lowfi_collision", "lowfi_duration", "lowfi_max_z", "lowfi_min_y", "lowfi_max_y")
FITNESS = NAMES[0]
NO_FLIGHT_FITNESS = -1000.0  # a flight with no trajectory (finite: the outcomes are model features)
LOW_FIDELITY = SimConfig(noise=NoiseConfig.off(), control_hz=50.0, outer_hz=10.0, planner_hz=5.0, log_hz=5.0)


class LowFidelity:
    """Flies test cases of one problem with the low-fidelity simulator and measures the outcomes.

    Args:
        seed_test: the problem's seed test (mission, parameters, commands; its obstacles are replaced). The
            parameters of its reference log are frozen into it, so the problem is self-contained.
        reference: the reference trajectory (N, 3) of a replication problem, or None.
    The configuration is ``LOW_FIDELITY`` (fixed, so a saved model featurizes as it was trained).
    """

    config = LOW_FIDELITY

    def __init__(self, seed_test: TestCase, reference=None):
        params = resolve_params(seed_test, self.config)  # frozen in: the stored seed test has no log to read
        self.seed_test = replace(seed_test, params=params, params_file=None, reference_log=None,
                                 commands_file=None, mission_file=None)
        self.reference = None if reference is None else np.asarray(reference, dtype=np.float64)
        self.runs = 0
        self._cache: dict[str, np.ndarray] = {}

    def outcomes(self, obstacles) -> np.ndarray:
        """The outcome vector (``NAMES``) of the seed test with these obstacles."""
        from surrealist_gym.sim import simulate

        test = self.seed_test.with_obstacles(obstacles)
        key = test.key()
        if key not in self._cache:
            run = simulate(test, runs=1, seed=0, config=self.config)[0]
            self.runs += 1
            xyz = np.asarray(run.trajectory, dtype=np.float64).reshape(-1, 3)
            d = f = 0.0
            if not len(xyz):
                fitness, top = NO_FLIGHT_FITNESS, (0.0, 0.0, 0.0)
            else:
                top = (xyz[:, 2].max(), xyz[:, 1].min(), xyz[:, 1].max())
                if self.reference is not None:
                    fitness, _ = replication_fitness(self.reference, [xyz])  # one run: its own average
                    d, f = -fitness, frechet(self.reference, xyz)
                else:
                    fitness = generation_fitness([xyz], test.obstacles).fitness
            self._cache[key] = np.array([fitness, d, f, np.log1p(d), np.log1p(f), min(run.min_distance_2d, 50.0),
                                         min(run.min_distance, 50.0), float(run_status(run) is RunStatus.COLLISION),
                                         run.duration, *top])
        return self._cache[key]

    def fitness(self, obstacles) -> float:
        """The problem's fitness of the low-fidelity flight with these obstacles (``lowfi_fitness``)."""
        return float(self.outcomes(obstacles)[0])

    def save(self, folder) -> None:
        """Write the problem (seed test with its mission and frozen parameters; the reference) to ``folder``."""
        from surrealist_gym.aerialist import save_test
        from surrealist_gym.mission import write_plan

        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        test = self.seed_test
        if test.mission is not None:
            write_plan(test.mission, folder / "lowfi-mission.plan")
            test = replace(test, mission_file=str((folder / "lowfi-mission.plan").resolve()))
        save_test(test, folder / "lowfi-seed.yaml")
        if self.reference is not None:
            np.save(folder / "lowfi-reference.npy", self.reference)

    @classmethod
    def load(cls, folder) -> "LowFidelity":
        """The problem :meth:`save` wrote to ``folder``."""
        from surrealist_gym.aerialist import load_test

        folder = Path(folder)
        ref = folder / "lowfi-reference.npy"
        seed = folder / "lowfi-seed.yaml"
        return cls(load_test(seed, allow_outside=_named_folders(seed)), np.load(ref) if ref.is_file() else None)


def _named_folders(path: Path) -> list[str]:
    """The folders of the files :meth:`LowFidelity.save`'s YAML names by absolute path (the seed test's params,
    commands and reference log, where the model was trained): the model's own file may read there."""
    import os

    from surrealist_gym.errors import SurrealistError, safe_yaml

    try:
        doc = safe_yaml(path.read_text(encoding="utf-8"), str(path))
    except (OSError, UnicodeDecodeError, SurrealistError):
        return []  # load_test says what is wrong
    sections = doc.values() if isinstance(doc, dict) else ()
    return sorted({os.path.dirname(value) for section in sections if isinstance(section, dict)
                   for key, value in section.items()
                   if key.endswith("_file") and isinstance(value, str) and os.path.isabs(value)})

