"""The navigator (:class:`~surrealist_gym.sim.navigator.Navigator`) and PX4's avoidance flight task
(:class:`~surrealist_gym.sim.flight_task.AvoidanceFlightTask`) as numba kernels over plain arrays, for the
compiled flight loop (docs/compiled-loop.md). The classes stay the readable reference; every function here follows
one of their methods line by line (named in its docstring), with the same floating-point operations in the same
order, so that a kernel run equals the class bit for bit (tests/surrealist_gym/sim/test_navigator_kernels.py
replays recorded flights through both).

Arrays, built once per run or per test:

- **state** (:func:`initial_state`): one float64 vector of :data:`N_STATE` values per vehicle, named by the ``S_*``
  offsets: the phase (its position in :class:`~surrealist_gym.sim.navigator.Phase`, :data:`PHASES`), the item
  index, the cruise speed, the current target (x, y, z and, during the RTL climb, the return position), the
  previous setpoint, the timers, the slewed velocity command, the yaw setpoint, the carrot, and the flight task's
  trajectory (position, velocity, acceleration, speed lock). The class's ``None`` values (yaw setpoint before the
  first update, landed-since, carrot) are NaN; its booleans are 0.0 / 1.0.
- **mission** (:func:`mission_array`): one row per item, columns ``M_*`` (MAV_CMD code, x, y, z, acceptance
  radius, hold time, speed); rows after the last item have the command :data:`NO_ITEM`, so missions of several
  lengths share one padded array.
- **params** (:func:`param_vector`): the PX4 parameters the navigator and the task read, at ``P_<NAME>`` offsets,
  plus the run's mission start and take-off hold.

:func:`nav_update` is :meth:`Navigator.update`. The planner's output enters as three values (:func:`plan_inputs`):
a kind (:data:`PLAN_NONE`, :data:`PLAN_VELOCITY` for the simple planner's ``velocity``, :data:`PLAN_POSITION` for
PX4-Avoidance's ``position``), that 3-vector, and the yaw.

Bit equality with CPython needs :mod:`~surrealist_gym.sim.cpython_math`'s ``py_hypot`` and ``py_remainder``, and
:func:`py_square` (CPython's ``x ** 2`` is libm's ``pow``, which rounds ~0.08 % of squares differently from
``x * x``; LLVM rewrites ``pow(x, 2.0)`` with a constant exponent to ``x * x``, so the exponent is read from the
params vector at run time).
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..mission import Command, Mission
from .cpython_math import py_hypot, py_remainder
from .flight_task import _COS_TURN, _TURN_MIN_SPEED, stopping_speed
from .navigator import Phase

__all__ = ["PHASES", "N_STATE", "PLAN_NONE", "PLAN_VELOCITY", "PLAN_POSITION", "initial_state", "mission_array",
           "param_vector", "plan_inputs", "phase_of", "nav_update", "nav_target", "nav_goal", "nav_prev",
           "nav_cruise", "nav_index", "nav_phase", "nav_armed", "nav_on_ground_phase", "nav_uses_planner",
           "nav_mission_complete", "task_start", "task_update", "task_target", "CompiledNavigator"]

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

_stopping_speed = njit(cache=True)(stopping_speed)  # the flight task's own function, compiled


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
    and the take-off hold [s] (the arguments of :class:`~surrealist_gym.sim.navigator.Navigator`)."""
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
    """A planner output (:class:`~surrealist_gym.sim.planner.PlannerCommand`, or None) as :func:`nav_update` takes
    it: (kind, 3-vector, yaw)."""
    if plan is None:
        return PLAN_NONE, (0.0, 0.0, 0.0), 0.0
    if plan.position is not None:
        p = plan.position
        return PLAN_POSITION, (float(p[0]), float(p[1]), float(p[2])), float(plan.yaw)
    v = plan.velocity
    return PLAN_VELOCITY, (float(v[0]), float(v[1]), float(v[2])), float(plan.yaw)


def phase_of(state: np.ndarray) -> Phase:
    """The state's phase as a :class:`~surrealist_gym.sim.navigator.Phase`."""
    return PHASES[int(state[S_PHASE])]


# --- CPython's arithmetic -------------------------------------------------------------------------------------------
@njit(cache=True, inline="always")
def py_square(x, params):  # pragma: no cover - compiled
    """CPython's ``x ** 2``: libm's ``pow(x, 2.0)``, which is not always ``x * x``; the exponent comes from the
    params vector so that LLVM cannot rewrite the call to a multiplication."""
    return x ** params[P_SQUARE_EXPONENT]


