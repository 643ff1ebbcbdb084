"""What the run loop asks of an obstacle-avoidance planner, whichever model flies.

:class:`Planner` is one vehicle's planner: :meth:`Planner.step` once per planner cycle (``SimConfig.planner_hz``),
:meth:`Planner.reset` at the start of a flight. A step returns a :class:`PlannerCommand`, which the navigator reads:
a position setpoint (PX4-Avoidance's trajectory waypoint, flown through PX4's flight task) or, when ``position`` is
None, a velocity setpoint (its ``velocity``), and a yaw setpoint. The two planners declare both:
:class:`~surrealist_gym.sim.avoidance.px4.local_planner.Px4LocalPlanner` (PX4-Avoidance as in Aerialist's SITL) and
:class:`~surrealist_gym.sim.avoidance.reactive.LocalPlanner` (the reactive planner tuned to the real PX4 Vision), with
their outputs :class:`~surrealist_gym.sim.avoidance.px4.local_planner.Px4PlannerOutput` and
:class:`~surrealist_gym.sim.avoidance.reactive.PlannerOutput`. World frame: x north, y east, z up [m]; yaw [rad] from
north toward east.
"""
from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["Planner", "PlannerCommand"]

Vector = tuple[float, float, float]


@runtime_checkable
class PlannerCommand(Protocol):
    """One planner cycle's setpoints for the navigator (plain attributes, so the frozen dataclasses that declare the
    protocol keep their fields).

    Attributes:
        position: Position setpoint (x, y, z up) [m], or None for a planner that commands its ``velocity`` [m/s].
        yaw: Yaw setpoint [rad].
    """

    __slots__ = ()
    position: Vector | None
    yaw: float


@runtime_checkable
class Planner(Protocol):
    """One vehicle's avoidance planner, as the run loop drives it."""

    __slots__ = ()

    def reset(self) -> None:
        """Forget the obstacle memory and the filters (a new flight)."""

    def step(self, t: float, position: Vector, velocity: Vector, yaw: float, goal: Vector, prev_goal: Vector,
             hits: np.ndarray, cruise: float) -> PlannerCommand:
        """One planner cycle.

        Args:
            t: Time [s], monotonic within a flight.
            position, velocity: the vehicle's estimate (x, y, z up) [m], [m/s]. yaw: its heading [rad].
            goal: the current mission target [m]; prev_goal: the previous one (the mission line runs between them).
            hits: (K, 3) world points of the depth camera's latest scan [m] (may be empty).
            cruise: the mission's current speed [m/s] (MPC_XY_CRUISE or the last DO_CHANGE_SPEED).
        """
