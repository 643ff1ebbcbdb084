"""Gymnasium environments (registered by ``import surrealist_gym``)."""
from .base import EnvSetup, SurrealistEnv

__all__ = ["EnvSetup", "SurrealistEnv"]
