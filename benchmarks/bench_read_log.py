"""Time to read the real flight case0.ulg into its trajectory, against pyulog's parse time alone (same run).

Run from the project root::

    python benchmarks/bench_read_log.py [--repeat 9]

Prints the median of ``--repeat`` runs of: pyulog parsing every topic; pyulog parsing only the topics our reader
decodes; ``read_flight(...).trajectory`` (that parse + selection + validity checks + mission + pipeline).
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

CASE0 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "surrealist" / "experiments" / "case0.ulg"


def _median_s(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=9)
    parser.add_argument("--log", default=str(CASE0))
    args = parser.parse_args()

    from pyulog import ULog

    from surrealist_gym.logs import read_flight
    from surrealist_gym.logs.ulog import TOPICS

    read_flight(args.log)  # warm imports and the file cache
    full = _median_s(lambda: ULog(args.log), args.repeat)
    filtered = _median_s(lambda: ULog(args.log, TOPICS), args.repeat)
    ours = _median_s(lambda: read_flight(args.log).trajectory, args.repeat)
    print(f"log: {args.log} ({Path(args.log).stat().st_size / 1e6:.2f} MB), median of {args.repeat} runs")
    print(f"pyulog parse, all topics            {full * 1e3:8.1f} ms")
    print(f"pyulog parse, the {len(TOPICS)} topics we use     {filtered * 1e3:8.1f} ms")
    print(f"read_flight(...).trajectory         {ours * 1e3:8.1f} ms")
    print(f"ratio read_flight / pyulog (same topics) {ours / filtered:6.2f}")
    print(f"ratio read_flight / pyulog (all topics)  {ours / full:6.2f}")


if __name__ == "__main__":
    main()
