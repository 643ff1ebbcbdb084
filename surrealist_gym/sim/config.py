"""Configuration of the simulator: frozen ``*Config`` dataclasses (units in brackets) and PX4 parameter defaults.

PX4 parameters keep their PX4 names. Their values come, in increasing priority, from :data:`PX4_DEFAULTS`
(PX4 v1.12 defaults, the firmware generation of ``case0.ulg``), the reference log's parameters (when the test has
one and :attr:`SimConfig.use_reference_params` is set), the test case's ``params`` and
:attr:`SimConfig.params` overrides.
"""
from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from enum import Enum
from functools import lru_cache
from typing import TYPE_CHECKING, Any, Mapping, Union

# a test's params uav.<setting> set the simulated UAV (profiles.py)
from ..errors import UAV_SETTING_PREFIX, FrozenDict, SurrealistError

if TYPE_CHECKING:  # the planners and the sensor load numba and PyBullet; a config names them only
    from .avoidance.px4.local_planner import Px4AvoidanceConfig
    from .avoidance.reactive import AvoidanceConfig
    from .sensing.sensor import DepthSensorConfig

#: The configuration of either planner (``SimConfig.avoidance_config``).
PlannerConfig = Union["AvoidanceConfig", "Px4AvoidanceConfig"]

# PX4 v1.12 defaults of the parameters the simulated UAV reads (sources: the *_params.c / *_params.yaml of
# mc_pos_control, mc_att_control, mc_rate_control, navigator, land_detector, commander in PX4-Autopilot v1.12).
PX4_DEFAULTS: Mapping[str, float] = FrozenDict({
    # position / velocity control (mc_pos_control)
    "MPC_XY_P": 0.95, "MPC_Z_P": 1.0,
    "MPC_XY_VEL_P_ACC": 1.8, "MPC_XY_VEL_I_ACC": 0.4, "MPC_XY_VEL_D_ACC": 0.2,
    "MPC_Z_VEL_P_ACC": 4.0, "MPC_Z_VEL_I_ACC": 2.0, "MPC_Z_VEL_D_ACC": 0.0,
    "MPC_XY_CRUISE": 5.0, "MPC_XY_VEL_MAX": 12.0, "MPC_Z_VEL_MAX_UP": 3.0, "MPC_Z_VEL_MAX_DN": 1.0,
    "MPC_TILTMAX_AIR": 45.0, "MPC_THR_HOVER": 0.5, "MPC_USE_HTE": 1, "MPC_THR_MIN": 0.12, "MPC_THR_MAX": 1.0,
    "MPC_ACC_HOR": 3.0, "MPC_ACC_UP_MAX": 4.0, "MPC_ACC_DOWN_MAX": 3.0, "MPC_JERK_AUTO": 4.0, "MPC_JERK_MAX": 8.0,
    "MPC_TKO_SPEED": 1.5, "MPC_TKO_RAMP_T": 3.0, "MPC_LAND_SPEED": 0.7, "MPC_LAND_ALT1": 10.0,
    "MPC_LAND_ALT2": 5.0, "MPC_YAWRAUTO_MAX": 45.0, "MPC_YAW_MODE": 0, "MPC_XY_TRAJ_P": 0.5, "MPC_XY_ERR_MAX": 2.0,
    # attitude and rate control (mc_att_control, mc_rate_control)
    "MC_ROLL_P": 6.5, "MC_PITCH_P": 6.5, "MC_YAW_P": 2.8, "MC_YAW_WEIGHT": 0.4,
    "MC_ROLLRATE_P": 0.15, "MC_ROLLRATE_I": 0.2, "MC_ROLLRATE_D": 0.003, "MC_ROLLRATE_K": 1.0,
    "MC_PITCHRATE_P": 0.15, "MC_PITCHRATE_I": 0.2, "MC_PITCHRATE_D": 0.003, "MC_PITCHRATE_K": 1.0,
    "MC_YAWRATE_P": 0.2, "MC_YAWRATE_I": 0.1, "MC_YAWRATE_D": 0.0, "MC_YAWRATE_K": 1.0,
    "MC_ROLLRATE_MAX": 220.0, "MC_PITCHRATE_MAX": 220.0, "MC_YAWRATE_MAX": 200.0,
    "MC_RR_INT_LIM": 0.3, "MC_PR_INT_LIM": 0.3, "MC_YR_INT_LIM": 0.3, "THR_MDL_FAC": 0.0,
    # navigator (mission mode, RTL)
    "NAV_ACC_RAD": 10.0, "NAV_MC_ALT_RAD": 0.8, "MIS_TAKEOFF_ALT": 2.5, "MIS_YAW_ERR": 12.0,
    "RTL_RETURN_ALT": 60.0, "RTL_LAND_DELAY": 0.0,
    # land detector, commander
    "LNDMC_Z_VEL_MAX": 0.5, "LNDMC_XY_VEL_MAX": 1.5, "LNDMC_TRIG_TIME": 1.0, "COM_DISARM_LAND": 2.0,
    "COM_OBS_AVOID": 0,
})


