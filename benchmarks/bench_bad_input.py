"""Bad input, measured: seeded random damage to real logs, plans and test YAMLs, each given to the command line as a
new user would (``surrealist inspect LOG``, ``surrealist simulate TEST``). A clean answer is exit 0 (the damage
left a readable file) or exit 2 with one ``error:`` line naming the file; never a traceback, never over 10 s or
1 GB. Prints the share of clean answers per kind, the slowest and the largest, and every unclean one.

    python benchmarks/bench_bad_input.py [--per-file 12] [--seed 2026]
"""
from __future__ import annotations

import argparse
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "surrealist_gym" / "data"
FORMATS = ROOT.parent / "shared" / "data" / "formats"
LOGS = [DATA / "case0.ulg", FORMATS / "ulog" / "px4tools_19_56_46.ulg",
        FORMATS / "tlog" / "dronekit_log_upload_test.tlog", FORMATS / "dataflash" / "pymavlink_test.BIN"]
TESTS = [DATA / "rq1-seed1.yaml", DATA / "rq2-seed.yaml"]
PLANS = [DATA / "case0.plan", DATA / "auto1.plan"]
QUIET = ["--runs", "1", "--no-plot", "--no-ulog", "--no-reference"]
COMPANIONS = ["case0.plan", "case0-params.csv", "case0-commands.csv", "auto1.plan", "auto1-params.csv",
              "auto-commands.csv"]


def damage(data: bytes, rng: np.random.Generator) -> bytes:
    """One to six edits (flip, delete, insert, cut), half of them in the first 4 KB (headers, definitions)."""
    out = bytearray(data)
    for _ in range(rng.integers(1, 7)):
        if not out:
            break
        span = min(4096, len(out)) if rng.random() < 0.5 else len(out)
        i = int(rng.integers(0, span))
        kind = rng.integers(0, 4)
        if kind == 0:
            out[i] ^= int(rng.integers(1, 256))
        elif kind == 1:
            del out[i:i + int(rng.integers(1, 9))]
        elif kind == 2:
            out[i:i] = bytes([int(rng.integers(0, 256))]) * int(rng.integers(1, 9))
        else:
            del out[i:]
    return bytes(out)


def answer(command: list[str]) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    start = time.perf_counter()
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=60)
        code, err = done.returncode, done.stderr
    except subprocess.TimeoutExpired:
        code, err = None, "timeout after 60 s"
    seconds = time.perf_counter() - start
    rss_mb = max(before, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss) / 1024
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    clean = (code == 0 or (code == 2 and len(errors) == 1)) and "Traceback" not in err
    return {"clean": clean and seconds <= 10.0 and rss_mb <= 1024, "code": code, "seconds": seconds,
            "rss_mb": rss_mb, "error": errors[0] if errors else err.strip().splitlines()[-1:] or ""}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--per-file", type=int, default=12, help="damaged copies of each file (default 12)")
    parser.add_argument("--seed", type=int, default=2026, help="seed of the damage (default 2026)")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    cli = [sys.executable, "-m", "surrealist_gym.cli"]
    results: dict[str, list[dict]] = {"log": [], "test": [], "plan": []}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name in COMPANIONS:
            shutil.copy(DATA / name, folder / name)
        sources = [("log", p) for p in LOGS if p.is_file()] + [("test", p) for p in TESTS] + \
                  [("plan", p) for p in PLANS]
        for kind, source in sources:
            for i in range(args.per_file):
                path = folder / f"bad{i}-{source.name}"
                path.write_bytes(damage(source.read_bytes(), rng))
                if kind == "log":
                    command = cli + ["inspect", str(path), "--no-plot"]
                elif kind == "test":
                    command = cli + ["simulate", str(path), *QUIET, "--out", str(folder / "out")]
                else:  # a damaged plan behind an intact test
                    test = folder / f"bad{i}-test.yaml"
                    test.write_text((DATA / "rq1-seed1.yaml").read_text().replace(
                        "case0.plan", path.name).replace("auto1.plan", path.name))
                    command = cli + ["simulate", str(test), *QUIET, "--out", str(folder / "out")]
                results[kind].append({"file": path.name, **answer(command)})
    print("| input | damaged files | clean answers | exit 2 | slowest [s] | largest [MB] |")
    print("|---|---|---|---|---|---|")
    for kind, rows in results.items():
        if rows:
            clean = sum(r["clean"] for r in rows)
            print(f"| {kind} | {len(rows)} | {clean} ({clean / len(rows):.0%}) | {sum(r['code'] == 2 for r in rows)} | "
                  f"{max(r['seconds'] for r in rows):.1f} | {max(r['rss_mb'] for r in rows):.0f} |")
    for kind, rows in results.items():
        for r in [r for r in rows if r["code"] == 2][:2]:
            print(f"e.g. {kind}: {r['error']}")
    unclean = [r for rows in results.values() for r in rows if not r["clean"]]
    for r in unclean:
        print(f"unclean: {r['file']}: exit {r['code']}, {r['seconds']:.1f} s, {r['rss_mb']:.0f} MB: {r['error']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
