"""Physical ranges of the values that set up the simulated UAV: one table for UAV profiles (``params``, ``planner``,
``sensor``, ``noise``, timings) and for a test's PX4 ``params`` and ``uav.*`` settings; and :class:`FrozenDict`, the
read-only mapping that holds such values (a test's, a log's or a profile's parameters) inside frozen dataclasses.

Keys are spelt as a profile spells them: a PX4 parameter by its name (``MPC_XY_CRUISE``), a profile field by its
name (``takeoff_delay_s``), a planner, camera or noise field with its section (``planner.cruise_speed``,
``sensor.rays_h``, ``noise.pos_noise_std``); a test's ``uav.<setting>`` param is checked as ``<setting>``. A value
outside its range would fly a UAV that times out, flies away or divides by zero, so it is refused before anything
flies, in one line naming the field. A numeric value without an entry need only be finite.

PX4 parameters: the upper bounds are the ``@max`` of PX4 v1.12's parameter metadata (the firmware generation of
case0.ulg and of Aerialist's SITL), from the ``*_params.c`` files that generate the parameter reference
(https://docs.px4.io/v1.12/en/advanced_config/parameter_reference.html): ``mc_pos_control_params.c`` (e.g.
MPC_XY_CRUISE and MPC_XY_VEL_MAX at most 20 m/s, MPC_Z_VEL_MAX_UP 8, MPC_Z_VEL_MAX_DN 4, MPC_TKO_SPEED 5,
accelerations 15 m/s^2, MPC_JERK_AUTO 80 and MPC_JERK_MAX 500 m/s^3, thrusts 1), ``navigator_params.c``
(NAV_ACC_RAD and NAV_MC_ALT_RAD at most 200 m), ``mission_params.c`` (MIS_TAKEOFF_ALT 80 m, MIS_YAW_ERR 90 deg),
``rtl_params.c`` (RTL_RETURN_ALT 150 m, RTL_LAND_DELAY 300 s), ``mc_att_control_params.c`` and
``mc_rate_control_params.c`` (gains, rate limits 1800 deg/s) and ``commander_params.c`` (COM_DISARM_LAND 20 s).
Where the metadata gives no maximum, the bound is named beside the entry. The lower bounds are where the simulated
UAV stops being one, not PX4's ``@min`` (which PX4 itself does not enforce and which flights do go below, e.g. a
cruise speed under 3 m/s): a speed, an acceleration, a jerk, the hover thrust and the velocity gain the controller
divides by must be > 0; gains, radii and altitudes >= 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


class FrozenDict(dict):
    """A read-only dict: hashable, picklable (unlike ``types.MappingProxyType``), and equal to a plain dict."""

    def _readonly(self, *args, **kwargs):
        raise TypeError(f"{type(self).__name__} is read-only")

    __setitem__ = __delitem__ = clear = pop = popitem = setdefault = update = __ior__ = _readonly

    def __hash__(self) -> int:
        return hash(tuple(sorted(self.items())))

    def __reduce__(self):
        return (type(self), (dict(self),))


UAV_SETTING_PREFIX = "uav."  # a test's params named uav.<setting> set the simulated UAV, not PX4
UAV_TIMINGS = ("takeoff_delay_s", "takeoff_hold_s")  # the UAV settings that are profile fields, not the planner's


@dataclass(frozen=True, slots=True)
class Range:
    """A closed or half-open interval of finite numbers, with its unit for messages."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    unit: str = ""

    def holds(self, value: float) -> bool:
        """Whether ``value`` lies in the range (each end open or closed as set)."""
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def __str__(self) -> str:
        if self.high == math.inf:
            text = f"{'>' if self.low_open else '>='} {self.low:g}"
        else:
            text = f"in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}{')' if self.high_open else ']'}"
        return text + (f" {self.unit}" if self.unit else "")


def _speed(high: float) -> Range:
    return Range(0.0, high, low_open=True, unit="m/s")


def _accel(high: float) -> Range:
    return Range(0.0, high, low_open=True, unit="m/s^2")


def _gain(high: float = math.inf, positive: bool = False) -> Range:
    return Range(0.0, high, low_open=positive)


_METRES = "m"
_SECONDS = "s"
_THRUST = Range(0.0, 1.0, low_open=True)  # normalised thrust: 0 cannot lift, above 1 is more than the motors give
_FLAG = Range(0.0, 1.0)
_NOISE_M = Range(0.0, 10.0, unit=_METRES)  # a position error beyond 10 m is no estimator's
_TAU = Range(0.0, 3600.0, low_open=True, unit=_SECONDS)
_MAX_S = 3600.0  # [s] an hour on the ground or at a hold is longer than any battery lasts