@njit(cache=True, inline="always")
def _line_projection(px, py, ax, ay, bx, by):  # pragma: no cover - compiled
    """:func:`surrealist_gym.geometry.line_projection` of (px, py) on the line a -> b: (defined, fraction along,
    foot x, foot y); not defined (its None) when a and b (nearly) coincide."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    if length2 < 1e-6:
        return False, 0.0, 0.0, 0.0
    s = ((px - ax) * dx + (py - ay) * dy) / length2
    return True, s, ax + s * dx, ay + s * dy


# --- accessors (the Navigator's properties) ---------------------------------------------------------------------
@njit(cache=True, inline="always")
def nav_phase(state):  # pragma: no cover - compiled
    """The phase code (:data:`PHASES`)."""
    return int(state[S_PHASE])


@njit(cache=True, inline="always")
def nav_index(state):  # pragma: no cover - compiled
    """The current mission item (-1 before the first)."""
    return int(state[S_INDEX])


@njit(cache=True, inline="always")
def nav_cruise(state):  # pragma: no cover - compiled
    """The mission's current horizontal speed [m/s] (Navigator.cruise)."""
    return state[S_CRUISE]


@njit(cache=True, inline="always")
def nav_target(state):  # pragma: no cover - compiled
    """The current target (x, y, z up) [m] (Navigator.target's first three values, what ``goal()`` gives the
    planner)."""
    return state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2]


nav_goal = nav_target  #: Navigator.goal()


@njit(cache=True, inline="always")
def nav_prev(state):  # pragma: no cover - compiled
    """The previous setpoint (Navigator.prev)."""
    return state[S_PREV], state[S_PREV + 1], state[S_PREV + 2]


@njit(cache=True, inline="always")
def nav_uses_planner(state):  # pragma: no cover - compiled
    """Navigator.uses_planner: the phase hands the horizontal flight to the avoidance planner."""
    return int(state[S_PHASE]) == PH_CRUISE


@njit(cache=True, inline="always")
def nav_armed(state):  # pragma: no cover - compiled
    """Navigator.armed: every phase but DONE, and DONE after a mission that ended in the air."""
    return int(state[S_PHASE]) != PH_DONE or state[S_FINISHED_IN_AIR] != 0.0


@njit(cache=True, inline="always")
def nav_on_ground_phase(state):  # pragma: no cover - compiled
    """Navigator.on_ground_phase: idle, landed, or done after landing."""
    ph = int(state[S_PHASE])
    return ph == PH_IDLE or ph == PH_LANDED or (ph == PH_DONE and state[S_FINISHED_IN_AIR] == 0.0)


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def _item_count(mission):  # pragma: no cover - compiled
    n = 0
    while n < mission.shape[0] and int(mission[n, M_COMMAND]) != NO_ITEM:
        n += 1
    return n


@njit(cache=True)
def _go(state, t, phase, x, y, z, return_x, return_y):  # pragma: no cover - compiled
    """Navigator._go: a new phase toward a target (the RTL climb's carries the return position), the carrot, the
    flight task and the land detector reset."""
    state[S_PHASE] = phase
    state[S_PHASE_T0] = t
    state[S_CARROT:S_CARROT + 3] = NAN
    state[S_TASK_ACTIVE] = 0.0
    state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2] = x, y, z
    state[S_TARGET + 3], state[S_TARGET + 4] = return_x, return_y
    state[S_LANDED_SINCE] = NAN


