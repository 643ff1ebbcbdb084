"""Ship the policy for every mission: copy the last part trained by ``benchmarks/train_pretrained.sh`` into the package
(``surrealist_gym/data/policies/ppo-missions.zip``, what ``ppo-sample:pretrained`` loads) with a record of how it was
trained: every part's settings and what it met, the steps and wall time in all, and the commands that retrain it.

Usage::

    python benchmarks/ship_pretrained.py results/pretrained
"""
from __future__ import annotations

import json
import re
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET = ROOT / "surrealist_gym" / "data" / "policies" / "ppo-missions.zip"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    folder = Path(argv[0] if argv else "results/pretrained")
    parts = sorted(folder.glob("part*.json"), key=lambda p: int(re.sub(r"\D", "", p.stem)))
    if not parts:
        print(f"{folder}: no part*.json (train with benchmarks/train_pretrained.sh first)", file=sys.stderr)
        return 2
    records = [json.loads(p.read_text()) for p in parts]
    if any(r.get("problem") != "missions" or "interrupted_after_steps" in r for r in records):
        print(f"{folder}: every part must be a finished `train --problem missions`", file=sys.stderr)
        return 2
    TARGET.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(parts[-1].with_suffix(".zip"), TARGET)
    steps = sum(r["steps"] for r in records)
    summary = {"problem": "missions", "frame": "mission", "algorithm": records[-1]["algorithm"], "steps": steps,
               "parts": len(records), "wall_seconds": round(sum(r["wall_seconds"] for r in records), 1),
               "retrain": f"bash benchmarks/train_pretrained.sh {len(records)} {folder} && "
                          f"python benchmarks/ship_pretrained.py {folder}",
               "part_records": [{k: v for k, v in r.items() if k not in ("policy", "init")} for r in records]}
    TARGET.with_suffix(".json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"shipped {parts[-1].with_suffix('.zip')} as {TARGET} ({steps} steps in {len(records)} parts, "
          f"{summary['wall_seconds']:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
