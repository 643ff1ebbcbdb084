"""The ICST 2027 UAV perception testing track's registered scenario space: its limits and the names of its rules.

Every figure here is the track's, from ``starter_kit/validate.py`` of the track's kit
(``../shared/third_party/uav-testing-track-2027``, the only gate a submission passes) and ``starter_kit/preflight.py``,
as ``../shared/TRACK2027.md`` sections 2-4 state them. :mod:`.rules` checks a scenario against them,
:mod:`.measures` measures it with them, and :class:`InvalidScenario` names the :class:`Rule` a scenario breaks.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from enum import Enum

from ..errors import InvalidTestCase


@dataclass(frozen=True, slots=True)
class Interval:
    """A closed interval ``[low, high]`` of a scenario's number, with its unit for messages."""

    low: float
    high: float
    unit: str = ""

    def holds(self, value: float) -> bool:
        """Whether ``low <= value <= high`` (both ends admitted, as validate.py compares)."""
        return self.low <= value <= self.high

    def __str__(self) -> str:
        return f"[{self.low:g}, {self.high:g}]" + (f" {self.unit}" if self.unit else "")


#: The ranges of a scenario's numbers, in the order validate.py checks them (its ``BOUNDS``; TRACK2027.md section 3;
#: the seed's range is validate.py's alone).
SCENARIO_RANGES = {
    "seed": Interval(1, 100000),
    "density": Interval(0.012, 0.120, "trees/m^2"),
    "area": Interval(10.0, 40.0, "m"),
    "corridor": Interval(2.0, 12.0, "m"),
    "ego_max_vel": Interval(1.2, 3.5, "m/s"),
    "wind": Interval(0.0, 8.0, "m/s"),
    "alt": Interval(0.5, 4.0, "m"),
    "voxel": Interval(0.05, 0.20, "m"),
}
#: The ranges of the poles' size (validate.py's ``pole_radius`` and ``pole_height``; TRACK2027.md section 3).
POLE_RANGES = {"radius": Interval(0.02, 0.10, "m"), "height": Interval(1.0, 5.0, "m")}

SCENARIOS_PER_SUBMISSION = 20  # exactly this many (validate.py CAP)
MIN_RECIPES = 5  # distinct scenarios once the forest seed is ignored (validate.py MIN_DISTINCT_RECIPES)
WAYPOINT_COUNT = Interval(2, 6)  # waypoints of a patrol (validate.py MIN_WP, MAX_WP)
LEG_M = Interval(8.0, 34.0, "m")  # [m] length of each leg (validate.py MIN_LEG, MAX_LEG)
TURN_DEG = Interval(25.0, 160.0, "deg")  # [deg] turn at each interior waypoint (validate.py MIN/MAX_TURN_DEG)
EDGE_MARGIN_M = 3.0  # [m] waypoints stay this far inside the field's half-width ``area`` (validate.py MARGIN)
MAX_POLES = 10  # poles per scenario (validate.py MAX_POLES)
POLE_WAYPOINT_CLEARANCE_M = 3.0  # [m] least distance of a pole from any waypoint (validate.py POLE_WP_EXCL)
POLE_SEPARATION_M = 1.5  # [m] least distance between two poles (validate.py POLE_MIN_SEP)

SWEPT_RADIUS_M = 0.444  # [m] the Holybro X500's swept radius (validate.py SWEPT, preflight.py VEHICLE_R)
TIGHT_WIDTH_M = 0.40  # [m] a lane with less free lateral width is reported as tight (validate.py TIGHT_GAP)
BLOCKED_WIDTH_M = 0.05  # [m] ... and with less than this as blocked; both admissible (validate.py GAP_EPS)
STATION_STEP_M = 0.10  # [m] the free lateral width is measured at stations this far apart (check_navigable)
TIGHT_BAND_CORRIDOR_M = 4.5  # [m] a corridor at most this wide is in the tight band (preflight.py BAND_CUT)

#: The fields that change a flight (validate.py FLIGHT_KEYS), in the order the track's README writes them.
FLIGHT_FIELDS = ("id", "seed", "area", "voxel", "corridor", "density", "wind", "ego_max_vel", "alt", "patrol",
                 "obstacle")
#: Provenance a scenario may carry; never read by the flight, never part of its fingerprint (validate.py).
METADATA_FIELDS = ("stratum", "turn_total_deg", "note", "generator")
OBSTACLE_FIELDS = ("type", "xy", "radius", "height")  # an obstacle's only fields; its type is "poles"
#: The factors whose spread is ``input_div``, each normalised by half its range (preflight.py FACTORS).
INPUT_DIV_FACTORS = ("density", "ego_max_vel", "alt", "wind", "corridor")

SAFE_TOKEN = re.compile(r"[A-Za-z0-9_-]{1,64}\Z")  # a submission's name and a scenario's id (validate.py SAFE)


class Rule(str, Enum):
    """The rule a submission or scenario breaks, one per check of validate.py (in the order it checks them)."""

    JSON = "the file is a JSON document"
    SUBMISSION_SHAPE = "a submission is an object with a 'scenarios' list"
    SUBMISSION_NAME = "the submission's name is a token [A-Za-z0-9_-]{1,64}"
    COUNT = f"exactly {SCENARIOS_PER_SUBMISSION} scenarios"
    SCENARIO_OBJECT = "a scenario is an object"
    SCENARIO_ID = "a scenario's id is a token [A-Za-z0-9_-]{1,64}"
    DUPLICATE_ID = "scenario ids are unique"
    SEED_INTEGER = "the seed is an integer"
    NUMBER = "each number is present and finite"
    RANGE = "each number within its range"
    WAYPOINTS = f"a patrol is a list of {WAYPOINT_COUNT.low}-{WAYPOINT_COUNT.high} waypoints"
    WAYPOINT_FORM = "a waypoint is [x, y] with finite numbers"
    EDGE_MARGIN = f"waypoints {EDGE_MARGIN_M:g} m inside the field's edge"
    LEG = f"legs {LEG_M}"
    TURN = f"interior turns {TURN_DEG}"
    OBSTACLE_TYPE = "the obstacle is {type: poles, ...}"
    OBSTACLE_NUMBER = "the poles' radius and height are present and finite"
    POLE_COUNT = f"the poles are a list of at most {MAX_POLES}"
    POLE_FORM = "a pole is [x, y] with finite numbers"
    POLE_EXTENT = "poles stand inside the field"
    POLE_LANE = "poles stand inside the lane"
    POLE_WAYPOINT = f"poles at least {POLE_WAYPOINT_CLEARANCE_M:g} m from every waypoint"
    POLE_SEPARATION = f"poles at least {POLE_SEPARATION_M:g} m apart"
    UNKNOWN_FIELD = "no field beyond the flight's and the provenance ones"
    UNKNOWN_OBSTACLE_FIELD = "no obstacle field beyond type, xy, radius and height"
    DUPLICATE_SCENARIO = "no two scenarios identical apart from their id"
    RECIPES = f"at least {MIN_RECIPES} distinct recipes once the seed is ignored"


class InvalidScenario(InvalidTestCase):
    """A submission or scenario breaks one of the track's rules: one line naming the file, the scenario and the field,
    and the :class:`Rule` broken (``rule``)."""

    def __init__(self, message: str, rule: Rule = Rule.JSON):
        super().__init__(message)
        self.rule = rule

    def within(self, where: str) -> InvalidScenario:
        """The same error with ``where`` (a file, a scenario) put before its message."""
        return InvalidScenario(f"{where}: {self}" if where else str(self), self.rule)

    def __reduce__(self):
        return (type(self), (str(self), self.rule))
