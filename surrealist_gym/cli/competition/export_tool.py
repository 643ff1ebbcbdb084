"""``surrealist export-tool DIR``: write a UAV Testing Competition tool folder that chooses its tests with
surrealist-gym's simulator and spends the real (PX4 SITL) budget on the best of them.

``python3 DIR/cli.py generate CASE_STUDY BUDGET`` searches the case study in our simulator (``surrealist generate
--case-study``, ``--sim-budget-factor`` x BUDGET evaluations), executes its ranked failures through Aerialist's agents,
best first, at most BUDGET, and writes those that fail in their real flight (docs/export-tool.md).

Example::

    surrealist export-tool tmp/tool
    surrealist compete tmp/tool mission2 10      # the tool, unedited, with our simulator standing in for PX4
"""
from __future__ import annotations

import argparse


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``surrealist export-tool``."""
    from ...competition.export_tool import AGENTS, ToolSettings
    from ..options import add_random_seed_argument

    default = ToolSettings()
    parser.add_argument("dir", metavar="DIR", help="the tool's folder to write (new or empty)")
    parser.add_argument("--sim-budget-factor", type=int, default=default.sim_budget_factor,
                        help="the simulator's evaluations per real simulation: the tool's search flies this times "
                             "BUDGET (default %(default)s)")
    parser.add_argument("--obstacles", type=int, default=default.obstacles, metavar="N",
                        help="boxes per test, 1-3 (default %(default)s)")
    parser.add_argument("--confirm", type=int, default=default.confirm,
                        help="re-runs of each failure in the simulator before ranking (default %(default)s)")
    parser.add_argument("--buffer", type=float, default=default.buffer, metavar="M",
                        help="the search's competition distance: half width added to the flight's polyline [m] "
                             "(default %(default)s, Aerialist master's, as the competition measures)")
    add_random_seed_argument(parser, f"seed of the tool's search and of the simulator's noise (default "
                                     f"{default.seed})", default=default.seed)
    parser.add_argument("--workers", type=int, default=default.workers, metavar="N",
                        help="simulator processes the tool uses (default %(default)s: the competition gives a tool "
                             "1.5 vCPU)")
    parser.add_argument("--agent", default=default.agent, choices=AGENTS,
                        help="the tool's search in the simulator: suite (default: distinct failures), or cmaes, "
                             "random, greedy, to compare searches under the competition's rules")
    parser.add_argument("--px4-verdict", action="store_true",
                        help="the tool's search ranks its failures by the model of PX4 SITL's verdict (P(PX4 < 1.5 m) "
                             "x expected test score) before spending the real budget (generate --px4-verdict; default "
                             "off)")


def run(args: argparse.Namespace) -> int:
    """Run the command; returns the exit code."""
    from ...competition.export_tool import SETTINGS_FILE, ToolSettings, write_tool
    from ..options import check_writable

    settings = ToolSettings(sim_budget_factor=args.sim_budget_factor, obstacles=args.obstacles, confirm=args.confirm,
                            buffer=args.buffer, seed=args.random_seed, workers=args.workers, agent=args.agent,
                            px4_verdict=args.px4_verdict).check()
    check_writable(args.dir, "DIR")
    folder = write_tool(args.dir, settings)
    print(f"tool written to {folder}/: cli.py, testcase.py, Dockerfile, requirements.txt, README.md, {SETTINGS_FILE}, "
          f"case_studies/, the surrealist-gym source it installs")
    print(f"search: {settings.sim_budget_factor} x BUDGET simulator evaluations, {settings.obstacles} boxes, "
          f"{settings.confirm} re-runs per failure, buffer {settings.buffer:g} m, seed {settings.seed}, "
          f"{settings.workers} worker(s), agent {settings.agent}"
          + (", ranked by the model of PX4's verdict" if settings.px4_verdict else ""))
    print(f"run it on our simulator: surrealist compete {folder} mission2 10; in the competition: "
          f"python3 cli.py generate case_studies/mission2.yaml 100 (README.md)")
    return 0