@njit(cache=True)
def _next_item(state, mission, params, t, pos):  # pragma: no cover - compiled
    """Navigator._next_item: skip to the next item with a flight phase (CHANGE_SPEED items set the cruise speed on
    the way); after the last, hold the last target for 2 s with the mission finished in the air."""
    n = _item_count(mission)
    while True:
        index = int(state[S_INDEX]) + 1
        state[S_INDEX] = index
        if index >= n:
            state[S_PHASE] = PH_HOLD
            state[S_FINISHED_IN_AIR] = 1.0
            if index <= 0:  # no item at all: hold where the vehicle is
                state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2] = pos[0], pos[1], pos[2]
            state[S_TARGET + 3] = state[S_TARGET + 4] = 0.0  # the class keeps target[:3]
            state[S_HOLD_UNTIL] = t + 2.0
            return
        cmd = int(mission[index, M_COMMAND])
        if cmd == CMD_CHANGE_SPEED:
            speed = mission[index, M_SPEED]
            if speed == speed and speed > 0:
                state[S_CRUISE] = speed
            continue
        if cmd == CMD_TAKEOFF:
            z = mission[index, M_Z]
            alt = max(z if z == z else 0.0, params[P_MIS_TAKEOFF_ALT])
            _go(state, t, PH_TAKEOFF, pos[0], pos[1], alt, 0.0, 0.0)
        elif cmd == CMD_WAYPOINT:
            _go(state, t, PH_CRUISE, mission[index, M_X], mission[index, M_Y], mission[index, M_Z], 0.0, 0.0)
        elif cmd == CMD_LAND:
            state[S_THEN_LAND] = 1.0
            prev_z = state[S_PREV + 2]
            alt = prev_z if prev_z > 0.5 else max(pos[2], 0.5)
            _go(state, t, PH_CRUISE, mission[index, M_X], mission[index, M_Y], alt, 0.0, 0.0)
        elif cmd == CMD_RETURN_TO_LAUNCH:
            state[S_THEN_LAND] = 1.0
            alt = max(pos[2], params[P_RTL_RETURN_ALT])
            if alt - pos[2] > params[P_NAV_MC_ALT_RAD]:
                _go(state, t, PH_CLIMB, pos[0], pos[1], alt, 0.0, 0.0)
            else:
                _go(state, t, PH_CRUISE, 0.0, 0.0, alt, 0.0, 0.0)
        return


@njit(cache=True)
def _next_position(state, mission):  # pragma: no cover - compiled
    """Navigator._next_position: (found, x, y, z) of the next item after the current one with a position that is
    not a take-off."""
    n = _item_count(mission)
    for i in range(int(state[S_INDEX]) + 1, n):
        if mission[i, M_X] == mission[i, M_X] and int(mission[i, M_COMMAND]) != CMD_TAKEOFF:
            return True, mission[i, M_X], mission[i, M_Y], mission[i, M_Z]
    return False, 0.0, 0.0, 0.0


@njit(cache=True)
def _passed(state, pos):  # pragma: no cover - compiled
    """Navigator._passed: the vehicle's projection on the line from the previous setpoint lies beyond the target."""
    ok, along, _, _ = _line_projection(pos[0], pos[1], state[S_PREV], state[S_PREV + 1], state[S_TARGET],
                                       state[S_TARGET + 1])
    return ok and along > 1.0


@njit(cache=True)
def _reached(state, mission, params, pos):  # pragma: no cover - compiled
    """Navigator._reached: within the item's acceptance radius (NAV_ACC_RAD without one; at most
    max(NAV_ACC_RAD, 0.1) for LAND and RTL) horizontally and max(NAV_MC_ALT_RAD, 0.1) vertically; with the flight
    task, passing the target along the line counts."""
    index = int(state[S_INDEX])
    has_item = 0 <= index < _item_count(mission)
    rad = params[P_NAV_ACC_RAD]
    if has_item and mission[index, M_ACCEPTANCE_RADIUS] > 0:
        rad = mission[index, M_ACCEPTANCE_RADIUS]
    if has_item:
        cmd = int(mission[index, M_COMMAND])
        if cmd == CMD_LAND or cmd == CMD_RETURN_TO_LAUNCH:
            rad = min(rad, max(params[P_NAV_ACC_RAD], 0.1))
    dh = py_hypot(pos[0] - state[S_TARGET], pos[1] - state[S_TARGET + 1])
    if state[S_TASK_ACTIVE] != 0.0 and _passed(state, pos):
        rad = dh + 0.5
    return dh < rad and abs(pos[2] - state[S_TARGET + 2]) < max(params[P_NAV_MC_ALT_RAD], 0.1)


