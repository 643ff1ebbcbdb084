"""Close-region agreement of one SimConfig variant on one split of rilast-mission1 (dev = even runs, held = odd).

    python benchmarks/lab/2026-11-24-sitl-pace/variants.py dev close 1 '{"planner": {"heading_offset_deg": 16}}'

The last argument overrides settings of the px4-v1.12-sitl-iris profile's SimConfig (``planner``: its avoidance
config). The cap variants of the README (``cruise_speed_max``, since removed) run at commit dd02d7e.
"""
import sys, json, time, dataclasses, re
import numpy as np
from surrealist_gym.fidelity.measure import load_labelled_set, fly_labelled_set, build_report
from surrealist_gym.sim.profiles import load_profile
from pathlib import Path
DATA = str(Path(__file__).resolve().parents[3].parent / "shared" / "data")
split = sys.argv[1]  # dev | held
region = sys.argv[2]  # close | all
every = int(sys.argv[3]) if len(sys.argv) > 3 else 1
changes = json.loads(sys.argv[4]) if len(sys.argv) > 4 else {}
lset = load_labelled_set(DATA + '/competition/rilast-mission1/tests.csv')
keep = []
for i, lab in enumerate(lset.labels):
    run = int(re.search(r'run(\d+)_', lab.test_id).group(1))
    if (run % 2 == 0) != (split == 'dev'):
        continue
    if region == 'close' and not (lab.result == 'flown' and lab.distance < 3.0):
        continue
    keep.append(i)
keep = keep[::every]
sub = dataclasses.replace(lset, labels=tuple(lset.labels[i] for i in keep), tests=tuple(lset.tests[i] for i in keep))
cfg = load_profile('px4-v1.12-sitl-iris').sim_config()
plan = changes.pop('planner', {})
if plan:
    cfg = dataclasses.replace(cfg, avoidance_config=dataclasses.replace(cfg.avoidance_config, **plan))
cfg = dataclasses.replace(cfg, **changes)
t = time.time()
out = fly_labelled_set(sub, 1, 0, cfg, 2, 0.0, None)
rep = build_report(sub, out, wall_s=time.time() - t)
o, c = rep.overall, rep.close
ours = np.array([r.distance for r in rep.rows if r.label.result == 'flown'])
theirs = np.array([r.label.distance for r in rep.rows if r.label.result == 'flown'])
ok = np.isfinite(ours)
print(f"{split}/{region} n={len(sub)} {sys.argv[4] if len(sys.argv) > 4 else '{}'}: spearman {c.spearman:.3f} auc {c.auc:.3f} "
      f"prec/rec {c.precision:.2f}/{c.recall:.2f} best_rec {c.best_recall:.2f}@{c.best_threshold_m:.2f} "
      f"fail theirs/ours {c.their_failure_rate:.2f}/{c.our_failure_rate:.2f} median(ours-theirs) {np.median(ours[ok]-theirs[ok]):.2f} "
      f"all-spearman {o.spearman:.3f} statuses {dict(rep.to_dict()['our_statuses'])} wall {rep.wall_s:.0f}s")
