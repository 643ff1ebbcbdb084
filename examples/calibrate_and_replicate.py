"""Calibrate the UAV on a log, then replicate the log searching the obstacles and the UAV's settings.

    python examples/calibrate_and_replicate.py ../shared/data/surrealist/experiments/m0.ulg --budget 100 --runs 5
    python examples/calibrate_and_replicate.py LOG --budget 3 --runs 1 --inline      # a quick look (CI)

The same as ``surrealist calibrate LOG --profile uav.yaml`` then ``surrealist replicate LOG --uav uav.yaml
--search-uav``, through the Python API (docs/calibration.md).
"""
import argparse

import surrealist_gym as sg
from search import AdaptiveGreedy
from surrealist_gym.envs.replicate import ReplicateEnv
from surrealist_gym.executors import InlineExecutor, LocalPoolExecutor
from surrealist_gym.fidelity.calibration import calibrate, format_calibration
from surrealist_gym.sim.profiles import test_uav_settings

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("log", help="a PX4 flight log with a mission (.ulg, .tlog, .bin)")
parser.add_argument("--budget", type=int, default=20)
parser.add_argument("--runs", type=int, default=1)
parser.add_argument("--inline", action="store_true", help="simulate in this process")
args = parser.parse_args()

flight = sg.read_flight(args.log)
executor = InlineExecutor() if args.inline else LocalPoolExecutor(2)
fitted = calibrate([flight], runs=1 if args.inline else 2, executor=executor)
print(format_calibration(fitted))

env = ReplicateEnv(args.log, uav=fitted.profile, uav_mutators=True, budget=args.budget, runs=args.runs,
                   executor="inline" if args.inline else None)
result = AdaptiveGreedy("authors").run(env, seed=0)
seed, best = env.seed_evaluation, env.best
print(f"DTW {seed.terms['dtw']:.1f} -> {best.terms['dtw']:.1f} (Frechet {seed.terms['frechet']:.2f} m -> "
      f"{best.terms['frechet']:.2f} m) after {result.evaluations_to_best} of {result.evaluations} evaluations")
print("best UAV settings:", test_uav_settings(best.test) or "the calibrated ones")
env.close()
executor.close()