class VehicleModel(str, Enum):
    """Vehicle presets (see :mod:`surrealist_gym.sim.vehicle.airframe`)."""

    PX4_VISION = "px4_vision"
    IRIS = "iris"


class AvoidanceModel(str, Enum):
    """Which obstacle-avoidance planner flies with ``COM_OBS_AVOID = 1``."""

    PX4 = "px4"        #: PX4-Avoidance's local planner as in Aerialist's SITL (avoidance/px4/local_planner.py)
    SIMPLE = "simple"  #: a reactive histogram planner tuned to the real PX4 Vision flight case0 (avoidance/reactive.py)


class Physics(str, Enum):
    """What integrates the vehicles and finds their contacts."""

    PYBULLET = "pybullet"  #: PyBullet (vehicle/world.py): the reference
    COMPILED = "compiled"  #: numba kernels: Bullet's integration, closed-form contacts (vehicle/compiled_physics.py)


PHYSICS_ENV = "SURREALIST_PHYSICS"


def default_physics() -> Physics:
    """The physics of a :class:`SimConfig` that names none: ``$SURREALIST_PHYSICS`` (``compiled`` or ``pybullet``),
    else the compiled kernels."""
    value = os.environ.get(PHYSICS_ENV) or Physics.COMPILED.value
    try:
        return Physics(value)
    except ValueError:
        raise SurrealistError(f"${PHYSICS_ENV}: {value!r} is not a physics (compiled or pybullet)") from None


TREE_REUSE_ENV = "SURREALIST_TREE_REUSE"
TREE_REUSE_M = 0.0  #: SimConfig.tree_reuse_m's default [m]: a tree every cycle (docs/compiled-loop.md, section 3)


def default_tree_reuse() -> float:
    """The ``tree_reuse_m`` of a :class:`SimConfig` that names none: ``$SURREALIST_TREE_REUSE`` (metres, 0: a tree
    every cycle), else :data:`TREE_REUSE_M`."""
    value = os.environ.get(TREE_REUSE_ENV)
    if not value:
        return TREE_REUSE_M
    try:
        metres = float(value)
    except ValueError:
        metres = math.nan
    if not 0 <= metres < math.inf:
        raise SurrealistError(f"${TREE_REUSE_ENV}: {value!r} is not a distance (metres >= 0; 0: a tree every cycle)")
    return metres


