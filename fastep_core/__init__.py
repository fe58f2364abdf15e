"""fastep_core: FAStep-Kinematic robot navigation without ROS (numpy/scipy only).

The pieces, one module each: `optimize` (Stepping Ahead Firefly, standard firefly, ACO_R), `geometry`
(circle and segment obstacles), `kinematics` (point mass, tractor-trailer, differential drive and controllers),
`planning` (the step fitness and the FAStep-Kinematic / ACO-Kinematic navigators), `scenario` (format v1),
`simulator` (all robots of a scenario in one loop) and `cli` (fastep-sim).
"""

from fastep_core.errors import FastepError, GoalError, ParameterError, ScenarioError
from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.optimize import OptimizeResult, aco_r, fastep, firefly
from fastep_core.planning import (
                                  ACOKinematic,
                                  FAStepKinematic,
                                  Mode,
                                  Navigator,
                                  OtherRobot,
                                  PlannerParams,
                                  make_navigator,
)
from fastep_core.scenario import RobotSpec, Scenario, builtin_names, load_scenario, parse_scenario
from fastep_core.simulator import RobotRun, Run, simulate
from fastep_core.world import World

__all__ = [
    'ACOKinematic', 'Circle', 'FAStepKinematic', 'FastepError', 'GoalError', 'Mode', 'Navigator', 'Obstacles',
    'OptimizeResult', 'OtherRobot', 'ParameterError', 'PlannerParams', 'RobotRun', 'RobotSpec', 'Run',
    'Scenario', 'ScenarioError', 'Segment', 'World', 'aco_r', 'builtin_names', 'fastep', 'firefly',
    'load_scenario', 'make_navigator', 'parse_scenario', 'simulate',
]
