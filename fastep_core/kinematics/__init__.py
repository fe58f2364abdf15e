"""Robot models (what a plant integrates) and their kinematic controllers (what a planner commands)."""

from fastep_core.kinematics.diff_drive import DiffDrive, DiffDriveController
from fastep_core.kinematics.model import Controller, RobotModel
from fastep_core.kinematics.point_mass import PointMass, PointMassController, lyapunov
from fastep_core.kinematics.tractor_trailer import TractorTrailer, TractorTrailerController, hitch_angle, wrap_angle

__all__ = ['Controller', 'DiffDrive', 'DiffDriveController', 'PointMass', 'PointMassController', 'RobotModel',
           'TractorTrailer', 'TractorTrailerController', 'hitch_angle', 'lyapunov', 'wrap_angle']
