"""The arrays the navigator and flight-task kernels share (docs/compiled-loop.md): codes, the columns of the
mission array, the parameter and state vectors, their Python builders, the accessors that read the Navigator's
properties from a state, and the arithmetic both kernels need bit for bit with CPython.

Arrays, built once per run or per test:

- **state** (:func:`initial_state`): one float64 vector of :data:`N_STATE` values per vehicle, named by the ``S_*``
  offsets: the phase (its position in :class:`~surrealist_gym.sim.navigation.navigator.Phase`, :data:`PHASES`), the item
  index, the cruise speed, the current target (x, y, z and, during the RTL climb, the return position), the
  previous setpoint, the timers, the slewed velocity command, the yaw setpoint, the carrot, and the flight task's
  trajectory (position, velocity, acceleration, speed lock). The class's ``None`` values (yaw setpoint before the
  first update, landed-since, carrot) are NaN; its booleans are 0.0 / 1.0.
- **mission** (:func:`mission_array`): one row per item, columns ``M_*`` (MAV_CMD code, x, y, z, acceptance
  radius, hold time, speed); rows after the last item have the command :data:`NO_ITEM`, so missions of several
  lengths share one padded array.
- **params** (:func:`param_vector`): the PX4 parameters the navigator and the task read, at ``P_<NAME>`` offsets,
  plus the run's mission start and take-off hold.

Bit equality with CPython needs :mod:`~surrealist_gym.sim.compiled.cpython_math`'s ``py_hypot`` and ``py_remainder``,
and :func:`py_square` (CPython's ``x ** 2`` is libm's ``pow``, which rounds ~0.08 % of squares differently from
``x * x``; LLVM rewrites ``pow(x, 2.0)`` with a constant exponent to ``x * x``, so the exponent is read from the
params vector at run time).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...mission import Command, Mission
from .navigator import Phase

__all__ = ["PHASES", "N_STATE", "N_PARAMS", "PARAM_NAMES", "PLAN_NONE", "PLAN_VELOCITY", "PLAN_POSITION",
           "initial_state", "mission_array", "param_vector", "plan_inputs", "phase_of", "nav_reset", "nav_target",
           "nav_goal", "nav_prev", "nav_cruise", "nav_index", "nav_phase", "nav_armed", "nav_on_ground_phase",
           "nav_uses_planner", "nav_mission_complete", "py_square", "line_projection"]

NAN = math.nan


# --- phase and command codes --------------------------------------------------------------------------------------
PHASES = tuple(Phase)  #: a phase's code is its position here (the enum's order)
PH_IDLE = PHASES.index(Phase.IDLE)
PH_TAKEOFF = PHASES.index(Phase.TAKEOFF)
PH_CRUISE = PHASES.index(Phase.CRUISE)
PH_CLIMB = PHASES.index(Phase.CLIMB)
PH_DESCEND = PHASES.index(Phase.DESCEND)
PH_HOLD = PHASES.index(Phase.HOLD)
PH_LANDED = PHASES.index(Phase.LANDED)
PH_DONE = PHASES.index(Phase.DONE)

CMD_WAYPOINT = int(Command.WAYPOINT)
CMD_RETURN_TO_LAUNCH = int(Command.RETURN_TO_LAUNCH)
CMD_LAND = int(Command.LAND)
CMD_TAKEOFF = int(Command.TAKEOFF)
CMD_CHANGE_SPEED = int(Command.CHANGE_SPEED)
NO_ITEM = 0  #: the command of a padding row after the mission's last item

PLAN_NONE, PLAN_VELOCITY, PLAN_POSITION = 0, 1, 2  #: what the planner's 3-vector is (no planner output: none)

# --- mission array columns ----------------------------------------------------------------------------------------
M_COMMAND, M_X, M_Y, M_Z, M_ACCEPTANCE_RADIUS, M_HOLD_S, M_SPEED = range(7)
N_MISSION_FIELDS = 7

# --- parameter vector -------------------------------------------------------------------------------------------
PARAM_NAMES = ("MPC_XY_CRUISE", "MPC_TKO_RAMP_T", "MPC_TKO_SPEED", "MPC_Z_VEL_MAX_UP", "MPC_Z_VEL_MAX_DN", "MPC_Z_P",
               "MPC_LAND_ALT1", "MPC_LAND_ALT2", "MPC_LAND_SPEED", "MPC_XY_P", "MPC_ACC_HOR", "MPC_ACC_UP_MAX",
               "MPC_ACC_DOWN_MAX", "MPC_JERK_AUTO", "MPC_XY_ERR_MAX", "MPC_YAW_MODE", "MPC_YAWRAUTO_MAX",
               "NAV_ACC_RAD", "NAV_MC_ALT_RAD", "MIS_TAKEOFF_ALT", "RTL_RETURN_ALT", "LNDMC_Z_VEL_MAX",
               "LNDMC_XY_VEL_MAX", "LNDMC_TRIG_TIME", "COM_DISARM_LAND")  #: PX4 parameters at their positions
P_MPC_XY_CRUISE = PARAM_NAMES.index("MPC_XY_CRUISE")
P_MPC_TKO_RAMP_T = PARAM_NAMES.index("MPC_TKO_RAMP_T")
P_MPC_TKO_SPEED = PARAM_NAMES.index("MPC_TKO_SPEED")
P_MPC_Z_VEL_MAX_UP = PARAM_NAMES.index("MPC_Z_VEL_MAX_UP")
P_MPC_Z_VEL_MAX_DN = PARAM_NAMES.index("MPC_Z_VEL_MAX_DN")
P_MPC_Z_P = PARAM_NAMES.index("MPC_Z_P")
P_MPC_LAND_ALT1 = PARAM_NAMES.index("MPC_LAND_ALT1")
P_MPC_LAND_ALT2 = PARAM_NAMES.index("MPC_LAND_ALT2")
P_MPC_LAND_SPEED = PARAM_NAMES.index("MPC_LAND_SPEED")
P_MPC_XY_P = PARAM_NAMES.index("MPC_XY_P")
P_MPC_ACC_HOR = PARAM_NAMES.index("MPC_ACC_HOR")
P_MPC_ACC_UP_MAX = PARAM_NAMES.index("MPC_ACC_UP_MAX")
P_MPC_ACC_DOWN_MAX = PARAM_NAMES.index("MPC_ACC_DOWN_MAX")
P_MPC_JERK_AUTO = PARAM_NAMES.index("MPC_JERK_AUTO")
P_MPC_XY_ERR_MAX = PARAM_NAMES.index("MPC_XY_ERR_MAX")
P_MPC_YAW_MODE = PARAM_NAMES.index("MPC_YAW_MODE")
P_MPC_YAWRAUTO_MAX = PARAM_NAMES.index("MPC_YAWRAUTO_MAX")
P_NAV_ACC_RAD = PARAM_NAMES.index("NAV_ACC_RAD")
P_NAV_MC_ALT_RAD = PARAM_NAMES.index("NAV_MC_ALT_RAD")
P_MIS_TAKEOFF_ALT = PARAM_NAMES.index("MIS_TAKEOFF_ALT")
P_RTL_RETURN_ALT = PARAM_NAMES.index("RTL_RETURN_ALT")
P_LNDMC_Z_VEL_MAX = PARAM_NAMES.index("LNDMC_Z_VEL_MAX")
P_LNDMC_XY_VEL_MAX = PARAM_NAMES.index("LNDMC_XY_VEL_MAX")
P_LNDMC_TRIG_TIME = PARAM_NAMES.index("LNDMC_TRIG_TIME")
P_COM_DISARM_LAND = PARAM_NAMES.index("COM_DISARM_LAND")
_N_PX4 = len(PARAM_NAMES)
P_YAW_RATE_RAD = _N_PX4          # math.radians(MPC_YAWRAUTO_MAX), as Navigator._yaw_step computes it
P_START_TIME = _N_PX4 + 1        # mission start after arming [s] (Navigator.start_time)
P_TAKEOFF_HOLD_S = _N_PX4 + 2    # time at the take-off altitude before the next item [s]
P_SQUARE_EXPONENT = _N_PX4 + 3   # 2.0, read at run time: see py_square
N_PARAMS = _N_PX4 + 4

# --- state vector ------------------------------------------------------------------------------------------------
S_PHASE = 0             # phase code (PHASES)
S_INDEX = 1             # current mission item, -1 before the first
S_CRUISE = 2            # horizontal cruise speed (MPC_XY_CRUISE or the last CHANGE_SPEED) [m/s]
S_TARGET = 3            # 5 values: target x, y, z; the RTL return x, y while climbing (0 otherwise)
S_PREV = 8              # 3 values: the previous setpoint (the mission line starts there)
S_HOLD_UNTIL = 11       # end of the hold [s]
S_PHASE_T0 = 12         # start of the phase [s]
S_V_CMD = 13            # 3 values: the slewed velocity command (x, y, z up) [m/s]
S_YAW_SP = 16           # yaw setpoint [rad]; NaN before the first update
S_LANDED_SINCE = 17     # land detector: since when the landed conditions hold [s]; NaN when they do not
S_LANDED_AT = 18        # time of landing [s]
S_THEN_LAND = 19        # 1: descend after reaching the target (LAND, RTL)
S_FINISHED_IN_AIR = 20  # 1: the mission ended without landing
S_T = 21                # time of the last update [s]
S_CARROT = 22           # 3 values: the position setpoint moving with the velocity setpoint; NaN when unset
S_TASK_ACTIVE = 25      # 1 while the flight task exists (PX4-Avoidance's position setpoints in CRUISE)
S_TASK_POS = 26         # 3 values: the task's trajectory position
S_TASK_VEL = 29         # 3 values: its velocity
S_TASK_ACC = 32         # 3 values: its acceleration
S_TASK_MAX_SPEED_PREV = 35  # the horizontal speed when last not turning
S_TASK_TURNING = 36     # 1 while turning (the speed lock holds)
S_TASK_CRUISE = 37      # the task's cruise speed
N_STATE = 38


# --- Python helpers ---------------------------------------------------------------------------------------------
def mission_array(mission: Mission, rows: int | None = None) -> np.ndarray:
    """The (rows, :data:`N_MISSION_FIELDS`) float64 array of a mission's items (``rows`` >= the item count pads
    with :data:`NO_ITEM` rows, for missions of several tests in one array)."""
    items = mission.items
    rows = len(items) if rows is None else rows
    if rows < len(items):
        raise ValueError(f"mission_array: {len(items)} items do not fit in {rows} rows")
    out = np.zeros((rows, N_MISSION_FIELDS), dtype=np.float64)
    out[:, M_X:M_Z + 1] = NAN
    out[:, M_SPEED] = NAN
    for i, it in enumerate(items):
        out[i] = (int(it.command), it.x, it.y, it.z, it.acceptance_radius, it.hold_s, it.speed)
    return out


def param_vector(params, start_time: float = 0.0, takeoff_hold_s: float = 0.0) -> np.ndarray:
    """The float64 parameter vector of the kernels from the resolved PX4 parameters, the mission start after arming
    and the take-off hold [s] (the arguments of :class:`~surrealist_gym.sim.navigation.navigator.Navigator`)."""
    out = np.empty(N_PARAMS, dtype=np.float64)
    for i, name in enumerate(PARAM_NAMES):
        out[i] = params[name]
    out[P_YAW_RATE_RAD] = math.radians(params["MPC_YAWRAUTO_MAX"])
    out[P_START_TIME] = start_time
    out[P_TAKEOFF_HOLD_S] = float(takeoff_hold_s)
    out[P_SQUARE_EXPONENT] = 2.0
    return out


def initial_state(params: np.ndarray) -> np.ndarray:
    """A navigator's state before its first update (:meth:`Navigator.__init__`), from :func:`param_vector`."""
    state = np.empty(N_STATE, dtype=np.float64)
    nav_reset(state, params)
    return state


