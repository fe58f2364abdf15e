"""The planners by name: the one registry that fastep-sim, fastep-bench, fastep-launch and the planner node read.

Each algorithm is a Navigator subclass (planning/navigator.py) that differs in how it picks the target of a
tick; `make_navigator` builds one for a scenario robot with the robot's kinematic model and controller.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from fastep_core.errors import ParameterError
from fastep_core.kinematics import PointMass, PointMassController, TractorTrailer, TractorTrailerController
from fastep_core.kinematics.model import Controller, RobotModel
from fastep_core.planning.aco_kinematic import ACOKinematic
from fastep_core.planning.fastep_route import FAStepRoute
from fastep_core.planning.navigator import FAStepKinematic, Navigator
from fastep_core.planning.optimal_kinematic import OptimalKinematic
from fastep_core.planning.params import PlannerParams
from fastep_core.world import World

__all__ = ['ALGORITHMS', 'ALGORITHM_NAMES', 'NAVIGATORS', 'algorithm_name', 'make_navigator', 'make_robot']

NAVIGATORS: dict[str, type[Navigator]] = {
    'fastep': FAStepKinematic,   # the paper's algorithm
    'aco': ACOKinematic,         # the paper's baseline
    'optimal': OptimalKinematic,  # the exact shortest path, driven by the same controller (a reference)
    'fastep_route': FAStepRoute,  # FAStep-Kinematic toward the farthest vertex in sight of the exact route
}
ALGORITHMS: tuple[str, ...] = tuple(NAVIGATORS)
ALGORITHM_NAMES: dict[str, str] = {'fastep': 'FAStep-Kinematic', 'aco': 'ACO-Kinematic', 'optimal': 'Optimal-Kinematic',
                                   'fastep_route': 'FAStep-Route'}
"""What tables, reports and figure titles call each algorithm (the paper's names)."""


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
    """The kinematic model and controller for a scenario robot ('point_mass' or 'tractor_trailer')."""
    if spec.model == 'point_mass':
        return PointMass(), PointMassController(params.alpha1, params.alpha2, params.max_speed)
    if spec.model == 'tractor_trailer':
        model = TractorTrailer(spec.length, spec.trailer_length, spec.hitch_offset)
        return model, TractorTrailerController(model, params.speed_gain, params.max_speed)
    raise ParameterError(f'unknown robot model {spec.model!r}')


def make_navigator(algorithm: str, spec: RobotLike, radius: float, world: World, params: PlannerParams,
                   rng: np.random.Generator | int | None = None) -> Navigator:
    """A navigator of the named algorithm (one of ALGORITHMS) for a scenario robot."""
    if algorithm not in NAVIGATORS:
        raise ParameterError(f'unknown algorithm {algorithm!r}; choose one of {", ".join(ALGORITHMS)}')
    model, controller = make_robot(spec, params)
    return NAVIGATORS[algorithm](model, controller, radius, world, params, rng)