@dataclass(frozen=True, slots=True)
class NoiseConfig:
    """Sources of run-to-run variation; all drawn from the run's seed.

    Attributes:
        pos_noise_std: white noise of the estimated position [m].
        pos_drift_std: stationary std of the slowly drifting estimator position error [m].
        pos_drift_tau_s: correlation time of that drift [s].
        vel_noise_std: white noise of the estimated velocity [m/s].
        turbulence_std: std of the ambient wind turbulence added to the test's wind [m/s].
        turbulence_tau_s: correlation time of the turbulence [s].
        sensor: whether the depth sensor gets the run's random generator (its own noise model).
        planner_jitter_s: the avoidance planner's cycles keep their period ``1 / planner_hz`` from a phase drawn per
            run, and each plans U(0, planner_jitter_s) [s] after its start, on the outer-loop grid (0: at every
            ``1 / planner_hz`` from the start).
        start_jitter_s: std of the mission start's offset from ``takeoff_delay_s`` [s] (never before arming).
    """

    pos_noise_std: float = 0.02
    pos_drift_std: float = 0.10
    pos_drift_tau_s: float = 5.0
    vel_noise_std: float = 0.03
    turbulence_std: float = 0.3
    turbulence_tau_s: float = 2.0
    sensor: bool = True
    planner_jitter_s: float = 0.0
    start_jitter_s: float = 0.0

    @classmethod
    def off(cls) -> "NoiseConfig":
        """No noise at all: every seed gives the same flight."""
        return cls(0.0, 0.0, 5.0, 0.0, 0.0, 2.0, False, 0.0, 0.0)


