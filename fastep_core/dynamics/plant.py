"""Plants: what moves a simulated robot when it is commanded, kinematic or with physics, behind one interface.

A `Plant` holds a robot's TRUE state (in its kinematic model's state form) and what its odometry measures. The
simulator (fastep_core/simulator.py) and the plant node (fastep_ros/plant.py) step one per robot:

- `KinematicPlant`: the kinematic model's `integrate`, the command done exactly as told; its odometry is the
  truth and its measured velocity the command it last applied (what the plant node has always published).
- `PhysicsPlant`: a differential-drive base with mass in MuJoCo (fastep_core/dynamics/mjcf.py), behind its own
  diff_drive_controller (controller.py), with wheel-encoder odometry (odometry.py): the base lags, brakes no
  harder than its motors and grip allow, slips, and its odometry drifts. mujoco is imported here, when the first
  physics plant is made, never by fastep_core otherwise (its import takes ~0.3 s).

Deterministic: the same dynamics, start, commands and seed give the same trajectory, bit for bit (MuJoCo runs
single-threaded; encoder noise comes from the Generator the plant is given).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from fastep_core.dynamics.controller import BaseController
from fastep_core.dynamics.mjcf import LEFT_JOINT, RIGHT_JOINT, TIMESTEP, base_mjcf
from fastep_core.dynamics.odometry import WheelOdometry
from fastep_core.dynamics.params import BaseDynamics
from fastep_core.errors import ParameterError
from fastep_core.kinematics.model import RobotModel

__all__ = ['SETTLE_TIME', 'KinematicPlant', 'PhysicsPlant', 'Plant', 'make_plant', 'odometry_generator']

FloatArray = NDArray[np.float64]
SETTLE_TIME = 0.2   # s: a new physics plant lets the base settle on its wheels this long before time 0
_ODOMETRY_STREAM = 0x6F646F   # 'odo': the spawn key of the encoder-noise streams (no swarm or map draws from it)


class Plant(Protocol):
    """What moves one robot: its true state, stepped by commands, and what its odometry measures."""

    state: FloatArray
    """The TRUE state, in the kinematic model's state form ((x, y, theta) for diff_drive)."""

    def step(self, command: FloatArray | None, dt: float, sent: float | None = None) -> None:
        """Hold `command` (the model's command form) for dt seconds; None: no new command came (the last holds,
        until a physics base's controller times it out). `sent`: when it was sent, on the plant's clock (None: now),
        for a physics controller's command timeout."""

    def measured_velocity(self) -> FloatArray:
        """The odometry's twist, in the model's command form ((v, omega) for diff_drive)."""

    def odometry(self) -> tuple[FloatArray, FloatArray]:
        """The odometry's pose (odom frame; the model's state form) and twist (command form)."""

    def velocity(self) -> FloatArray:
        """The true map-frame velocity (vx, vy) of the reference point: what the other robots see."""


class KinematicPlant:
    """A kinematic model integrated exactly as commanded (what every plant did before physics)."""

    def __init__(self, model: RobotModel, state: FloatArray) -> None:
        self.model = model
        self.state = np.asarray(state, dtype=float)
        self.applied = np.zeros(2)   # the command of the last step

    def step(self, command: FloatArray | None, dt: float, sent: float | None = None) -> None:
        command = self.applied if command is None else command
        self.state = self.model.integrate(self.state, command, dt)
        self.applied = command

    def measured_velocity(self) -> FloatArray:
        return self.applied

    def odometry(self) -> tuple[FloatArray, FloatArray]:
        return self.state, self.applied

    def velocity(self) -> FloatArray:
        return self.model.velocity(self.state, self.applied)


