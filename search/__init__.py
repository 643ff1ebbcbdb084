"""Search agents: the paper's adaptive greedy (reference), and agents that plug into the same interface."""
from .base import Agent, SearchResult
from .greedy import AdaptiveGreedy, GreedyConfig

__all__ = ["Agent", "AdaptiveGreedy", "GreedyConfig", "SearchResult"]