@njit(cache=True)
def _advance(state, mission, params, t, pos, vel, ground_contact):  # pragma: no cover - compiled
    """Navigator._advance: the phase transitions of one step."""
    ph = int(state[S_PHASE])
    if ph == PH_IDLE:
        if t >= params[P_START_TIME]:
            state[S_PREV], state[S_PREV + 1], state[S_PREV + 2] = pos[0], pos[1], 0.0
            _next_item(state, mission, params, t, pos)
    elif ph == PH_TAKEOFF or ph == PH_CLIMB:
        if abs(pos[2] - state[S_TARGET + 2]) < params[P_NAV_MC_ALT_RAD]:
            state[S_PREV], state[S_PREV + 1], state[S_PREV + 2] = pos[0], pos[1], state[S_TARGET + 2]
            if ph == PH_CLIMB:
                _go(state, t, PH_CRUISE, state[S_TARGET + 3], state[S_TARGET + 4], state[S_TARGET + 2], 0.0, 0.0)
            elif params[P_TAKEOFF_HOLD_S] > 0:
                _go(state, t, PH_HOLD, state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2], 0.0, 0.0)
                state[S_HOLD_UNTIL] = t + params[P_TAKEOFF_HOLD_S]
            else:
                _next_item(state, mission, params, t, pos)
    elif ph == PH_CRUISE:
        if _reached(state, mission, params, pos):
            target_x, target_y, target_z = state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2]
            if state[S_THEN_LAND] != 0.0:
                _go(state, t, PH_DESCEND, target_x, target_y, target_z, 0.0, 0.0)
            else:
                hold_s = mission[int(state[S_INDEX]), M_HOLD_S]
                _go(state, t, PH_HOLD, target_x, target_y, target_z, 0.0, 0.0)
                state[S_HOLD_UNTIL] = t + max(hold_s, 0.0)
    elif ph == PH_HOLD:
        if t >= state[S_HOLD_UNTIL] and state[S_FINISHED_IN_AIR] == 0.0:
            state[S_PREV], state[S_PREV + 1], state[S_PREV + 2] = state[S_TARGET], state[S_TARGET + 1], \
                state[S_TARGET + 2]
            _next_item(state, mission, params, t, pos)
    elif ph == PH_DESCEND:
        vz_ok = abs(vel[2]) < params[P_LNDMC_Z_VEL_MAX]
        vxy_ok = py_hypot(vel[0], vel[1]) < params[P_LNDMC_XY_VEL_MAX]
        if ground_contact and vz_ok and vxy_ok:
            if state[S_LANDED_SINCE] != state[S_LANDED_SINCE]:
                state[S_LANDED_SINCE] = t
            elif t - state[S_LANDED_SINCE] >= params[P_LNDMC_TRIG_TIME]:
                state[S_PHASE], state[S_LANDED_AT] = PH_LANDED, t
        else:
            state[S_LANDED_SINCE] = NAN
    elif ph == PH_LANDED:
        if t - state[S_LANDED_AT] >= max(params[P_COM_DISARM_LAND], 0.0):
            state[S_PHASE] = PH_DONE


# --- setpoint shaping (Navigator._line_velocity ... _yaw_step) ---------------------------------------------------
@njit(cache=True)
def _line_velocity(state, params, pos):  # pragma: no cover - compiled
    """Navigator._line_velocity: along the line from the previous setpoint to the target at the cruise speed
    (vertical limits on a slope), braking before the target, with a cross-track correction."""
    p00, p01, p02 = state[S_PREV], state[S_PREV + 1], state[S_PREV + 2]
    p10, p11, p12 = state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2]
    dx, dy, dz = p10 - p00, p11 - p01, p12 - p02
    length = math.sqrt(dx * dx + dy * dy + dz * dz)
    ex, ey, ez = p10 - pos[0], p11 - pos[1], p12 - pos[2]
    dist = math.sqrt(ex * ex + ey * ey + ez * ez)
    if length < 1e-6:
        if dist > 1e-6:
            ux, uy, uz = ex / dist, ey / dist, ez / dist
        else:
            ux, uy, uz = 0.0, 0.0, 0.0
        s = 0.0
    else:
        ux, uy, uz = dx / length, dy / length, dz / length
        s = (pos[0] - p00) * ux + (pos[1] - p01) * uy + (pos[2] - p02) * uz
        s = min(max(s, 0.0), length)
    cx, cy, cz = p00 + ux * s - pos[0], p01 + uy * s - pos[1], p02 + uz * s - pos[2]
    remaining = ex * ux + ey * uy + ez * uz
    hor = py_hypot(ux, uy)
    vmax = state[S_CRUISE] / hor if hor > 1e-6 else params[P_MPC_Z_VEL_MAX_UP]
    if uz > 1e-6:
        vmax = min(vmax, params[P_MPC_Z_VEL_MAX_UP] / uz)
    elif uz < -1e-6:
        vmax = min(vmax, params[P_MPC_Z_VEL_MAX_DN] / -uz)
    brake = 0.5 * params[P_MPC_ACC_HOR]
    along = min(vmax, math.sqrt(2.0 * brake * max(remaining, 0.0)), params[P_MPC_XY_P] * max(remaining, 0.0) + 0.1)
    kp = params[P_MPC_XY_P]
    return along * ux + kp * cx, along * uy + kp * cy, along * uz + kp * cz