def plan_inputs(plan) -> tuple[int, tuple[float, float, float], float]:
    """A planner output (:class:`~surrealist_gym.sim.avoidance.planner.PlannerCommand`, or None) as :func:`nav_update`
    takes
    it: (kind, 3-vector, yaw)."""
    if plan is None:
        return PLAN_NONE, (0.0, 0.0, 0.0), 0.0
    if plan.position is not None:
        p = plan.position
        return PLAN_POSITION, (float(p[0]), float(p[1]), float(p[2])), float(plan.yaw)
    v = plan.velocity
    return PLAN_VELOCITY, (float(v[0]), float(v[1]), float(v[2])), float(plan.yaw)


def phase_of(state: np.ndarray) -> Phase:
    """The state's phase as a :class:`~surrealist_gym.sim.navigation.navigator.Phase`."""
    return PHASES[int(state[S_PHASE])]


# --- CPython's arithmetic -------------------------------------------------------------------------------------------
@njit(cache=True)
def py_square(x, params):  # pragma: no cover - compiled
    """CPython's ``x ** 2``: libm's ``pow(x, 2.0)``, which is not always ``x * x``; the exponent comes from the
    params vector so that LLVM cannot rewrite the call to a multiplication."""
    return x ** params[P_SQUARE_EXPONENT]


