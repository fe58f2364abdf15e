"""Robots with mass: a physics plant (MuJoCo) of a differential-drive base behind its own controller.

    from fastep_core.dynamics import PhysicsPlant, preset
    plant = PhysicsPlant(preset('heavy'), np.array([0.0, 0.0, 0.0]))
    plant.step(np.array([1.0, 0.0]), 0.05)      # hold (v, omega) for 0.05 s: 25 physics steps
    plant.state, plant.measured_velocity()       # the true pose; the wheel odometry's twist

`params.py` the base's parameters and presets, `mjcf.py` its MuJoCo model, `controller.py` its
diff_drive_controller, `odometry.py` its wheel-encoder odometry, `plant.py` the Plant interface with the
kinematic and physics plants. Nothing imports mujoco until a PhysicsPlant is made.
"""

from fastep_core.dynamics.controller import BaseController
from fastep_core.dynamics.mjcf import TIMESTEP, base_mjcf
from fastep_core.dynamics.odometry import WheelOdometry
from fastep_core.dynamics.params import PRESETS, BaseDynamics, dynamics_data, dynamics_from_text, parse_dynamics, preset
from fastep_core.dynamics.plant import KinematicPlant, PhysicsPlant, Plant, make_plant, odometry_generator

__all__ = ['PRESETS', 'TIMESTEP', 'BaseController', 'BaseDynamics', 'KinematicPlant', 'PhysicsPlant', 'Plant',
           'WheelOdometry', 'base_mjcf', 'dynamics_data', 'dynamics_from_text', 'make_plant', 'odometry_generator',
           'parse_dynamics', 'preset']
