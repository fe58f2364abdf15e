"""FAStep-Kinematic, the ACO-Kinematic baseline, and the step planning they share."""

from fastep_core.planning.navigator import (ACOKinematic, FAStepKinematic, Mode, Navigator, OtherRobot,
                                           make_navigator, make_robot)
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.step import StepPlan, StepProblem, plan_step

__all__ = ['ACOKinematic', 'FAStepKinematic', 'Mode', 'Navigator', 'OtherRobot', 'PlannerParams', 'StepPlan',
           'StepProblem', 'make_navigator', 'make_robot', 'plan_step']
