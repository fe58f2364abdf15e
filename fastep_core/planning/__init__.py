"""Planning: the navigators, the step their swarm plans, and the safety nets around them.

What lives where (each sub-package's `__init__` says more):

- `navigator`: the control loop every algorithm shares; `behaviours`: its tick's behaviours in order of priority;
  `control`: the bounded control tick on the newest plan; `algorithms`: the navigators by name (`make_navigator`).
- `navigators/`: FAStep-Kinematic (the paper's and ours), FAStep-Route, ACO-Kinematic, Optimal-Kinematic, DWA.
- `swarm/`: when the swarm runs (detection, step planning) and the step it plans (eq. 3-11).
- `shortest_path/`: the exact shortest path (the reference optimum, routes, escapes) and its search.
- `recovery/`: progress and trap detection, the escape along the exact path, backing up, tractor manoeuvres.
- `safety/`: the guard, yielding to movers, passages, the base's measured braking, lateness, the smoother.
- `params`, `limits`: the planner's parameters and its speed and acceleration limits; `others`: other robots as a
  navigator sees them; `outline`: the robot's shape as the planners use it; `mode`: what a navigator is doing.
"""

from fastep_core.planning.algorithms import ALGORITHMS, make_navigator, make_robot
from fastep_core.planning.navigator import Mode, Navigator
from fastep_core.planning.navigators.aco_kinematic import ACOKinematic
from fastep_core.planning.navigators.fastep_kinematic import FAStepKinematic, FAStepPaper
from fastep_core.planning.navigators.optimal_kinematic import OptimalKinematic
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.swarm.step import StepPlan, StepProblem, plan_step

__all__ = ['ALGORITHMS', 'ACOKinematic', 'FAStepKinematic', 'FAStepPaper', 'Mode', 'Navigator', 'OptimalKinematic',
           'OtherRobot', 'PlannerParams', 'StepPlan', 'StepProblem', 'make_navigator', 'make_robot', 'plan_step']
