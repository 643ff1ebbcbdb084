"""Gymnasium environments (registered by ``import surrealist_gym``)."""
from .base import SurrealistEnv

__all__ = ["SurrealistEnv"]
