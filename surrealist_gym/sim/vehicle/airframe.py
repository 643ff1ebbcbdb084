"""Vehicle presets: rigid-body quadrotors with the public figures they come from.

Rotor thrust follows a quadratic rotor model ``T = k_f * omega^2`` with the actuator command ``u`` in [0, 1]
mapped to rotor speed, ``omega = u * omega_max`` (as PX4 SITL does for Gazebo), so ``T = T_max * u^2``;
``thrust_curve`` blends that with a linear map, the way PX4's THR_MDL_FAC describes an ESC/motor
(``T/T_max = f u^2 + (1 - f) u``). Yaw reaction torque per rotor is ``k_m * T``. Frame: body FRD, rotors of a
quad X in PX4 order (1 front-right CCW, 2 back-left CCW, 3 front-left CW, 4 back-right CW).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..config import VehicleModel

GRAVITY = 9.80665  # [m/s^2] (PX4 CONSTANTS_ONE_G)


@dataclass(frozen=True, slots=True)
class VehicleParams:
    """Physical parameters of a quadrotor (SI units).

    Attributes:
        name: preset name.
        mass: [kg]. ixx, iyy, izz: principal moments of inertia [kg m^2].
        arm_length: centre to rotor axis [m] (rotors at +-45 deg in a quad X).
        motor_constant: k_f, thrust per squared rotor speed [N / (rad/s)^2].
        moment_constant: k_m, yaw reaction torque per thrust [m].
        max_rot_velocity: [rad/s].
        thrust_curve: physical thrust-curve factor f in ``T/T_max = f u^2 + (1 - f) u``.
        motor_tau_up / motor_tau_down: first-order motor time constants [s].
        drag_xy / drag_z: linear drag (rotor drag + body) [N / (m/s)]; drag_quad: quadratic body drag [N / (m/s)^2].
        size: collision box (length, width, height) [m].
    """

    name: str
    mass: float
    ixx: float
    iyy: float
    izz: float
    arm_length: float
    motor_constant: float
    moment_constant: float
    max_rot_velocity: float
    thrust_curve: float
    motor_tau_up: float
    motor_tau_down: float
    drag_xy: float
    drag_z: float
    drag_quad: float
    size: tuple[float, float, float]

    @property
    def max_thrust(self) -> float:
        """Maximum thrust of one rotor [N]."""
        return self.motor_constant * self.max_rot_velocity ** 2

    @property
    def hover_command(self) -> float:
        """Actuator command ``u`` that holds the vehicle in hover (the physical MPC_THR_HOVER)."""
        rel = self.mass * GRAVITY / (4.0 * self.max_thrust)
        f = self.thrust_curve
        if f <= 1e-9:
            return rel
        return (-(1 - f) + math.sqrt((1 - f) ** 2 + 4 * f * rel)) / (2 * f)


# 3DR Iris as modelled in PX4 SITL Gazebo (PX4/PX4-SITL_gazebo, models/iris/iris.sdf and rotors_description
# iris.xacro): mass 1.5 kg; inertia ixx = iyy = 0.029125, izz = 0.055225 kg m^2; rotors at (+-0.13, +-0.22) m
# (arm 0.255 m); motorConstant 8.54858e-06 N/(rad/s)^2; momentConstant 0.016 m; maxRotVelocity 1100 rad/s;
# timeConstantUp 0.0125 s, timeConstantDown 0.025 s; rotorDragCoefficient 8.06428e-05 N s/(m rad) per rotor,
# i.e. ~0.053 N/(m/s) per rotor at the 656 rad/s hover speed; body collision box 0.47 x 0.47 x 0.11 m.
# Gazebo maps the actuator command linearly to rotor speed, hence thrust_curve = 1.
IRIS = VehicleParams(
    name="iris", mass=1.5, ixx=0.029125, iyy=0.029125, izz=0.055225, arm_length=math.hypot(0.13, 0.22),
    motor_constant=8.54858e-06, moment_constant=0.016, max_rot_velocity=1100.0, thrust_curve=1.0,
    motor_tau_up=0.0125, motor_tau_down=0.025, drag_xy=0.21, drag_z=0.05, drag_quad=0.02,
    size=(0.47, 0.47, 0.11),
)

# Holybro PX4 Vision DevKit v1 (the real case0 flight). Public figures: PX4 user guide "PX4 Vision Autonomy
# Development Kit" and Holybro's product page: quad X, ~286 mm motor-to-motor diagonal (arm ~0.143 m), ~1.2 kg
# without battery (about 1.4 kg ready to fly with the 4S battery), 10-inch propellers. PX4's airframe
# 4016_holybro_px4vision sets THR_MDL_FAC 0.3 and COM_OBS_AVOID 1; case0.ulg has MPC_THR_HOVER 0.30.
# Estimated here: the rotor constant is chosen so that hover needs u = 0.30 with f = 0.3 (the log's hover thrust),
# i.e. T_max = 1.4 * g / 4 / 0.237 = 14.5 N per rotor (a 2216-class motor with a 10" prop on 4S gives ~13-15 N);
# the inertia scales the Iris' by mass and arm length squared; drag like the Iris' (same rotor size class);
# motor time constants of a 10" prop (~0.02-0.03 s); collision box = frame plus propeller discs.
_VISION_MASS = 1.4
_VISION_TMAX = _VISION_MASS * GRAVITY / 4.0 / (0.3 * 0.3 ** 2 + 0.7 * 0.3)
PX4_VISION = VehicleParams(
    name="px4_vision", mass=_VISION_MASS, ixx=0.0125, iyy=0.0125, izz=0.0230, arm_length=0.143,
    motor_constant=_VISION_TMAX / 1000.0 ** 2, moment_constant=0.016, max_rot_velocity=1000.0, thrust_curve=0.3,
    motor_tau_up=0.02, motor_tau_down=0.03, drag_xy=0.25, drag_z=0.08, drag_quad=0.03,
    size=(0.45, 0.45, 0.16),
)

VEHICLES: dict[VehicleModel, VehicleParams] = {VehicleModel.PX4_VISION: PX4_VISION, VehicleModel.IRIS: IRIS}


def preset(model: VehicleModel | str) -> VehicleParams:
    """The parameters of a vehicle preset (``"px4_vision"`` or ``"iris"``)."""
    return VEHICLES[VehicleModel(model)]