@njit(cache=True)
def line_projection(px, py, ax, ay, bx, by):  # pragma: no cover - compiled
    """:func:`surrealist_gym.geometry.line_projection` of (px, py) on the line a -> b: (defined, fraction along,
    foot x, foot y); not defined (its None) when a and b (nearly) coincide."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    if length2 < 1e-6:
        return False, 0.0, 0.0, 0.0
    s = ((px - ax) * dx + (py - ay) * dy) / length2
    return True, s, ax + s * dx, ay + s * dy


# --- accessors (the Navigator's properties) ---------------------------------------------------------------------
@njit(cache=True)
def nav_phase(state):  # pragma: no cover - compiled
    """The phase code (:data:`PHASES`)."""
    return int(state[S_PHASE])


@njit(cache=True)
def nav_index(state):  # pragma: no cover - compiled
    """The current mission item (-1 before the first)."""
    return int(state[S_INDEX])


@njit(cache=True)
def nav_cruise(state):  # pragma: no cover - compiled
    """The mission's current horizontal speed [m/s] (Navigator.cruise)."""
    return state[S_CRUISE]


@njit(cache=True)
def nav_target(state):  # pragma: no cover - compiled
    """The current target (x, y, z up) [m] (Navigator.target's first three values, what ``goal()`` gives the
    planner)."""
    return state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2]


