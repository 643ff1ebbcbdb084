"""How a run's end is worded (``RunResult.message``): one sentence per way a run ends, the same in every loop."""
from __future__ import annotations


def finished(landed: bool, t: float) -> str:
    """The mission completed: landed and disarmed, or its last item reached in the air."""
    return ("landed and disarmed" if landed else "mission finished in the air") + f" at t={t:.2f} s"


def collided(obstacle: int, t: float) -> str:
    """The vehicle touched obstacle number ``obstacle``."""
    return f"collision with obstacle {obstacle} at t={t:.2f} s"


def timed_out(limit: float, phase: str) -> str:
    """The time limit ended the run in navigator phase ``phase``."""
    return f"timeout after {limit:g} s in phase {phase}"


def stuck(distance: float, window: float, phase: str, t: float) -> str:
    """No progress of ``distance`` toward the goal in ``window`` seconds."""
    return f"stuck: no progress of {distance:g} m toward the goal in {window:g} s (phase {phase}, t={t:.2f} s)"


def invalid(t: float) -> str:
    """The vehicle flipped or its state stopped being finite."""
    return f"vehicle flipped or state invalid at t={t:.2f} s"
