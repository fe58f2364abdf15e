"""Planning: the navigators (FAStep-Kinematic, ACO-Kinematic, Optimal-Kinematic), the step they plan, and
the safety nets around them. `algorithms` is the registry by name; `navigator` the shared loop."""

from fastep_core.planning.aco_kinematic import ACOKinematic
from fastep_core.planning.algorithms import ALGORITHMS, make_navigator, make_robot
from fastep_core.planning.fastep_kinematic import FAStepKinematic, FAStepPaper
from fastep_core.planning.navigator import Mode, Navigator
from fastep_core.planning.optimal_kinematic import OptimalKinematic
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.step import StepPlan, StepProblem, plan_step

__all__ = ['ALGORITHMS', 'ACOKinematic', 'FAStepKinematic', 'FAStepPaper', 'Mode', 'Navigator', 'OptimalKinematic',
           'OtherRobot', 'PlannerParams', 'StepPlan', 'StepProblem', 'make_navigator', 'make_robot', 'plan_step']
