"""The behaviours of a navigator's control tick, in the order `Navigator.tick` asks them (first answer wins).

Each is an object that keeps its own state and is called with the navigator's narrow `Steering` view and the
tick (`Tick`: the robot, the goal and the world believed now); it returns the tick's command (the tick ends
there) or None (the next one is asked):

- `arrival`: `Arrival` (turn to the goal's heading, arrived once stopped), `BackToGoal` (a goal overshot, backed
  up to).
- `checks`: `PathCheck` (a goal nothing reaches fails), `ProgressCheck` (Nav2's progress checker), `TrapCheck`
  (trapped: starts an escape or a manoeuvre and goes on).
- `recoveries`: `Manoeuvring` (a tractor-trailer's manoeuvre under way), `BackingUp`, `HoldBreaker` (a step round
  a robot the guard holds this one for), `Escaping` (along the exact path out of a trap).
- `driving`: `Algorithm` (the algorithm's `choose_target`, asked last), `drive_on`, `stand_clear`.
- `order`: `Behaviours`, one navigator's set of them in order. Why a list: a reader sees in one place what has
  priority over what.

The mechanisms they drive are planning/recovery/'s; what they ask of the navigator is `tick.Steering`.
"""

from fastep_core.planning.behaviours.arrival import RETURNING, ROTATING, STOPPING, Arrival, BackToGoal
from fastep_core.planning.behaviours.checks import PathCheck, ProgressCheck, TrapCheck
from fastep_core.planning.behaviours.driving import Algorithm, drive_on, stand_clear
from fastep_core.planning.behaviours.order import Behaviours
from fastep_core.planning.behaviours.recoveries import BackingUp, Escaping, HoldBreaker, Manoeuvring
from fastep_core.planning.behaviours.tick import Steering, Tick

__all__ = ['RETURNING', 'ROTATING', 'STOPPING', 'Algorithm', 'Arrival', 'BackToGoal', 'BackingUp', 'Behaviours',
           'Escaping', 'HoldBreaker', 'Manoeuvring', 'PathCheck', 'ProgressCheck', 'Steering', 'Tick', 'TrapCheck',
           'drive_on', 'stand_clear']