RANGES = FrozenDict({
    # --- PX4 parameters the simulator reads (sim/config.py: PX4_DEFAULTS), PX4 v1.12 metadata maxima ---
    "MPC_XY_CRUISE": _speed(20.0), "MPC_XY_VEL_MAX": _speed(20.0),
    "MPC_Z_VEL_MAX_UP": _speed(8.0), "MPC_Z_VEL_MAX_DN": _speed(4.0), "MPC_TKO_SPEED": _speed(5.0),
    "MPC_LAND_SPEED": _speed(4.0),  # no @max in the metadata: bounded by the descent limit's (MPC_Z_VEL_MAX_DN)
    "MPC_ACC_HOR": _accel(15.0), "MPC_ACC_UP_MAX": _accel(15.0), "MPC_ACC_DOWN_MAX": _accel(15.0),
    "MPC_JERK_AUTO": Range(0.0, 80.0, low_open=True, unit="m/s^3"),
    "MPC_JERK_MAX": Range(0.0, 500.0, low_open=True, unit="m/s^3"),
    "MPC_THR_HOVER": Range(0.0, 1.0, low_open=True, high_open=True),  # the controller divides by it
    "MPC_THR_MIN": _THRUST, "MPC_THR_MAX": _THRUST, "MPC_USE_HTE": _FLAG,
    "MPC_TILTMAX_AIR": Range(0.0, 89.0, low_open=True, unit="deg"),
    "MPC_XY_P": _gain(2.0, positive=True), "MPC_Z_P": _gain(1.5, positive=True),
    "MPC_XY_VEL_P_ACC": _gain(5.0, positive=True),  # the anti-windup divides by it
    "MPC_XY_VEL_I_ACC": _gain(60.0), "MPC_XY_VEL_D_ACC": _gain(2.0),
    "MPC_Z_VEL_P_ACC": _gain(15.0, positive=True), "MPC_Z_VEL_I_ACC": _gain(3.0), "MPC_Z_VEL_D_ACC": _gain(2.0),
    "MPC_XY_TRAJ_P": _gain(1.0, positive=True), "MPC_XY_ERR_MAX": Range(0.0, 10.0, low_open=True),
    "MPC_TKO_RAMP_T": Range(0.0, 5.0, unit=_SECONDS),
    "MPC_LAND_ALT1": Range(0.0, 122.0, unit=_METRES), "MPC_LAND_ALT2": Range(0.0, 122.0, unit=_METRES),
    "MPC_YAWRAUTO_MAX": Range(0.0, 360.0, low_open=True, unit="deg/s"), "MPC_YAW_MODE": Range(0.0, 4.0),
    "MC_ROLL_P": _gain(12.0), "MC_PITCH_P": _gain(12.0), "MC_YAW_P": _gain(5.0), "MC_YAW_WEIGHT": _gain(1.0),
    "MC_ROLLRATE_P": _gain(0.5), "MC_ROLLRATE_I": _gain(), "MC_ROLLRATE_D": _gain(0.01),
    "MC_ROLLRATE_K": _gain(5.0, positive=True),
    "MC_PITCHRATE_P": _gain(0.6), "MC_PITCHRATE_I": _gain(), "MC_PITCHRATE_D": _gain(),
    "MC_PITCHRATE_K": _gain(5.0, positive=True),
    "MC_YAWRATE_P": _gain(0.6), "MC_YAWRATE_I": _gain(), "MC_YAWRATE_D": _gain(),
    "MC_YAWRATE_K": _gain(5.0, positive=True),
    "MC_ROLLRATE_MAX": Range(0.0, 1800.0, unit="deg/s"), "MC_PITCHRATE_MAX": Range(0.0, 1800.0, unit="deg/s"),
    "MC_YAWRATE_MAX": Range(0.0, 1800.0, unit="deg/s"),
    "MC_RR_INT_LIM": _gain(), "MC_PR_INT_LIM": _gain(), "MC_YR_INT_LIM": _gain(), "THR_MDL_FAC": _gain(1.0),
    "NAV_ACC_RAD": Range(0.0, 200.0, low_open=True, unit=_METRES),
    "NAV_MC_ALT_RAD": Range(0.0, 200.0, low_open=True, unit=_METRES),
    "MIS_TAKEOFF_ALT": Range(0.0, 80.0, unit=_METRES), "MIS_YAW_ERR": Range(0.0, 90.0, unit="deg"),
    "RTL_RETURN_ALT": Range(0.0, 150.0, unit=_METRES), "RTL_LAND_DELAY": Range(-1.0, 300.0, unit=_SECONDS),
    # the land detector's thresholds have no @max: bounded as the speeds above
    "LNDMC_Z_VEL_MAX": _speed(8.0), "LNDMC_XY_VEL_MAX": _speed(20.0),
    "LNDMC_TRIG_TIME": Range(0.0, 10.0, low_open=True, unit=_SECONDS),
    "COM_DISARM_LAND": Range(-1.0, 20.0, unit=_SECONDS), "COM_OBS_AVOID": _FLAG,
    # --- UAV profile fields and the UAV settings a test's uav.* params set ---
    "takeoff_delay_s": Range(0.0, _MAX_S, unit=_SECONDS), "takeoff_hold_s": Range(0.0, _MAX_S, unit=_SECONDS),
    "timeout_s": Range(0.0, 86_400.0, low_open=True, unit=_SECONDS),  # a day of simulated time
    "obstacle_collision_scale": Range(0.0, 1.0, low_open=True),
    # --- planners (sim/avoidance.py, sim/px4_avoidance.py): speeds bounded as PX4's cruise and climb ---
    "planner.cruise_speed": _speed(20.0), "planner.avoid_speed": _speed(20.0),
    "planner.max_climb_rate": Range(0.0, 8.0, unit="m/s"), "planner.goal_brake_accel": _accel(15.0),
    "planner.max_turn_rate_deg_s": Range(0.0, 1800.0, low_open=True, unit="deg/s"),
    "planner.range_max": Range(0.0, 100.0, low_open=True, unit=_METRES),
    "planner.max_sensor_range": Range(0.0, 100.0, low_open=True, unit=_METRES),
    "planner.memory_time": _TAU, "planner.max_point_age_s": _TAU,
    "planner.heading_offset_deg": Range(-90.0, 90.0, unit="deg"),
    # --- depth camera (sim/sensor.py): rays cost time as their product, so a few hundred per axis at most ---
    "sensor.rays_h": Range(1.0, 512.0), "sensor.rays_v": Range(1.0, 512.0),
    "sensor.range_max": Range(0.0, 100.0, low_open=True, unit=_METRES),
    "sensor.noise_std": _NOISE_M,
    # --- run-to-run variation (sim/config.py: NoiseConfig) ---
    "noise.pos_noise_std": _NOISE_M, "noise.pos_drift_std": _NOISE_M,
    "noise.vel_noise_std": Range(0.0, 10.0, unit="m/s"),
    "noise.turbulence_std": Range(0.0, 30.0, unit="m/s"),  # the wind bound of testcase.MAX_WIND_SPEED_MS
    "noise.pos_drift_tau_s": _TAU, "noise.turbulence_tau_s": _TAU,
    "noise.planner_jitter_s": Range(0.0, 5.0, unit=_SECONDS), "noise.start_jitter_s": Range(0.0, 60.0, unit=_SECONDS),
})


