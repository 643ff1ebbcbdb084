"""Test-property mutators (paper section 3.1.2): parameterised operators on one obstacle of a test case.

``Mutator.apply(test, value)`` returns a new test case whose obstacle is changed by ``value`` relative to ``test``
(additive mutators; the default value 0 leaves the test unchanged). Moves are along the world axes (x north,
y east); resizes keep the footprint centre and the base; rotations are in degrees, positive from north toward east.
An invalid result (non-positive size, overlapping obstacles) raises :class:`InvalidTestCase`: never simulate it.
:class:`UavMutator` and :class:`WindMutator` change a UAV setting or the test's wind with the same interface,
:class:`PropertyMutator`, which the envs and agents rely on.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from enum import Enum
from typing import Protocol, Sequence, runtime_checkable

import numpy as np

from .errors import InvalidTestCase
from .testcase import MAX_WIND_SPEED_MS, TestCase, Wind


@runtime_checkable
class PropertyMutator(Protocol):
    """What the envs and the agents ask of a mutator of one test property (obstacle, UAV setting, wind).

    Attributes:
        default_step / min_step: the adaptive line search's first and smallest steps (units of the property).
        low, high: the range of the mutator value (an action's -1 and 1; agents that sample draw from it).
        default_value: the value that leaves the test unchanged (0: the mutators are additive).
    """

    __slots__ = ()  # plain attributes, so the frozen dataclasses that declare the protocol keep their fields
    default_step: float
    min_step: float
    low: float
    high: float
    default_value: float

    @property
    def name(self) -> str:
        """The mutator's name in results and options, e.g. ``obstacle0.x``, ``uav.takeoff_delay_s``."""

    def valid_range(self, test: TestCase) -> tuple[float, float]:
        """The part of ``[low, high]`` that gives a valid property on ``test``."""

    def apply(self, test: TestCase, value: float) -> TestCase:
        """A new test case with the property changed by ``value``; InvalidTestCase when the result is invalid."""


class MutatorKind(str, Enum):
    """What a mutator changes; the value is the name the authors' code uses (order y, x, r, sy, sx, sz)."""

    MOVE_X = "x"
    MOVE_Y = "y"
    ROTATE = "r"
    RESIZE_L = "sx"
    RESIZE_W = "sy"
    RESIZE_H = "sz"


_FIELD = {MutatorKind.MOVE_X: "x", MutatorKind.MOVE_Y: "y", MutatorKind.ROTATE: "r",
          MutatorKind.RESIZE_L: "l", MutatorKind.RESIZE_W: "w", MutatorKind.RESIZE_H: "h"}
MOVE_KINDS = (MutatorKind.MOVE_Y, MutatorKind.MOVE_X)
AUTHORS_ORDER = (MutatorKind.MOVE_Y, MutatorKind.MOVE_X, MutatorKind.ROTATE,
                 MutatorKind.RESIZE_W, MutatorKind.RESIZE_L, MutatorKind.RESIZE_H)


@dataclass(frozen=True, slots=True)
class Mutator(PropertyMutator):
    """An additive mutator of one obstacle property.

    Attributes:
        obstacle: index of the obstacle in ``TestCase.obstacles``.
        kind: the property changed.
        default_step: the first step of the adaptive line search (4 m, or 30 degrees for rotations).
        min_step: the smallest step worth trying (0.1 m / 0.5 degrees in the authors' run).
        low, high: the range of the mutator value (used by agents that sample it, e.g. random search).
        lowest, highest: bounds on the property's value itself (e.g. the competition's rules); a mutation beyond
            them is invalid, and ``valid_range`` leaves it out.
    """

    obstacle: int
    kind: MutatorKind
    default_step: float = 0.0
    min_step: float = 0.0
    low: float = -20.0
    high: float = 20.0
    default_value: float = 0.0
    lowest: float = -math.inf
    highest: float = math.inf

    def __post_init__(self):
        kind = MutatorKind(self.kind)
        object.__setattr__(self, "kind", kind)
        rotation = kind == MutatorKind.ROTATE
        if self.default_step == 0.0:
            object.__setattr__(self, "default_step", 30.0 if rotation else 4.0)
        if self.min_step == 0.0:
            object.__setattr__(self, "min_step", 0.5 if rotation else 0.1)
        if rotation and (self.low, self.high) == (-20.0, 20.0):
            object.__setattr__(self, "low", -180.0)
            object.__setattr__(self, "high", 180.0)

    @property
    def name(self) -> str:
        """The mutator's name: ``obstacle<index>.<kind>``."""
        return f"obstacle{self.obstacle}.{self.kind.value}"

    def valid_range(self, test: TestCase) -> tuple[float, float]:
        """The part of ``[low, high]`` that keeps the obstacle's size at least ``min_step`` on ``test``.

        Resizes by less than ``min_step - size`` are invalid whatever the other mutators do; agents that sample
        the range (random search, CMA-ES) draw from this part. Overlaps with other obstacles are still possible.
        """
        if not 0 <= self.obstacle < len(test.obstacles):
            return self.low, self.high
        now = getattr(test.obstacles[self.obstacle], _FIELD[self.kind])
        lowest = self.lowest
        if self.kind in (MutatorKind.RESIZE_L, MutatorKind.RESIZE_W, MutatorKind.RESIZE_H):
            lowest = max(lowest, self.min_step)
        low, high = max(self.low, lowest - now), min(self.high, self.highest - now)
        return (min(low, self.high), high) if low <= high else (self.low, self.high)

    def apply(self, test: TestCase, value: float) -> TestCase:
        """A new test case with this mutator applied by ``value``; raises InvalidTestCase if the result is invalid."""
        if not 0 <= self.obstacle < len(test.obstacles):
            raise InvalidTestCase(f"mutator {self.name}: the test has {len(test.obstacles)} obstacle(s)")
        if value == self.default_value:
            return test
        obstacles = list(test.obstacles)
        obstacles[self.obstacle] = self.mutate(obstacles[self.obstacle], value)
        try:
            return test.with_obstacles(obstacles)
        except InvalidTestCase as err:
            raise InvalidTestCase(f"mutator {self.name} by {value:+g}: {err}") from err

    def mutate(self, obstacle, value: float):
        """The obstacle changed by ``value`` (checked on its own; overlaps are the test's to check)."""
        attr = _FIELD[self.kind]
        new_value = getattr(obstacle, attr) + value
        if not self.lowest - 1e-9 <= new_value <= self.highest + 1e-9:
            raise InvalidTestCase(f"mutator {self.name} by {value:+g}: obstacles[{self.obstacle}].{attr} "
                                  f"{new_value:g} is outside [{self.lowest:g}, {self.highest:g}]")
        # within 1e-9 of a bound is on it: only the rounding of ``bound - now`` (an action of -1 or +1 over a range
        # of ``lowest - now`` to ``highest - now``) puts a value there, so those actions give the bounds exactly
        if abs(new_value - self.lowest) < 1e-9:
            new_value = self.lowest
        elif abs(new_value - self.highest) < 1e-9:
            new_value = self.highest
        try:
            return replace(obstacle, **{attr: new_value})
        except InvalidTestCase as err:
            raise InvalidTestCase(f"mutator {self.name} by {value:+g}: {err}") from err


@dataclass(frozen=True, slots=True)
class UavMutator(PropertyMutator):
    """An additive mutator of one UAV setting (paper section 3: the UAV's configuration is a test property too).

    It sets the test's param ``uav.<setting>`` (``takeoff_delay_s``, ``planner.<field>``;
    :data:`~surrealist_gym.sim.profiles.SETTINGS`) to its current value plus ``value``; the current value is the
    test's own, else ``base`` (the profile's). Same interface as :class:`Mutator`.
    """

    setting: str
    base: float
    default_step: float
    min_step: float
    low: float
    high: float
    lowest: float
    highest: float
    default_value: float = 0.0

    @property
    def name(self) -> str:
        """The mutator's name, also its key in the test's params: ``uav.<setting>``."""
        return "uav." + self.setting

    def current(self, test: TestCase) -> float:
        """The setting's value on ``test`` (its base value when the test does not set it)."""
        return float(test.params.get(self.name, self.base))

    def valid_range(self, test: TestCase) -> tuple[float, float]:
        """The part of ``[low, high]`` that keeps the setting within ``[lowest, highest]`` on ``test``."""
        now = self.current(test)
        low, high = max(self.low, self.lowest - now), min(self.high, self.highest - now)
        return (low, high) if low <= high else (self.low, self.high)

    def apply(self, test: TestCase, value: float) -> TestCase:
        """A new test case with the setting changed by ``value``; InvalidTestCase outside its range."""
        if value == self.default_value:
            return test
        new = round(self.current(test) + value, 9)
        if not self.lowest <= new <= self.highest:
            raise InvalidTestCase(f"mutator {self.name} by {value:+g}: {new:g} is outside "
                                  f"[{self.lowest:g}, {self.highest:g}]")
        return replace(test, params={**test.params, self.name: new})


def uav_mutators(profile, settings=None) -> tuple[UavMutator, ...]:
    """Mutators of the profile's UAV settings (all of its avoidance model's, or those named), each ranging over
    the setting's whole span."""
    from .sim.profiles import SETTINGS

    known = {s.name: s for s in SETTINGS[profile.avoidance_model]}
    names = list(known) if settings is None else list(settings)
    for name in names:
        if name not in known:
            raise InvalidTestCase(f"UAV setting {name!r}: not one of {sorted(known)} (avoidance model "
                                  f"{profile.avoidance_model.value})")
    out = []
    for name in names:
        s = known[name]
        span = s.high - s.low
        out.append(UavMutator(name, s.value(profile), s.step, s.min_step, -span, span, s.low, s.high))
    return tuple(out)


class WindKind(str, Enum):
    """What a wind mutator changes: the mean speed [m/s] or the horizontal direction [degrees]."""

    SPEED = "speed"
    DIRECTION = "direction"


@dataclass(frozen=True, slots=True)
class WindMutator(PropertyMutator):
    """An additive mutator of the test's wind (Aerialist's wind plugin fields, :class:`~surrealist_gym.testcase.Wind`).

    ``speed`` adds ``value`` [m/s] to ``velocity_mean`` and raises ``velocity_max`` to the new mean when a given
    maximum would fall below it; the mean must stay in ``[0, MAX_WIND_SPEED_MS]``. ``direction`` turns the
    horizontal part of ``direction`` by ``value`` [degrees], positive from north toward east, and keeps its vertical
    part. A test without wind starts from ``Wind()`` (calm, blowing toward north), so the two kinds commute. Same
    interface as :class:`Mutator`.

    Attributes:
        kind: what is changed (``"speed"`` or ``"direction"``).
        default_step / min_step: the line search's first and smallest steps (2 / 0.1 m/s, 30 / 0.5 degrees).
        low, high: the range of the mutator value (-10 to 10 m/s, -180 to 180 degrees by default).

    Example::

        speed, direction = wind_mutators()
        windy = direction.apply(speed.apply(test, 8.0), 90.0)  # 8 m/s toward east
    """

    kind: WindKind
    default_step: float = 0.0
    min_step: float = 0.0
    low: float = 0.0
    high: float = 0.0
    default_value: float = 0.0

    def __post_init__(self):
        kind = _wind_kind(self.kind)
        object.__setattr__(self, "kind", kind)
        speed = kind == WindKind.SPEED
        if self.default_step == 0.0:
            object.__setattr__(self, "default_step", 2.0 if speed else 30.0)
        if self.min_step == 0.0:
            object.__setattr__(self, "min_step", 0.1 if speed else 0.5)
        if (self.low, self.high) == (0.0, 0.0):
            object.__setattr__(self, "low", -10.0 if speed else -180.0)
            object.__setattr__(self, "high", 10.0 if speed else 180.0)
        if not (math.isfinite(self.low) and math.isfinite(self.high) and self.low < self.high):
            raise InvalidTestCase(f"mutator {self.name}: expected a range low < high, got [{self.low:g}, "
                                  f"{self.high:g}]")

    @property
    def name(self) -> str:
        """The mutator's name: ``wind.<kind>``."""
        return "wind." + self.kind.value

    def valid_range(self, test: TestCase) -> tuple[float, float]:
        """The part of ``[low, high]`` that keeps the mean speed within ``[0, MAX_WIND_SPEED_MS]`` on ``test``."""
        if self.kind != WindKind.SPEED:
            return self.low, self.high
        now = (test.wind or Wind()).velocity_mean
        low, high = max(self.low, 0.0 - now), min(self.high, MAX_WIND_SPEED_MS - now)
        return (low, high) if low <= high else (self.low, self.high)

    def apply(self, test: TestCase, value: float) -> TestCase:
        """A new test case with the wind changed by ``value``; InvalidTestCase outside the physical range."""
        if value == self.default_value:
            return test
        wind = test.wind or Wind()
        try:
            if self.kind == WindKind.SPEED:
                mean = round(wind.velocity_mean + value, 9)
                if not 0 <= mean <= MAX_WIND_SPEED_MS:
                    raise InvalidTestCase(f"mean speed {mean:g} m/s is outside [0, {MAX_WIND_SPEED_MS:g}]")
                vmax = wind.velocity_max if wind.velocity_max == 0 else max(wind.velocity_max, mean)
                wind = replace(wind, velocity_mean=mean, velocity_max=vmax)
            else:
                north, east, down = wind.direction
                c, s = math.cos(math.radians(value)), math.sin(math.radians(value))
                # + 0.0: -0.0 and 0.0 are one direction, so one key
                wind = replace(wind, direction=(round(c * north - s * east, 12) + 0.0,
                                                round(s * north + c * east, 12) + 0.0, down))
        except InvalidTestCase as err:
            raise InvalidTestCase(f"mutator {self.name} by {value:+g}: {err}") from err
        return replace(test, wind=wind)


def _wind_kind(value) -> WindKind:
    try:
        return WindKind(value)
    except ValueError:
        raise InvalidTestCase(f"wind mutator kind {value!r}: expected one of "
                              f"{[k.value for k in WindKind]}") from None


def wind_mutators(speed_range: tuple[float, float] = (-10.0, 10.0),
                  kinds=(WindKind.SPEED, WindKind.DIRECTION)) -> tuple[WindMutator, ...]:
    """Mutators of the test's wind: mean speed [m/s] over ``speed_range`` and direction [degrees] over a full turn,
    in the order of ``kinds`` (``"speed"``, ``"direction"``)."""
    out = []
    for kind in map(_wind_kind, kinds):
        out.append(WindMutator(kind, low=speed_range[0], high=speed_range[1]) if kind == WindKind.SPEED
                   else WindMutator(kind))
    return tuple(out)


def default_mutators(test: TestCase, kinds=AUTHORS_ORDER, obstacles=None) -> tuple[Mutator, ...]:
    """Mutators of the given kinds for each obstacle (all by default), obstacle by obstacle, kinds in order."""
    indices = range(len(test.obstacles)) if obstacles is None else obstacles
    return tuple(Mutator(i, k) for i in indices for k in kinds)


def action_values(mutators: Sequence[PropertyMutator], action) -> list[float]:
    """The mutator values an action stands for: one value in [-1, 1] per mutator (clipped), scaled to the mutator's
    range (centre + value x half range), rounded to 1e-9 so that equal actions give equal keys."""
    values = []
    for mutator, a in zip(mutators, np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)):
        centre, half_range = (mutator.high + mutator.low) / 2, (mutator.high - mutator.low) / 2
        values.append(float(np.round(centre + a * half_range, 9)))
    return values