@njit(cache=True)
def _approach(state, mission, params, pos, v0, v1, v2):  # pragma: no cover - compiled
    """Navigator._approach: before a stop (landing, the last item) at most MPC_XY_P times the distance left."""
    has_next = _next_position(state, mission)[0]
    if not (state[S_THEN_LAND] != 0.0 or not has_next):
        return v0, v1, v2
    d = math.sqrt(py_square(state[S_TARGET] - pos[0], params) + py_square(state[S_TARGET + 1] - pos[1], params)
                  + py_square(state[S_TARGET + 2] - pos[2], params))
    cap = params[P_MPC_XY_P] * d + 0.1
    n = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
    if n <= cap:
        return v0, v1, v2
    return v0 * cap / n, v1 * cap / n, v2 * cap / n


@njit(cache=True)
def _carrot(state, params, pos, v0, v1, v2, dt):  # pragma: no cover - compiled
    """Navigator._carrot: the position setpoint moved by the velocity setpoint, kept within 1 m of the vehicle."""
    if state[S_CARROT] != state[S_CARROT]:
        c0, c1, c2 = pos[0], pos[1], pos[2]
    else:
        c0, c1, c2 = state[S_CARROT], state[S_CARROT + 1], state[S_CARROT + 2]
    c0, c1, c2 = c0 + v0 * dt, c1 + v1 * dt, c2 + v2 * dt
    d = math.sqrt(py_square(c0 - pos[0], params) + py_square(c1 - pos[1], params) + py_square(c2 - pos[2], params))
    if d > 1.0:
        c0, c1, c2 = pos[0] + (c0 - pos[0]) / d, pos[1] + (c1 - pos[1]) / d, pos[2] + (c2 - pos[2]) / d
    state[S_CARROT], state[S_CARROT + 1], state[S_CARROT + 2] = c0, c1, c2
    return c0, c1, c2


@njit(cache=True)
def _slew(state, params, v0, v1, v2, dt):  # pragma: no cover - compiled
    """Navigator._slew: the velocity command changes at most MPC_ACC_HOR horizontally, MPC_ACC_UP_MAX /
    MPC_ACC_DOWN_MAX vertically."""
    o0, o1, o2 = state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2]
    ah = params[P_MPC_ACC_HOR] * dt
    dx, dy = v0 - o0, v1 - o1
    d = py_hypot(dx, dy)
    if d > ah:
        dx, dy = dx * ah / d, dy * ah / d
    dz = min(max(v2 - o2, -params[P_MPC_ACC_DOWN_MAX] * dt), params[P_MPC_ACC_UP_MAX] * dt)
    state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2] = o0 + dx, o1 + dy, o2 + dz
    return o0 + dx, o1 + dy, o2 + dz


@njit(cache=True)
def _yaw_mode(state, params, pos, vel, has_target, target_x, target_y):  # pragma: no cover - compiled
    """Navigator._yaw_mode: the heading MPC_YAW_MODE asks for (0 the target, 1 home, 2 away from home, 3 along
    the velocity); the current yaw setpoint when it is undefined (no target, within 1 m, slower than 0.5 m/s)."""
    mode = int(params[P_MPC_YAW_MODE])
    if mode == 1:
        has_target, target_x, target_y = True, 0.0, 0.0
    elif mode == 2:
        has_target, target_x, target_y = True, 2 * pos[0], 2 * pos[1]
    elif mode == 3:
        if py_hypot(vel[0], vel[1]) > 0.5:
            return math.atan2(vel[1], vel[0])
        return state[S_YAW_SP]
    if not has_target:
        return state[S_YAW_SP]
    dx, dy = target_x - pos[0], target_y - pos[1]
    if py_hypot(dx, dy) < 1.0:
        return state[S_YAW_SP]
    return math.atan2(dy, dx)


@njit(cache=True)
def _yaw_step(params, current, target, dt):  # pragma: no cover - compiled
    """Navigator._yaw_step: toward the target heading at most MPC_YAWRAUTO_MAX, wrapped to [-pi, pi]."""
    step = params[P_YAW_RATE_RAD] * dt
    diff = py_remainder(target - current, 2 * math.pi)
    return py_remainder(current + max(-step, min(step, diff)), 2 * math.pi)


