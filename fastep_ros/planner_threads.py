"""The planner node's two sides, what each owns, and the immutable values that pass between them.

The planner node (fastep_ros/planner.py) runs its control tick on the executor and its planning passes on a
thread of its own (fastep_ros/planning_thread.py). Nothing is shared mutably between the two:

- the executor (subscriptions, timers, services, action servers, the control tick) owns the inputs
  (fastep_ros/planner_inputs.py: odometry and its history, localization, scans and their placing, the world's
  messages), the ControlTick, every publisher, status and the action runs;
- the planning side (passes, and the changes `call`ed between them) owns the navigator (fastep_core), scan
  perception, the map perception fuses with (`inputs.world`) and the goal driven to (`goal`, `goal_msg`,
  `pending_goal`, `goal_refused`, `refused_msg`).

What crosses, each an immutable value replaced whole (one reference swap, atomic in Python):
- executor -> planning: a `PlanSnapshot` per control tick (the state, the robots told of, the newest scan with the
  robot's pose at its stamp, read on the executor, and what the control tick has measured of the base: its
  braking and slide, `ShownResponse`), and changes: the typed requests below (`Change`), which the planning thread
  applies in the order given, between passes (PlannerNode.apply). They are the only writers of the planning
  side's state; the executor reads it (status, actions) and acts only on what a change has done, never ahead of
  it.
- planning -> executor: a `PassResult` per pass (the plan with the control tick it was planned from, and the
  belief to show on `tracked_obstacles`), and the navigator's `guard_inputs` (fastep_core.planning.safety.guard:
  margin, scan returns and free space of one scan), posted as soon as a scan is perceived so the guard checks
  the newest returns while a long pass still runs.
Publishing is the executor's: a change or a pass on the planning thread leaves what to publish for the next
control tick (status, plan, belief).

A third thread, the action thread (fastep_ros/action_thread.py), spins the node `<planner>_navigation` that holds
Nav2's action servers: it takes and converts their requests (a goal of 100,000 poses is seconds of Python objects
made), answers goal requests (accepted while `lifecycle.is_active`, a flag the executor writes, read whole) and
cancel requests (accepted: rclpy marks the goal CANCELING under its handle's lock, which the executor reads), and
hands each goal to execute to the executor as an `ActionGoal` on a queue, which the executor drains on its control
tick (NavigateActions.check). It owns nothing of the planner's: the runs, their poses, feedback and results are
the executor's (fastep_ros/navigate_actions.py). Back: the executor sets the goal's `done` Future to the terminal
state it chose and the result, and wakes the action executor; the action thread then makes the transition and
sends the result (why each call is safe from which thread: fastep_ros/action_thread.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
from geometry_msgs.msg import PoseStamped

from fastep_core.planning.control import Plan
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.safety.base_response import ShownResponse
from fastep_core.world import World
from fastep_ros.progress import Way
from fastep_ros.sensors import PlacedScan

__all__ = ['ActionGoal', 'AdoptWorld', 'Change', 'DropGoal', 'FailGoal', 'ForgetSeen', 'Localized', 'PassResult',
           'PlanSnapshot', 'RestartClock', 'Retune', 'TakeGoal']


@dataclass(frozen=True)
class PlanSnapshot:
    """What a planning pass plans from: the control tick's time, state and the robots and movers it was told of,
    and the newest scan not yet perceived (placed, with the robot's pose at its stamp)."""

    t: float
    tick: int                # the control tick's number
    state: np.ndarray
    others: list[OtherRobot]
    scan: PlacedScan | None
    velocity: np.ndarray | None = None   # what the base measurably did (odometry's twist), None: not known ...
    measured_at: float | None = None     # ... as of this time (the odometry's stamp)
    response: ShownResponse | None = None   # what the control tick has measured of the base so far


@dataclass(frozen=True)
class PassResult:
    """What a planning pass leaves for the executor: its plan, the control tick it was planned from (the plan's
    age is counted from it), and the belief its scan made, as the serialized MarkerArray `tracked_obstacles`
    shows (None: no scan perceived in this pass), and the way ahead to the goal it planned (navigation feedback's
    distance_remaining: fastep_ros.progress.Way; None: no goal)."""

    plan: Plan
    tick: int
    belief: bytes | None = None
    way: Way | None = None


@dataclass(frozen=True)
class ActionGoal:
    """action thread -> executor: a goal one of the action servers accepted, its execution begun (its execute
    coroutine awaits `done` on the action thread). `kind`: the action's name (navigate_actions.TO_POSE, ...);
    `handle`: rclpy's ServerGoalHandle, its request converted on the action thread and not changed after;
    `done`: an rclpy Future the executor sets once, to (terminal state, result); `epoch`: the deactivations the
    executor had counted when the goal was accepted (one counted since: the goal is not driven)."""

    kind: str
    handle: Any
    done: Any
    epoch: int


# ------------------------------------------------------------------------------------------------ changes
@dataclass(frozen=True)
class TakeGoal:
    """A goal (in the map frame, or as given when TF does not resolve its frame: refused then, saying why)."""

    msg: PoseStamped


@dataclass(frozen=True)
class DropGoal:
    """Forget the goal (a cancel): the robot brakes to a stop, status idle with `reason`."""

    reason: str


@dataclass(frozen=True)
class FailGoal:
    """The goal fails (a fault of the control tick): status failed with `reason`."""

    reason: str


@dataclass(frozen=True)
class AdoptWorld:
    """A new world: the first makes the navigator, later ones replace its map; perception believes afresh on it."""

    world: World
    count: int   # obstacles in it, for the log


@dataclass(frozen=True)
class Retune:
    """New planner parameters (their limits reach every reader at once: Navigator.retune)."""

    params: PlannerParams


@dataclass(frozen=True)
class Localized:
    """A localization pose came: its covariance (None: none, as from TF) bounds the poses scans are placed at."""

    covariance: tuple[float, ...] | None
    sigmas: float


@dataclass(frozen=True)
class RestartClock:
    """The clock restarts at `t` (activated again, or use_sim_time switched): the navigator's timers restart, the
    plan made before is not driven on."""

    t: float


@dataclass(frozen=True)
class ForgetSeen:
    """Forget what the laser added to the belief (its walls and circles, the tracks) inside the square of side `side`
    centred at `centre`, axis-aligned in the map frame (`inside` false: outside it; side inf: everywhere), the map's
    obstacles kept: a Nav2 costmap-clearing service's request (fastep_ros.costmap_services). `done` is told what
    was forgotten once applied (a costmap_services.Forgotten)."""

    centre: tuple[float, float]
    side: float
    inside: bool
    done: Callable[[Any], None]


Change = TakeGoal | DropGoal | FailGoal | AdoptWorld | Retune | Localized | RestartClock | ForgetSeen
"""What the executor asks of the planning side (PlannerNode.change); nothing else changes it."""
