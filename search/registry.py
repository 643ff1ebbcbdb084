"""Agents by name: ``make_agent("cmaes", seed=0)``, as the command line and ``compare`` spell them.

Names:
    ``greedy`` (the adaptive greedy with the authors' preset), ``greedy-paper`` (paper Table 1), ``random``,
    ``cmaes``, ``suite`` (suites of distinct failures), ``ppo:POLICY.zip`` / ``sac:POLICY.zip`` (a policy
    trained by ``surrealist train``, deterministic first), ``ppo-sample:POLICY.zip`` / ``sac-sample:POLICY.zip``
    (every action sampled from the policy), any name added with :func:`register_agent`, and ``module:Class`` or
    ``path/to/file.py:Class`` for an Agent subclass of your own (built as ``Class(seed=seed, **options)``).

Example:
    >>> make_agent("random", seed=0).name
    'random'
    >>> make_agent("grredy")
    Traceback (most recent call last):
    ...
    surrealist_gym.errors.UnknownAgent: unknown agent 'grredy'; did you mean 'greedy'? (known: ...)
"""
from __future__ import annotations

import difflib
import importlib
import importlib.util
from pathlib import Path
from typing import Callable

from surrealist_gym.errors import UnknownAgent

from .base import Agent

POLICY_PREFIXES = ("ppo", "sac", "ppo-sample", "sac-sample")


def _greedy(preset: str) -> Callable[..., Agent]:
    def factory(seed=None, **options):
        from .greedy import AdaptiveGreedy
        return AdaptiveGreedy(options.pop("config", preset), seed=seed, **options)
    return factory


def _random(seed=None, **options):
    from .random import RandomSearch
    return RandomSearch(seed=seed, **options)


def _cmaes(seed=None, **options):
    from .cmaes import CMAES
    return CMAES(seed=seed, **options)


def _suite(seed=None, **options):
    from .novelty import SuiteSearch
    return SuiteSearch(seed=seed, **options)


_REGISTRY: dict[str, Callable[..., Agent]] = {
    "greedy": _greedy("authors"),
    "greedy-paper": _greedy("paper"),
    "random": _random,
    "cmaes": _cmaes,
    "suite": _suite,
}


def register_agent(name: str, factory: Callable[..., Agent]) -> None:
    """Make ``make_agent(name, seed=..., **options)`` call ``factory(seed=..., **options)`` (an Agent class works)."""
    if not name or ":" in name or "," in name:
        raise ValueError(f"agent name: expected a non-empty name without ':' or ',', got {name!r}")
    _REGISTRY[name] = factory


def agent_names() -> list[str]:
    """The registered names (policies are spelled ``ppo:PATH``, ``sac:PATH``, ``ppo-sample:PATH``, ...)."""
    return sorted(_REGISTRY) + [f"{p}:POLICY.zip" for p in POLICY_PREFIXES]


def agent_label(name: str) -> str:
    """A short label for tables: ``ppo:runs/p.zip`` -> ``ppo``, ``pkg.mod:MyAgent`` -> ``MyAgent``."""
    prefix, sep, rest = name.partition(":")
    if not sep:
        return name
    return prefix if prefix in POLICY_PREFIXES else rest


def make_agent(name: str, seed: int | None = None, **options) -> Agent:
    """A new agent from its name (see the module docstring); unknown names raise UnknownAgent with a hint."""
    prefix, sep, rest = name.partition(":")
    if sep and prefix in POLICY_PREFIXES:
        from .policy import PPOAgent
        algorithm, _, sample = prefix.partition("-")
        return PPOAgent(rest, seed=seed, algorithm=algorithm, sample=bool(sample), **options)
    if sep:
        return _import_agent(prefix, rest)(seed=seed, **options)
    if name in _REGISTRY:
        return _REGISTRY[name](seed=seed, **options)
    if name in POLICY_PREFIXES:
        raise UnknownAgent(f"agent {name!r} needs a trained policy: {name}:POLICY.zip "
                           f"(train one with `surrealist train`)")
    close = difflib.get_close_matches(name, list(_REGISTRY) + list(POLICY_PREFIXES), n=1)
    hint = f"; did you mean {close[0]!r}?" if close else ""
    raise UnknownAgent(f"unknown agent {name!r}{hint} (known: {', '.join(agent_names())}, or module:Class)")


def _import_agent(module: str, attr: str):
    """``module:Class`` or ``file.py:Class`` -> the class."""
    try:
        if module.endswith(".py"):
            path = Path(module)
            spec = importlib.util.spec_from_file_location(path.stem, path)
            if spec is None or not path.is_file():
                raise FileNotFoundError(module)
            mod = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(mod)
        else:
            mod = importlib.import_module(module)
        factory = getattr(mod, attr)
    except (ImportError, FileNotFoundError, AttributeError) as err:
        close = difflib.get_close_matches(module, POLICY_PREFIXES, n=1)
        hint = f"; did you mean {close[0]}:{attr}?" if close else ""
        raise UnknownAgent(f"agent '{module}:{attr}': cannot import it ({type(err).__name__}: {err}){hint}") from err
    if not callable(factory):
        raise UnknownAgent(f"agent '{module}:{attr}': not a class or factory")
    return factory