@dataclass(frozen=True, slots=True)
class SimConfig:
    """How a test case is flown.

    Attributes:
        vehicle: vehicle preset.
        physics_hz: PyBullet's integration rate [Hz] (>= 200).
        control_hz: attitude/rate loop and motor rate [Hz]; PyBullet takes physics_hz / control_hz sub-steps
            per control step (the forces held constant over them).
        outer_hz: position/velocity controller and navigator rate [Hz].
        planner_hz: avoidance planner and depth sensor rate [Hz].
        log_hz: rate of the recorded local-position samples (the trajectory and the ULog) [Hz].
        avoidance: fly with the local planner; None = from the parameter COM_OBS_AVOID.
        params: PX4 parameter overrides (highest priority).
        use_reference_params: read the parameters of the test's reference log, below the test's own.
        takeoff_delay_s: time on the ground between arming (start of the log) and the mission start [s].
        takeoff_hold_s: time at the take-off altitude, once the take-off is accepted, before the next item starts
            [s] (0 in the code as read; a calibrated UAV may measure one: docs/calibration.md).
        timeout_s: simulated-time limit [s]; None = 90 s + 4 s per metre of the mission's path.
        stuck_window_s / stuck_distance_m: early stopping, off by default (None): the run ends as STUCK when
            its distance to the current goal has not shrunk by stuck_distance_m [m] during the last
            stuck_window_s [s] of flight. PX4 keeps flying such flights (and often finishes them).
        tree_reuse_m / tree_reuse_cycles: the compiled loop's PX4-Avoidance planner keeps its last look-ahead tree
            for up to tree_reuse_cycles cycles in a row while the vehicle stays within tree_reuse_m [m] of where
            it was built, toward the same goal: a hovering vehicle builds a tree about once a second instead of
            ten times. Default 0 (``$SURREALIST_TREE_REUSE`` sets another): a tree every cycle, as PX4-Avoidance
            and the PyBullet loop do. 0.2 m with 9 cycles is five times faster on stuck hovers, but it moves the
            replication of PX4-Avoidance flights beyond its seed-to-seed spread, so it is a speed setting, off
            unless asked for (docs/compiled-loop.md, section 3).
        noise: noise configuration.
        common_noise: common random numbers: run ``i`` of every test draws the same noise (from the base seed and
            ``i`` alone), so two tests are compared under the same wind and sensor errors and their fitness
            differs only by what the tests change. Default False: the noise also derives from the test (the
            product's semantics: each test meets its own conditions).
        avoidance_model: which planner flies with avoidance (:class:`AvoidanceModel`).
        airframe_params: PX4 parameters of the airframe (a UAV profile's), above PX4's defaults and below the
            reference log's and the test's.
        profile: name of the UAV profile this configuration came from (recorded with results), or None.
        obstacle_collision_scale: horizontal scale of the obstacles' collision shapes; the depth camera and the
            reported distances use the full obstacle (Aerialist's Gazebo boxes: 0.8).
        avoidance_config / sensor_config: the planner's and the depth sensor's configurations (None = the
            model's defaults: :class:`~surrealist_gym.sim.avoidance.px4.local_planner.Px4AvoidanceConfig` and the SITL
            Iris depth camera for ``px4``, :class:`~surrealist_gym.sim.avoidance.reactive.AvoidanceConfig` and the PX4
            Vision's camera for ``simple``).
        physics: what integrates the vehicles and finds their contacts (:class:`Physics`): the compiled kernels
            (default; ``$SURREALIST_PHYSICS`` sets another), which fly the same runs as PyBullet within the
            tolerances of tests/surrealist_gym/sim/vehicle/test_compiled_physics.py, or PyBullet, the reference.
        competition_buffer_m: half width added to the flight's polyline in each run's competition distance [m]
            (``--buffer``): 0.125 is Aerialist's since Oct 2024, whose figures read that much lower; 0 (default) is
            Aerialist's before then, as the labelled PX4 flights were measured.
    """

    vehicle: VehicleModel = VehicleModel.PX4_VISION
    physics_hz: float = 200.0
    control_hz: float = 100.0
    outer_hz: float = 50.0
    planner_hz: float = 10.0
    log_hz: float = 10.0
    avoidance: bool | None = None
    params: Mapping[str, float] = field(default_factory=dict)
    use_reference_params: bool = True
    takeoff_delay_s: float = 4.0
    takeoff_hold_s: float = 0.0
    timeout_s: float | None = None
    stuck_window_s: float | None = None
    stuck_distance_m: float = 0.5
    tree_reuse_m: float = field(default_factory=default_tree_reuse, repr=False)  # stores' identities name it
    tree_reuse_cycles: int = field(default=9, repr=False)
    noise: NoiseConfig = NoiseConfig()
    common_noise: bool = False
    avoidance_model: AvoidanceModel = AvoidanceModel.SIMPLE
    airframe_params: Mapping[str, float] = field(default_factory=dict)
    profile: str | None = None
    obstacle_collision_scale: float = 1.0
    avoidance_config: PlannerConfig | None = None
    sensor_config: DepthSensorConfig | None = None
    competition_buffer_m: float = 0.0
    physics: Physics = field(default_factory=default_physics, repr=False)  # out of the repr; stores' identities name it

    def __post_init__(self):
        if not (isinstance(self.competition_buffer_m, (int, float)) and 0 <= self.competition_buffer_m < math.inf):
            raise ValueError(f"SimConfig.competition_buffer_m must be a finite number >= 0, got "
                             f"{self.competition_buffer_m!r}")
        object.__setattr__(self, "vehicle", VehicleModel(self.vehicle))
        object.__setattr__(self, "avoidance_model", AvoidanceModel(self.avoidance_model))
        object.__setattr__(self, "physics", Physics(self.physics))
        object.__setattr__(self, "params", FrozenDict(dict(self.params)))
        object.__setattr__(self, "airframe_params", FrozenDict(dict(self.airframe_params)))
        if not 0.0 < self.obstacle_collision_scale <= 1.0:
            raise ValueError(f"SimConfig.obstacle_collision_scale must be in (0, 1], got "
                             f"{self.obstacle_collision_scale!r}")
        if not (isinstance(self.tree_reuse_m, (int, float)) and 0 <= self.tree_reuse_m < math.inf):
            raise ValueError(f"SimConfig.tree_reuse_m must be a finite number >= 0, got {self.tree_reuse_m!r}")
        if isinstance(self.tree_reuse_cycles, bool) or not isinstance(self.tree_reuse_cycles, int) \
                or self.tree_reuse_cycles < 0:
            raise ValueError(f"SimConfig.tree_reuse_cycles must be an int >= 0, got {self.tree_reuse_cycles!r}")
        if self.physics_hz < 200:
            raise ValueError(f"SimConfig.physics_hz must be >= 200 Hz, got {self.physics_hz:g}")
        if not 0 < self.control_hz <= self.physics_hz or _not_divisor(self.physics_hz, self.control_hz):
            raise ValueError(f"SimConfig.control_hz must divide physics_hz ({self.physics_hz:g}), got "
                             f"{self.control_hz:g}")
        for name in ("outer_hz", "planner_hz", "log_hz"):
            rate = getattr(self, name)
            if not 0 < rate <= self.control_hz or _not_divisor(self.control_hz, rate):
                raise ValueError(f"SimConfig.{name} must divide control_hz ({self.control_hz:g}), got {rate:g}")
        if abs(self.outer_hz / self.planner_hz - round(self.outer_hz / self.planner_hz)) > 1e-9:
            raise ValueError(f"SimConfig.planner_hz must divide outer_hz, got {self.planner_hz:g}")
        if abs(self.outer_hz / self.log_hz - round(self.outer_hz / self.log_hz)) > 1e-9:
            raise ValueError(f"SimConfig.log_hz must divide outer_hz, got {self.log_hz:g}")

    @property
    def reuses_trees(self) -> bool:
        """Whether runs on this config keep PX4-Avoidance's tree while hovering (``tree_reuse_m``): the compiled loop
        flying that planner, with the reuse on."""
        return (self.physics is Physics.COMPILED and self.avoidance_model is AvoidanceModel.PX4
                and self.tree_reuse_m > 0 and self.tree_reuse_cycles > 0)

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> "SimConfig":
        """A config from keyword values; an unknown key is a ``TypeError`` naming it."""
        return replace_checked(cls(), **dict(values))

    @classmethod
    def coerce(cls, value: "SimConfig | Mapping[str, Any] | None") -> "SimConfig":
        """A config from a config, a mapping of keyword values (JSON-friendly: ``{"common_noise": True}``) or None
        (the defaults)."""
        if value is None:
            return cls()
        return cls.from_dict(value) if isinstance(value, Mapping) else value