# --- the flight task (AvoidanceFlightTask) --------------------------------------------------------------------------
@njit(cache=True)
def task_start(state, cruise, pos, vel):  # pragma: no cover - compiled
    """AvoidanceFlightTask.__init__: the trajectory starts at the vehicle's position and velocity."""
    state[S_TASK_ACTIVE] = 1.0
    state[S_TASK_CRUISE] = cruise
    for i in range(3):
        state[S_TASK_POS + i] = pos[i]
        state[S_TASK_VEL + i] = vel[i]
        state[S_TASK_ACC + i] = 0.0
    state[S_TASK_MAX_SPEED_PREV] = cruise
    state[S_TASK_TURNING] = 0.0


@njit(cache=True)
def task_target(params, pos, prev, goal):  # pragma: no cover - compiled
    """AvoidanceFlightTask.target: PX4's own target (x, y, z): the mission item, the previous one, or the foot of
    the perpendicular on the line ("offtrack")."""
    r = params[P_NAV_ACC_RAD]
    ok, along, cx, cy = _line_projection(pos[0], pos[1], prev[0], prev[1], goal[0], goal[1])
    if not ok:
        return goal[0], goal[1], goal[2]
    if along > 1.0:
        return goal[0], goal[1], goal[2]
    if along < 0.0 and py_hypot(pos[0] - prev[0], pos[1] - prev[1]) > r:
        return prev[0], prev[1], prev[2]
    if py_hypot(pos[0] - cx, pos[1] - cy) > r:
        return cx, cy, goal[2]
    return goal[0], goal[1], goal[2]


@njit(cache=True)
def task_update(state, params, dt, pos, setpoint, prev, goal):  # pragma: no cover - compiled
    """AvoidanceFlightTask.update: one cycle toward the injected ``setpoint``; returns the (position, velocity,
    acceleration) setpoints (x, y, z up) and advances the task's trajectory in ``state``."""
    tp, tv, ta = S_TASK_POS, S_TASK_VEL, S_TASK_ACC
    # the turning check against PX4's own target
    tgt = task_target(params, pos, prev, goal)
    vxy = py_hypot(state[tv], state[tv + 1])
    tx, ty = tgt[0] - state[tp], tgt[1] - state[tp + 1]
    to_target = py_hypot(tx, ty)
    turning = (vxy > _TURN_MIN_SPEED and to_target > params[P_NAV_ACC_RAD]
               and (state[tv] * tx + state[tv + 1] * ty) / (vxy * to_target) < _COS_TURN)
    state[S_TASK_TURNING] = 1.0 if turning else 0.0
    # speed that stops at the injected point
    jerk = max(params[P_MPC_JERK_AUTO], 1e-3)
    dx, dy, dz = setpoint[0] - state[tp], setpoint[1] - state[tp + 1], setpoint[2] - state[tp + 2]
    dxy = py_hypot(dx, dy)
    xy_speed = min(state[S_TASK_CRUISE], _stopping_speed(jerk, params[P_MPC_ACC_HOR], dxy))
    if dz >= 0.0:
        z_speed = min(params[P_MPC_Z_VEL_MAX_UP], _stopping_speed(jerk, params[P_MPC_ACC_UP_MAX], dz))
    else:
        z_speed = min(params[P_MPC_Z_VEL_MAX_DN], _stopping_speed(jerk, params[P_MPC_ACC_DOWN_MAX], -dz))
    if turning:
        xy_speed = min(state[S_TASK_MAX_SPEED_PREV], xy_speed)
    else:
        state[S_TASK_MAX_SPEED_PREV] = xy_speed
    d = math.sqrt(dxy * dxy + dz * dz)
    if d > 1e-6:
        s = math.sqrt(xy_speed * xy_speed + z_speed * z_speed) / d
        vt0, vt1, vt2 = dx * s, dy * s, dz * s
        h = py_hypot(vt0, vt1)
        if h > xy_speed > 0.0:
            vt0, vt1 = vt0 * xy_speed / h, vt1 * xy_speed / h
        vt2 = max(-z_speed, min(z_speed, vt2))
    else:
        vt0, vt1, vt2 = 0.0, 0.0, 0.0
    # time stretch while the vehicle lags behind the trajectory
    ex, ey = state[tp] - pos[0], state[tp + 1] - pos[1]
    stretch = 1.0
    if ex * state[tv] + ey * state[tv + 1] > 0.0:
        stretch = 1.0 - min(max(py_hypot(ex, ey) / max(params[P_MPC_XY_ERR_MAX], 1e-3), 0.0), 1.0)
    step = dt * stretch
    for i in range(3):
        v_target = vt0 if i == 0 else (vt1 if i == 1 else vt2)
        if i < 2:
            a_max = params[P_MPC_ACC_HOR]
        else:
            a_max = params[P_MPC_ACC_UP_MAX] if v_target > state[tv + i] else params[P_MPC_ACC_DOWN_MAX]
        dv = v_target - state[tv + i]
        want = math.copysign(min(math.sqrt(2.0 * jerk * abs(dv)), a_max), dv)
        da = want - state[ta + i]
        lim = jerk * step
        state[ta + i] += max(-lim, min(lim, da))
        new_v = state[tv + i] + state[ta + i] * step
        if (dv > 0.0 and new_v > v_target) or (dv < 0.0 and new_v < v_target):
            new_v, state[ta + i] = v_target, 0.0
        state[tp + i] += 0.5 * (state[tv + i] + new_v) * step
        state[tv + i] = new_v
    return ((state[tp], state[tp + 1], state[tp + 2]), (state[tv], state[tv + 1], state[tv + 2]),
            (state[ta], state[ta + 1], state[ta + 2]))


