"""Wrappers that change what a Surrealist env charges or reports, and the layer agents bind to.

A :class:`SurrealistWrapper` is a Gymnasium wrapper that forwards the env's search API (the list below) to the env
it wraps, so an agent given a wrapped env searches through the outermost one (:func:`search_layer`): it sees that
layer's budget and steps. Gymnasium's own wrappers (``gym.make``'s checkers) are passed through.
"""
from __future__ import annotations

import gymnasium as gym

FORWARDED_PROPERTIES = ("mutators", "seed_test", "seed_action", "budget", "budget_left", "evaluations", "simulations",
                        "evaluator", "seed_evaluation", "best")
FORWARDED_METHODS = ("values_for", "action_for", "action_bounds", "test_for", "evaluated")


class SurrealistWrapper(gym.Wrapper):
    """Base of the wrappers of a Surrealist env; subclasses override what they change (e.g. ``budget_left``)."""

    @property
    def inner(self):
        """The Surrealist layer this one wraps."""
        return search_layer(self.env)


def _forward_property(name: str):
    return property(lambda self: getattr(self.inner, name), doc=f"The wrapped env's ``{name}``.")


def _forward_method(name: str):
    def method(self, *args, **kwargs):
        return getattr(self.inner, name)(*args, **kwargs)
    method.__name__, method.__doc__ = name, f"The wrapped env's ``{name}``."
    return method


for _name in FORWARDED_PROPERTIES:
    setattr(SurrealistWrapper, _name, _forward_property(_name))
for _name in FORWARDED_METHODS:
    setattr(SurrealistWrapper, _name, _forward_method(_name))


def search_layer(env):
    """The outermost layer of ``env`` that speaks the search API: a :class:`SurrealistWrapper`, else the env itself
    (under Gymnasium's wrappers)."""
    while isinstance(env, gym.Wrapper) and not isinstance(env, SurrealistWrapper):
        env = env.env
    return env


__all__ = ["SurrealistWrapper", "search_layer"]