def problem(key: str, value) -> str | None:
    """What is wrong with ``value`` for ``key`` (None when nothing is): a number outside the key's physical range
    (:data:`RANGES`), anything but a finite number for a key with a range, or a non-finite number for any key
    (other values, such as a planner's flags, are left to the field's own type)."""
    rng = RANGES.get(key)
    number = not isinstance(value, bool) and isinstance(value, (int, float))
    if rng is None:
        return f"expected a finite number, got {value!r}" if number and not math.isfinite(value) else None
    if not number or not math.isfinite(value):
        return f"expected a finite number {rng}, got {value!r}"
    return None if rng.holds(value) else f"expected a number {rng}, got {value:g}"


def param_problem(name: str, value) -> str | None:
    """What is wrong with a test's param ``name`` (a PX4 parameter, or a UAV setting ``uav.<setting>``: a timing or
    ``planner.<field>``), or None; a param must be a finite number. (Whether a planner field exists depends on the
    UAV's avoidance model: sim/profiles.py: with_uav_settings checks that.)"""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return f"expected a number, got {value!r}"
    key = name.removeprefix(UAV_SETTING_PREFIX) if name.startswith(UAV_SETTING_PREFIX) else name
    if name.startswith(UAV_SETTING_PREFIX) and key not in UAV_TIMINGS and not key.startswith("planner."):
        return f"unknown UAV setting (expected one of {list(UAV_TIMINGS)} or planner.<field>)"
    return problem(key, value) or (None if math.isfinite(value) else f"expected a finite number, got {value!r}")


__all__ = ["FrozenDict", "RANGES", "Range", "UAV_SETTING_PREFIX", "UAV_TIMINGS", "param_problem", "problem"]