nav_goal = nav_target  #: Navigator.goal()


@njit(cache=True)
def nav_prev(state):  # pragma: no cover - compiled
    """The previous setpoint (Navigator.prev)."""
    return state[S_PREV], state[S_PREV + 1], state[S_PREV + 2]


@njit(cache=True)
def nav_uses_planner(state):  # pragma: no cover - compiled
    """Navigator.uses_planner: the phase hands the horizontal flight to the avoidance planner."""
    return int(state[S_PHASE]) == PH_CRUISE


@njit(cache=True)
def nav_armed(state):  # pragma: no cover - compiled
    """Navigator.armed: every phase but DONE, and DONE after a mission that ended in the air."""
    return int(state[S_PHASE]) != PH_DONE or state[S_FINISHED_IN_AIR] != 0.0


@njit(cache=True)
def nav_on_ground_phase(state):  # pragma: no cover - compiled
    """Navigator.on_ground_phase: idle, landed, or done after landing."""
    ph = int(state[S_PHASE])
    return ph == PH_IDLE or ph == PH_LANDED or (ph == PH_DONE and state[S_FINISHED_IN_AIR] == 0.0)


@njit(cache=True)
def nav_mission_complete(state):  # pragma: no cover - compiled
    """Navigator.mission_complete: disarmed after landing, or the hold after the last item is over."""
    return int(state[S_PHASE]) == PH_DONE or (state[S_FINISHED_IN_AIR] != 0.0 and state[S_T] >= state[S_HOLD_UNTIL])


# --- the state machine (Navigator._advance and its helpers) --------------------------------------------------------
@njit(cache=True)
def nav_reset(state, params):  # pragma: no cover - compiled
    """Navigator.__init__: idle before the first item, cruise at MPC_XY_CRUISE, nothing set."""
    state[:] = 0.0
    state[S_PHASE] = PH_IDLE
    state[S_INDEX] = -1.0
    state[S_CRUISE] = params[P_MPC_XY_CRUISE]
    state[S_YAW_SP] = NAN
    state[S_LANDED_SINCE] = NAN
    state[S_CARROT:S_CARROT + 3] = NAN