def mutated_obstacles(test: TestCase, mutators: Sequence[PropertyMutator], action) -> tuple:
    """The obstacles of ``test`` changed by the obstacle mutators of an action (:func:`action_values`), each checked
    on its own but not against the others (they may overlap); the other mutators are left out."""
    return _mutated_obstacles(test, zip(mutators, action_values(mutators, action)))


def _mutated_obstacles(test: TestCase, pairs) -> tuple:
    obstacles = list(test.obstacles)
    for mutator, value in pairs:
        if not isinstance(mutator, Mutator):
            continue
        if not 0 <= mutator.obstacle < len(obstacles):
            raise InvalidTestCase(f"mutator {mutator.name}: the test has {len(obstacles)} obstacle(s)")
        if value != mutator.default_value:
            obstacles[mutator.obstacle] = mutator.mutate(obstacles[mutator.obstacle], value)
    return tuple(obstacles)


def apply_action(test: TestCase, mutators: Sequence[PropertyMutator], action) -> TestCase:
    """The test that an action stands for (:func:`action_values`). The obstacle mutators change their obstacles
    first and the layout is checked once, as a whole (a box may pass through another on the way:
    :func:`mutated_obstacles`); then the others (UAV settings, wind) apply in order. Raises InvalidTestCase for an
    invalid result."""
    pairs = list(zip(mutators, action_values(mutators, action)))
    obstacles = _mutated_obstacles(test, pairs)
    if obstacles != tuple(test.obstacles):
        test = test.with_obstacles(obstacles)
    for mutator, value in pairs:
        if not isinstance(mutator, Mutator):
            test = mutator.apply(test, value)
    return test