# --- one navigator step -------------------------------------------------------------------------------------------
@njit(cache=True)
def nav_update(state, mission, params, t, pos, vel, yaw, dt, ground_contact, plan_kind, plan_vector,
               plan_yaw):  # pragma: no cover - compiled
    """Navigator.update: one navigator step.

    Args:
        state: the navigator's state (:func:`initial_state`), updated in place.
        mission, params: :func:`mission_array`, :func:`param_vector`.
        t: time since arming [s]. pos, vel: estimated position and velocity (x, y, z up) [m], [m/s] (tuples or
            arrays). yaw: estimated heading [rad]. dt: step [s]. ground_contact: the vehicle touches the ground.
        plan_kind, plan_vector, plan_yaw: the latest planner output (:func:`plan_inputs`).

    Returns:
        (pos_sp_ned, vel_ff_ned, acc_ff_ned, yaw_sp) as Navigator.update: NED position setpoint (nan = free),
        velocity and acceleration feed-forward, heading.
    """
    state[S_T] = t
    if state[S_YAW_SP] != state[S_YAW_SP]:
        state[S_YAW_SP] = yaw
    _advance(state, mission, params, t, pos, vel, ground_contact)
    ph = int(state[S_PHASE])
    if ph == PH_IDLE or ph == PH_LANDED or ph == PH_DONE:
        state[S_V_CMD] = state[S_V_CMD + 1] = state[S_V_CMD + 2] = 0.0
        return (NAN, NAN, NAN), (0.0, 0.0, 0.3), (0.0, 0.0, 0.0), state[S_YAW_SP]  # push down: minimum thrust
    pos_sp = (NAN, NAN, NAN)
    vel_sp = (0.0, 0.0, 0.0)
    acc = (0.0, 0.0, 0.0)
    yaw_target = state[S_YAW_SP]
    if ph == PH_TAKEOFF or ph == PH_CLIMB:
        if ph == PH_TAKEOFF:
            ramp = min(1.0, (t - state[S_PHASE_T0]) / max(params[P_MPC_TKO_RAMP_T], 1e-3))
            speed = params[P_MPC_TKO_SPEED]
        else:
            ramp = 1.0
            speed = params[P_MPC_Z_VEL_MAX_UP]
        err = state[S_TARGET + 2] - pos[2]
        vz = min(speed * ramp, math.sqrt(2.0 * 1.0 * max(err, 0.0)), params[P_MPC_Z_P] * err + 0.3 * speed)
        pos_sp, vel_sp = (state[S_TARGET], state[S_TARGET + 1], NAN), (0.0, 0.0, max(vz, -0.5))
        has_next, next_x, next_y, _ = _next_position(state, mission)
        yaw_target = _yaw_mode(state, params, pos, vel, has_next, next_x, next_y)
    elif ph == PH_HOLD:
        pos_sp = (state[S_TARGET], state[S_TARGET + 1], state[S_TARGET + 2])
    elif ph == PH_DESCEND:
        alt = pos[2]
        a1, a2 = params[P_MPC_LAND_ALT1], params[P_MPC_LAND_ALT2]
        vmax, vland = params[P_MPC_Z_VEL_MAX_DN], params[P_MPC_LAND_SPEED]
        if alt > a1:
            vd = vmax
        elif alt > a2 and a1 > a2:
            vd = vland + (vmax - vland) * (alt - a2) / (a1 - a2)
        else:
            vd = vland
        pos_sp, vel_sp = (state[S_TARGET], state[S_TARGET + 1], NAN), (0.0, 0.0, -vd)
    elif ph == PH_CRUISE:
        if plan_kind == PLAN_POSITION:  # a position setpoint: PX4's flight task
            if state[S_TASK_ACTIVE] == 0.0:
                task_start(state, state[S_CRUISE], pos, vel)
            prev = (state[S_PREV], state[S_PREV + 1], state[S_PREV + 2])
            pos_sp, vel_sp, acc = task_update(state, params, dt, pos, plan_vector, prev, nav_target(state))
            state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2] = vel_sp
            yaw_target = plan_yaw
        else:  # a velocity (or the mission line), slewed, with a position setpoint moving along
            if plan_kind == PLAN_VELOCITY:
                v0, v1, v2 = _approach(state, mission, params, pos, plan_vector[0], plan_vector[1], plan_vector[2])
                yaw_target = plan_yaw
            else:
                v0, v1, v2 = _line_velocity(state, params, pos)
                yaw_target = _yaw_mode(state, params, pos, vel, True, state[S_TARGET], state[S_TARGET + 1])
            o0, o1, o2 = state[S_V_CMD], state[S_V_CMD + 1], state[S_V_CMD + 2]
            vel_sp = _slew(state, params, v0, v1, v2, dt)
            acc = ((vel_sp[0] - o0) / dt, (vel_sp[1] - o1) / dt, (vel_sp[2] - o2) / dt)
            pos_sp = _carrot(state, params, pos, vel_sp[0], vel_sp[1], vel_sp[2], dt)
    state[S_YAW_SP] = _yaw_step(params, state[S_YAW_SP], yaw_target, dt)
    return ((pos_sp[0], pos_sp[1], -pos_sp[2]), (vel_sp[0], vel_sp[1], -vel_sp[2]), (acc[0], acc[1], -acc[2]),
            state[S_YAW_SP])


