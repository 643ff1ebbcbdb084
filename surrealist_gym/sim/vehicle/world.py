"""The PyBullet world of a test case: ground, obstacles as static collision shapes, and the vehicles.

The PyBullet frame is the local NED frame (x north, y east, z down; gravity +z), so PyBullet's base orientation
is PX4's body(FRD)-to-NED attitude. Obstacles follow PRODUCT.md: ``x, y`` footprint centre, ``z`` base height,
``r`` yaw in degrees from north toward east (a positive rotation about the down axis), ``l`` along the obstacle's
x axis, ``w`` along y, ``h`` up; a cylinder has diameter ``l``. Vehicles collide with the ground and the obstacles,
never with each other (collision groups), so the runs of a batch share one world.
"""
from __future__ import annotations

import math
from typing import Sequence

from ...testcase import Obstacle, Shape
from .airframe import GRAVITY, VehicleParams
from .pybullet_quiet import pb

_STATIC_GROUP, _VEHICLE_GROUP = 1, 2
# Idle DIRECT clients, reset and reused: connecting costs ~15 ms, resetSimulation ~2 ms.
_POOL: list[int] = []


def _client() -> int:
    while _POOL:
        cid = _POOL.pop()
        try:
            pb.resetSimulation(physicsClientId=cid)
            return cid
        except pb.error:  # disconnected behind our back
            continue
    return pb.connect(pb.DIRECT)


class World:
    """A PyBullet DIRECT world with ``n_vehicles`` copies of one vehicle resting at the origin.

    Args:
        obstacles: the test's obstacles. vehicle: the vehicle parameters. n_vehicles: number of vehicles.
        physics_hz: physics integration rate [Hz]. control_hz: rate of ``stepSimulation`` calls [Hz]
            (physics_hz / control_hz sub-steps each; default physics_hz).
    """

    def __init__(self, obstacles: Sequence[Obstacle], vehicle: VehicleParams, n_vehicles: int, physics_hz: float,
                 control_hz: float | None = None, collision_scale: float = 1.0):
        self.cid = cid = _client()
        try:
            pb.setGravity(0.0, 0.0, GRAVITY, physicsClientId=cid)
            control_hz = control_hz or physics_hz
            pb.setPhysicsEngineParameter(fixedTimeStep=1.0 / control_hz,
                                         numSubSteps=int(round(physics_hz / control_hz)),
                                         numSolverIterations=10, deterministicOverlappingPairs=1,
                                         physicsClientId=cid)
            plane = pb.createCollisionShape(pb.GEOM_PLANE, planeNormal=[0, 0, -1], physicsClientId=cid)
            self.ground = pb.createMultiBody(0, plane, physicsClientId=cid)
            self.obstacles: list[int] = []
            for o in obstacles:
                self.obstacles.append(self._add_obstacle(o, collision_scale))
            for body in [self.ground, *self.obstacles]:
                pb.setCollisionFilterGroupMask(body, -1, _STATIC_GROUP, _STATIC_GROUP | _VEHICLE_GROUP,
                                               physicsClientId=cid)
            hx, hy, hz = (s / 2 for s in vehicle.size)
            self.rest_z = -hz  # NED z of the vehicle's centre when it rests on the ground
            shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[hx, hy, hz], physicsClientId=cid)
            self.vehicles: list[int] = []
            for _ in range(n_vehicles):
                body = pb.createMultiBody(vehicle.mass, shape, basePosition=[0.0, 0.0, self.rest_z],
                                          physicsClientId=cid)
                pb.changeDynamics(body, -1, localInertiaDiagonal=[vehicle.ixx, vehicle.iyy, vehicle.izz],
                                  linearDamping=0.0, angularDamping=0.0, lateralFriction=0.8, restitution=0.0,
                                  physicsClientId=cid)
                pb.setCollisionFilterGroupMask(body, -1, _VEHICLE_GROUP, _STATIC_GROUP, physicsClientId=cid)
                self.vehicles.append(body)
            self.obstacle_index = {body: i for i, body in enumerate(self.obstacles)}
        except Exception:
            self.close()
            raise

    def _add_obstacle(self, o: Obstacle, scale: float) -> int:
        cid = self.cid
        if o.shape == Shape.CYLINDER:
            shape = pb.createCollisionShape(pb.GEOM_CYLINDER, radius=scale * o.l / 2, height=o.h, physicsClientId=cid)
        else:
            shape = pb.createCollisionShape(pb.GEOM_BOX, halfExtents=[scale * o.l / 2, scale * o.w / 2, o.h / 2],
                                            physicsClientId=cid)
        a = math.radians(o.r) / 2
        return pb.createMultiBody(0, shape, basePosition=[o.x, o.y, -(o.z + o.h / 2)],
                                  baseOrientation=[0.0, 0.0, math.sin(a), math.cos(a)], physicsClientId=cid)

    def set_yaw(self, body: int, yaw: float) -> None:
        """Turn a resting vehicle to a heading [rad] (before the run starts)."""
        pos, _ = pb.getBasePositionAndOrientation(body, physicsClientId=self.cid)
        pb.resetBasePositionAndOrientation(body, pos, [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)],
                                           physicsClientId=self.cid)

    def remove(self, body: int) -> None:
        """Take a finished vehicle out of the simulation."""
        pb.removeBody(body, physicsClientId=self.cid)

    def close(self) -> None:
        """Release the PyBullet client for reuse by the next world (idempotent)."""
        if self.cid is not None:
            if len(_POOL) < 4:
                _POOL.append(self.cid)
            else:
                try:
                    pb.disconnect(self.cid)
                except pb.error:
                    pass
            self.cid = None

    def __enter__(self) -> "World":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
