"""Every example runs (as a subprocess, with tiny settings)."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow
ROOT = Path(__file__).resolve().parents[2]

CASES = {
    "replicate_case0.py": ["--budget", "3", "--runs", "1", "--inline"],
    "compare_two_agents.py": ["--repetitions", "2", "--budget", "3", "--runs", "1", "--inline", "--out", "{tmp}"],
    "train_ppo.py": ["--steps", "16", "--budget", "3", "--policy", "{tmp}/ppo.zip"],
    "dask_cluster.py": ["--budget", "2", "--runs", "2"],
    "custom_agent.py": ["--budget", "4"],
    "prescreen_greedy.py": ["--budget", "3", "--runs", "2", "--first-runs", "1", "--kind", "knn"],
    "calibrate_and_replicate.py": [str(ROOT.parent / "shared" / "data" / "surrealist" / "experiments" / "m0.ulg"),
                                   "--budget", "3", "--runs", "1", "--inline"],
    "competition_suite.py": [str(ROOT.parent / "shared" / "data" / "competition" / "case_studies" / "mission1.yaml"),
                             "--budget", "6", "--confirm", "2", "--inline", "--out", "{tmp}/suite"],
}


@pytest.mark.parametrize("script", sorted(CASES))
def test_example_runs(script, tmp_path):
    args = [a.replace("{tmp}", str(tmp_path)) for a in CASES[script]]
    if any(a.endswith((".ulg", ".yaml")) and not Path(a).is_file() for a in args):
        pytest.skip("needs the shared data folder beside the project")
    env = {**os.environ, "PYTHONPATH": str(ROOT), "PYTHONWARNINGS": "ignore"}
    done = subprocess.run([sys.executable, str(ROOT / "examples" / script), *args], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip()


def test_every_example_is_tested():
    assert sorted(p.name for p in (ROOT / "examples").glob("*.py")) == sorted(CASES)