def _yaw(quaternion: FloatArray) -> float:
    w, x, y, z = (float(q) for q in quaternion)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class PhysicsPlant:
    """A differential-drive base in MuJoCo behind its controller, with wheel-encoder odometry (module docstring).

    state (x, y, theta): the true pose of the axle's midpoint (map frame). `time` is the plant's clock (s): 0 (or
    `start_time`) at the start, the physics steps taken since times 0.002 s after.
    """

    def __init__(self, dynamics: BaseDynamics, state: FloatArray, rng: np.random.Generator | None = None,
                 start_time: float = 0.0) -> None:
        import mujoco  # type: ignore[import-untyped]  # here: only a physics plant needs it (module docstring)

        self._mujoco: Any = mujoco
        self.dynamics = dynamics
        self.model: Any = mujoco.MjModel.from_xml_string(base_mjcf(dynamics))
        self.data: Any = mujoco.MjData(self.model)
        self.controller = BaseController(dynamics)
        self.start_time = start_time
        self._wheels = [int(self.model.jnt_qposadr[mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_JOINT, name)])
                        for name in (LEFT_JOINT, RIGHT_JOINT)]
        start = np.asarray(state, dtype=float)
        if start.shape != (3,) or not np.all(np.isfinite(start)):
            raise ParameterError(f'a physics plant starts from a finite (x, y, theta), got {start.tolist()}')
        # Let it settle on its wheels and caster, then put it exactly where it starts, at rest.
        mujoco.mj_step(self.model, self.data, nstep=int(round(SETTLE_TIME / TIMESTEP)))
        self._place(start)
        self._steps = 0           # physics steps since the start
        self._clock = 0.0         # the time the steps were asked for (sum of dt)
        self._until_control = 0   # physics steps until the controller's next update
        self.state = self._true_state()
        self.odom = WheelOdometry(self.state, self._angles(), dynamics.wheel_radius, dynamics.wheel_separation,
                                  dynamics.encoder_noise, rng)

    # ------------------------------------------------------------------------------------- physics state
    def _place(self, pose: FloatArray) -> None:
        qpos, qvel = self.data.qpos, self.data.qvel
        qpos[0], qpos[1] = pose[0], pose[1]
        half = 0.5 * float(pose[2])
        qpos[3:7] = (math.cos(half), 0.0, 0.0, math.sin(half))
        qvel[:] = 0.0
        self.data.ctrl[:] = 0.0
        self.data.qacc_warmstart[:] = 0.0
        self._mujoco.mj_forward(self.model, self.data)

    def _true_state(self) -> FloatArray:
        qpos = self.data.qpos
        return np.array([float(qpos[0]), float(qpos[1]), _yaw(qpos[3:7])])

    def _angles(self) -> tuple[float, float]:
        qpos = self.data.qpos
        return float(qpos[self._wheels[0]]), float(qpos[self._wheels[1]])

    @property
    def time(self) -> float:
        return self.start_time + self._steps * TIMESTEP

    def set_time(self, t: float) -> None:
        """Put the plant's clock at t (a node's integrated time, where commands' sent times are counted)."""
        self.start_time = t - self._steps * TIMESTEP

    # ------------------------------------------------------------------------------------- Plant
    def step(self, command: FloatArray | None, dt: float, sent: float | None = None) -> None:
        if command is not None:
            self.controller.take(command, self.time if sent is None else sent)
        self._clock += dt
        todo = int(round(self._clock / TIMESTEP)) - self._steps
        substeps = self.dynamics.control_substeps
        before = self.time
        while todo > 0:
            if self._until_control == 0:
                self.data.ctrl[:] = self.controller.update(self.time, substeps * TIMESTEP)
                self._until_control = substeps
            n = min(todo, self._until_control)
            self._mujoco.mj_step(self.model, self.data, nstep=n)
            todo -= n
            self._until_control -= n
            self._steps += n
        self.state = self._true_state()
        if self.time > before:   # no physics step, no new encoder reading (a twist of 0 / 0 s is not a stop)
            self.odom.update(self._angles(), self.time - before)

    def measured_velocity(self) -> FloatArray:
        return self.odom.twist.copy()

    def odometry(self) -> tuple[FloatArray, FloatArray]:
        return self.odom.pose.copy(), self.odom.twist.copy()

    def velocity(self) -> FloatArray:
        qvel = self.data.qvel   # a free joint's linear velocity is in the world frame, at the body's origin
        return np.array([float(qvel[0]), float(qvel[1])])

    def body_twist(self) -> FloatArray:
        """The true twist (v, omega) in the body frame: forward speed and yaw rate."""
        theta = float(self.state[2])
        qvel = self.data.qvel
        return np.array([float(qvel[0]) * math.cos(theta) + float(qvel[1]) * math.sin(theta), float(qvel[5])])


def odometry_generator(seed: int, index: int) -> np.random.Generator:
    """The encoder-noise stream of robot `index` in a run of `seed` (a stream no swarm, map or laser uses)."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(_ODOMETRY_STREAM, index)))


def make_plant(model_name: str, model: RobotModel, state: FloatArray, dynamics: BaseDynamics | None = None,
               rng: np.random.Generator | None = None, start_time: float = 0.0) -> Plant:
    """A KinematicPlant without dynamics; a PhysicsPlant with (only for diff_drive: ParameterError otherwise)."""
    if dynamics is None:
        return KinematicPlant(model, state)
    if model_name != 'diff_drive':
        raise ParameterError(f'dynamics: a physics plant is only for model diff_drive, got {model_name}')
    return PhysicsPlant(dynamics, state, rng, start_time)