# --- a drop-in for the Python run loop -----------------------------------------------------------------------------
class CompiledNavigator:
    """:class:`~surrealist_gym.sim.navigator.Navigator`'s interface over the kernels (for the Python run loop
    until the whole outer loop is compiled): the same constructor, ``update`` and properties.

    Args:
        mission, params, start_time, takeoff_hold_s: as :class:`~surrealist_gym.sim.navigator.Navigator`.
    """

    __slots__ = ("state", "mission", "params")

    def __init__(self, mission: Mission, params: dict, start_time: float, takeoff_hold_s: float = 0.0):
        self.mission = mission_array(mission)
        self.params = param_vector(params, start_time, takeoff_hold_s)
        self.state = initial_state(self.params)

    def update(self, t: float, pos, vel, yaw: float, dt: float, ground_contact: bool, planner=None):
        """:meth:`Navigator.update` (see :func:`nav_update`)."""
        kind, vector, plan_yaw = plan_inputs(planner)
        return nav_update(self.state, self.mission, self.params, t, pos, vel, yaw, dt, ground_contact, kind,
                          vector, plan_yaw)

    def goal(self) -> tuple[float, float, float]:
        """The current target (x, y, z up) [m] for the avoidance planner."""
        return nav_target(self.state)

    phase = property(lambda self: phase_of(self.state), doc="Navigator.phase")
    index = property(lambda self: int(self.state[S_INDEX]), doc="Navigator.index")
    cruise = property(lambda self: float(self.state[S_CRUISE]), doc="Navigator.cruise")
    target = property(lambda self: nav_target(self.state), doc="Navigator.target (x, y, z)")
    prev = property(lambda self: nav_prev(self.state), doc="Navigator.prev")
    armed = property(lambda self: nav_armed(self.state), doc="Navigator.armed")
    on_ground_phase = property(lambda self: nav_on_ground_phase(self.state), doc="Navigator.on_ground_phase")
    uses_planner = property(lambda self: nav_uses_planner(self.state), doc="Navigator.uses_planner")
    mission_complete = property(lambda self: nav_mission_complete(self.state), doc="Navigator.mission_complete")
