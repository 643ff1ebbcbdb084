"""Search agents: the paper's adaptive greedy (reference), and agents that plug into the same interface.

``make_agent("random")`` builds any of them by name; ``compare(...)`` runs several on the same problems.
"""
from .base import Agent, SearchResult
from .cmaes import CMAES, CMAESConfig
from .compare import CompareResult, compare
from .greedy import AdaptiveGreedy, GreedyConfig
from .metrics import SearchMetrics, search_metrics
from .novelty import SuiteSearch, SuiteSearchConfig
from .policy import PPOAgent
from .random import RandomConfig, RandomSearch
from .registry import agent_names, make_agent, register_agent
from .repetitions import Repetition, run_repetition
from .rl import ProceduralEnv, train_policy

__all__ = ["Agent", "AdaptiveGreedy", "CMAES", "CMAESConfig", "CompareResult", "GreedyConfig", "PPOAgent",
           "ProceduralEnv", "RandomConfig", "RandomSearch", "Repetition", "SearchMetrics", "SearchResult",
           "SuiteSearch", "SuiteSearchConfig",
           "agent_names", "compare", "make_agent", "register_agent", "run_repetition", "search_metrics",
           "train_policy"]
