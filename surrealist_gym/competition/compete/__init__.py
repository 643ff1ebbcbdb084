"""``surrealist compete``: the UAV Testing Competition's tools run unchanged on surrealist-gym's simulator.

A competition tool is a folder whose ``cli.py generate CASE_STUDY BUDGET`` builds tests through Aerialist and runs
them with Aerialist's ``LocalAgent``, ``DockerAgent`` or ``K8sAgent`` (PX4 SITL). :func:`prepare` checks the inputs,
:func:`run` runs the tool's own cli.py in a copy of its folder with a shim first on its ``PYTHONPATH`` that makes
those agents ask a :class:`SimulationServer` in this process to fly each test (budget counted there) and return
Aerialist's own results built from the ULogs. See docs/compete.md.

Example::

    >>> from surrealist_gym.competition.compete import prepare, run                                     # doctest: +SKIP
    >>> result = run(prepare("../shared/third_party/peers/ambiegen/snippets", "mission2", 10))  # doctest: +SKIP
    >>> result.output_folder, [t.points for t in result.tests]                                # doctest: +SKIP
"""
from .locate import AERIALIST_ENV, AerialistSource, find_aerialist, tool_apis
from .process import ToolLimits
from .server import Flight, SimulationServer
from .tool import CompetePlan, CompeteResult, WrittenTest, claim, prepare, run, tool_environment, ulog_distance
from .toolenv import EnvChoice, ToolEnv, choose_env, own_env

__all__ = ["AERIALIST_ENV", "AerialistSource", "CompetePlan", "CompeteResult", "EnvChoice", "Flight",
           "SimulationServer", "ToolEnv", "ToolLimits", "WrittenTest", "choose_env", "claim", "find_aerialist",
           "own_env", "prepare", "run", "tool_apis", "tool_environment", "ulog_distance"]
