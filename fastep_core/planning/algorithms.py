"""The planners by name: the one registry that fastep-sim, fastep-bench, fastep-launch and the planner node read.

Each algorithm is a Navigator subclass (planning/navigator.py) that differs in how it picks the target of a
tick; `make_navigator` builds one for a scenario robot with the robot's kinematic model and controller.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from fastep_core.errors import ParameterError
from fastep_core.footprint import Footprint
from fastep_core.kinematics import PointMass, PointMassController, TractorTrailer, TractorTrailerController
from fastep_core.kinematics.diff_drive import DiffDrive, DiffDriveController
from fastep_core.kinematics.model import Controller, RobotModel
from fastep_core.planning.navigator import Navigator
from fastep_core.planning.navigators.aco_kinematic import ACOKinematic
from fastep_core.planning.navigators.dwa import DynamicWindow
from fastep_core.planning.navigators.fastep_kinematic import FAStepKinematic, FAStepPaper
from fastep_core.planning.navigators.fastep_route import FAStepRoute
from fastep_core.planning.navigators.optimal_kinematic import OptimalKinematic
from fastep_core.planning.outline import body_radius, planning_radius
from fastep_core.planning.params import PlannerParams
from fastep_core.world import World

__all__ = ['ALGORITHMS', 'ALGORITHM_NAMES', 'DEFAULT_ALGORITHM', 'NAVIGATORS', 'REFUSED_MODELS', 'ROBOT_MODELS',
           'algorithm_name', 'check_drives', 'drives', 'make_navigator', 'make_robot']

NAVIGATORS: dict[str, type[Navigator]] = {
    'fastep': FAStepKinematic,   # the paper's algorithm, with the activation policy of docs/architecture.md
    'fastep_paper': FAStepPaper,  # the paper's algorithm with its literal activation policy
    'aco': ACOKinematic,         # the paper's baseline
    'optimal': OptimalKinematic,  # the exact shortest path, driven by the same controller (a reference)
    'dwa': DynamicWindow,        # the Dynamic Window Approach (Fox et al. 1997): the local planner users know
    'fastep_route': FAStepRoute,  # FAStep-Kinematic toward the farthest vertex in sight of the exact route
}
ALGORITHMS: tuple[str, ...] = tuple(NAVIGATORS)
ALGORITHM_NAMES: dict[str, str] = {'fastep': 'FAStep-Kinematic', 'fastep_paper': 'FAStep-Kinematic (paper policy)',
                                   'aco': 'ACO-Kinematic', 'optimal': 'Optimal-Kinematic', 'dwa': 'DWA',
                                   'fastep_route': 'FAStep-Route'}
"""What tables, reports and figure titles call each algorithm (the paper's names)."""

DEFAULT_ALGORITHM = 'fastep_route'
"""What the planner node and fastep-launch run unless told otherwise: on the families benchmark (docs/clutter.md:
150 unseen worlds) FAStep-Route arrived in every run without collision, with the shortest paths (path / optimum
1.003 at most on average per family) at the least compute (0.11-0.29 of ACO-Kinematic's). fastep-sim and
fastep-bench keep 'fastep', the paper's algorithm, as their default: they reproduce the paper."""


def algorithm_name(algorithm: str) -> str:
    """The paper's name of an algorithm ('aco' -> 'ACO-Kinematic'); an unknown one keeps its own."""
    return ALGORITHM_NAMES.get(algorithm, algorithm)


class RobotLike(Protocol):
    """What make_robot reads of a robot (a scenario's RobotSpec, the planner node's parameters)."""

    @property
    def model(self) -> str: ...

    @property
    def length(self) -> float: ...

    @property
    def trailer_length(self) -> float: ...

    @property
    def hitch_offset(self) -> float: ...


def make_robot(spec: RobotLike, params: PlannerParams) -> tuple[RobotModel, Controller]:
    """The kinematic model and controller for a scenario robot ('point_mass', 'tractor_trailer', 'diff_drive').

    A diff_drive's base limits come from the planner parameters' limits (max_speed, max_turn_rate,
    max_acceleration, max_turn_acceleration: `params.limits`), its gains from speed_gain and turn_gain
    (kinematics/diff_drive.py).
    """
    limits = params.limits
    if spec.model == 'point_mass':
        return PointMass(), PointMassController(params.alpha1, params.alpha2, limits.max_speed,
                                                params.min_approach_speed)
    if spec.model == 'tractor_trailer':
        model = TractorTrailer(spec.length, spec.trailer_length, spec.hitch_offset)
        return model, TractorTrailerController(model, params.speed_gain, limits.max_speed,
                                               params.min_approach_speed)
    if spec.model == 'diff_drive':
        return (DiffDrive(limits.max_speed, limits.max_turn_rate),
                DiffDriveController(params.speed_gain, params.turn_gain, limits.max_speed, limits.max_turn_rate,
                                    limits.max_acceleration, limits.max_turn_acceleration,
                                    min_speed=params.min_approach_speed))
    raise ParameterError(f'unknown robot model {spec.model!r}')


ROBOT_MODELS: tuple[str, ...] = ('point_mass', 'tractor_trailer', 'diff_drive')
"""The models make_robot builds (scenario.MODELS names the same)."""
REFUSED_MODELS: dict[str, frozenset[str]] = {'dwa': frozenset({'tractor_trailer'})}
"""Robot models an algorithm cannot drive: dwa samples velocities of a point mass or a unicycle
(planning/navigators/dwa.py), not the steering of a tractor-trailer."""


def drives(algorithm: str, model: str) -> bool:
    """Can the algorithm drive a robot of this model ('point_mass', 'tractor_trailer', 'diff_drive')?"""
    return model not in REFUSED_MODELS.get(algorithm, frozenset())


def check_drives(algorithm: str, model: str, robot: str = '') -> None:
    """Raise ParameterError (one line) when the algorithm cannot drive a robot of this model."""
    if not drives(algorithm, model):
        which = f'robot {robot} is' if robot else 'the robot is'
        able = ', '.join(a for a in ALGORITHMS if drives(a, model))
        models = ' and '.join(m for m in ROBOT_MODELS if drives(algorithm, m))
        raise ParameterError(f'{algorithm} drives {models} robots only; {which} a {model} (choose {able})')


def make_navigator(algorithm: str, spec: RobotLike, radius: float, world: World, params: PlannerParams,
                   rng: np.random.Generator | int | None = None, footprint: Footprint | None = None) -> Navigator:
    """A navigator of the named algorithm (one of ALGORITHMS) for a scenario robot.

    footprint: the robot's outline (default: the spec's `footprint`, if it has one; diff_drive only). With one,
    `radius` (at least its circumscribed radius) is what other robots are kept from, and the navigator plans with
    outline.planning_radius and guards with the polygon (planning/outline.py); `navigator.footprint` is it.
    """
    if algorithm not in NAVIGATORS:
        raise ParameterError(f'unknown algorithm {algorithm!r}; choose one of {", ".join(ALGORITHMS)}')
    check_drives(algorithm, spec.model, getattr(spec, 'name', ''))
    if footprint is None:
        footprint = getattr(spec, 'footprint', None)
    if footprint is not None and spec.model != 'diff_drive':
        raise ParameterError(f'a footprint is for diff_drive robots only; the robot is a {spec.model}')
    model, controller = make_robot(spec, params)
    planned = radius if footprint is None else planning_radius(footprint, radius)
    navigator = NAVIGATORS[algorithm](model, controller, planned, world, params, rng)
    if footprint is not None:
        navigator.take_footprint(footprint, body_radius(footprint, radius))
    navigator.name = str(getattr(spec, 'name', ''))
    return navigator