def _not_divisor(a: float, b: float) -> bool:
    return abs(a / b - round(a / b)) > 1e-9


def replace_checked(obj, **changes):
    """``dataclasses.replace`` that raises ``TypeError`` (with the valid names) for an unknown field."""
    names = {f.name for f in dataclasses.fields(obj)}
    unknown = sorted(set(changes) - names)
    if unknown:
        raise TypeError(f"{type(obj).__name__}: unknown field {unknown[0]!r} (expected one of {sorted(names)})")
    return dataclasses.replace(obj, **changes)


@lru_cache(maxsize=16)
def _log_params(path: str) -> Mapping[str, float]:
    from pyulog import ULog

    try:
        ulog = ULog(path, message_name_filter_list=[], parse_header_only=False)
    except Exception:  # pyulog raises assorted errors on corrupt files; the reference is then ignored
        return FrozenDict({})
    return FrozenDict({k: float(v) for k, v in ulog.initial_parameters.items()})


def resolve_params(test, config: SimConfig) -> dict[str, float]:
    """The PX4 parameters of a run: defaults < airframe < reference log < test params < config overrides (a test's
    ``uav.*`` settings are not PX4 parameters and are left out)."""
    params: dict[str, float] = dict(PX4_DEFAULTS)
    params.update(config.airframe_params)
    ref = getattr(test, "reference_log", None)
    if config.use_reference_params and ref and str(ref).lower().endswith(".ulg"):
        params.update(_log_params(str(ref)))
    params.update((k, v) for k, v in test.params.items() if not k.startswith(UAV_SETTING_PREFIX))
    params.update(config.params)
    return params


def auto_timeout(mission) -> float:
    """Default time limit of a mission [s]: 90 s plus 4 s per metre of the path through its items."""
    length, prev = 0.0, (0.0, 0.0, 0.0)
    for item in mission.items if mission is not None else ():
        if item.has_position:
            length += math.dist(prev, (item.x, item.y, item.z))
            prev = (item.x, item.y, item.z)
    return 90.0 + 4.0 * length
