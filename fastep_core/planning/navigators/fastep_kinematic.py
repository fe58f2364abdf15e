"""FAStep-Kinematic: the paper's Algorithm 1 (Fig. 1), on the loop every navigator shares (planning/navigator.py).

1. While nothing blocks the straight run to the goal, the kinematic controller (eq. 12 for a point mass,
   eq. 13 for a tractor-trailer) drives the robot to the goal.
2. An obstacle is detected (`blocked`) when its surface is nearer than `sensing_range` (eq. 11, epsilon)
   *and* the straight run to the goal passes closer to it than the robot's clearance: only obstacles on the
   way count (Fig. 2). Another robot is detected the same way, with the sum of both radii (case study 2).
3. On detection the swarm (eq. 3-4) plans one step (`plan_next_step`): the waypoint within `step_radius`
   that minimises the step fitness f = a/f1 + b/f2 + c*d (eq. 5-10, planning/swarm/step.py); the controller drives
   the robot there. At the waypoint, or as soon as the run to the goal is clear again, back to 1/2.
"""

from __future__ import annotations

import math
from typing import Sequence

from fastep_core.planning.navigator import FloatArray, Mode, Navigator
from fastep_core.planning.others import OtherRobot

__all__ = ['FAStepKinematic', 'FAStepPaper']


class FAStepKinematic(Navigator):
    """Algorithm 1: kinematics to the goal; the Stepping Ahead Firefly swarm only when something blocks the way.

    When the swarm runs is decided by the activation policy, on by default (docs/architecture.md, "When the swarm
    runs"): `plan_horizon` (plan only once the blocker is within the step the swarm could take) and `stuck_steps` (a
    step that ends where the robot already is starts the trap escape instead of being planned again every tick).
    Neither changes a step (eq. 3-10) or the controller (eq. 12-13); `FAStepPaper` is the paper's literal policy.
    """

    method = 'fastep'
    paper_policy = False   # True: plan on every detection, ignore plan_horizon, stuck_steps and waypoint_lead

    @property
    def plan_horizon(self) -> float:
        return 0.0 if self.paper_policy else self.params.plan_horizon

    @property
    def stuck_steps(self) -> int:
        return 0 if self.paper_policy else self.params.stuck_steps

    def choose_target(self, position: FloatArray, others: Sequence[OtherRobot]) -> FloatArray | None:
        assert self.goal is not None
        following = self.keep_waypoint(position, others)     # a waypoint not yet reached
        self.committed = self.committed and following
        if self.committed:                                  # a step that broke a hold is driven to its end
            return self.waypoint
        if not self.blocked(position, self.goal, others):    # eq. 11: nothing detected on the way
            self.waypoint, self.cost, self.mode, self.reason = None, 0.0, Mode.KINEMATIC, 'way is clear'
            return self.goal                                 # eq. 12 / 13 straight to the goal
        if following:
            return self.aim(position, self.waypoint)
        horizon = self.plan_horizon
        if horizon > 0.0 and not self.blocked(position, self.goal, others, horizon=horizon):
            # Blocked farther than the swarm can step: its step would be the straight one (c*d dominates
            # eq. 10), so drive on by the kinematics and plan once the blocker is within the horizon.
            self.waypoint, self.cost, self.mode, self.reason = None, 0.0, Mode.KINEMATIC, 'way is clear for now'
            return self.goal
        waypoint = self.plan_next_step(position, others)     # eq. 3-10: the swarm plans the next step
        if waypoint is not None and self.stuck_steps > 0:
            self.note_stuck(position, waypoint, others)
        return None if waypoint is None else self.aim(position, waypoint)

    def aim(self, position: FloatArray, waypoint: FloatArray | None) -> FloatArray | None:
        """The point the controller drives to for a waypoint: waypoint_lead beyond it on the ray from the robot.

        The robot still heads straight at the waypoint and counts it as reached within waypoint_tolerance, before
        any of the lead is driven; only eq. 12's slow-down near the target is avoided. Holonomic robots only
        (they follow that ray exactly).
        """
        lead = 0.0 if self.paper_policy else self.params.waypoint_lead
        if waypoint is None or lead <= 0.0 or not self.model.holonomic:
            return waypoint
        run = waypoint - position
        length = math.hypot(run[0], run[1])
        return waypoint if length <= 0.0 else waypoint + run * (lead / length)

    def note_stuck(self, position: FloatArray, waypoint: FloatArray, others: Sequence[OtherRobot]) -> None:
        """Count steps that end within waypoint_tolerance: the swarm's best point is where the robot already is.

        Such a step counts as reached on the next tick and is planned again, every tick, while the trap
        detector waits trap_timeout seconds for the robot to creep 0.5 m closer. With no other robot in
        sensing range nothing will move away: after stuck_steps of them the robot is called trapped at once.
        With robots near, the next plan waits RETRY_AFTER instead (they may make way).
        """
        if math.hypot(waypoint[0] - position[0], waypoint[1] - position[1]) > self.params.waypoint_tolerance:
            self._stuck = 0
            return
        if any(math.hypot(o.position[0] - position[0], o.position[1] - position[1]) - o.radius - self.radius
               < self.params.sensing_range for o in others):
            self.steps.retry_later(self._last_t or 0.0)
            return
        self._stuck += 1
        if self._stuck >= self.stuck_steps:
            self._stuck = 0
            self.trap.trip()


class FAStepPaper(FAStepKinematic):
    """FAStep-Kinematic with the paper's literal activation policy: the swarm plans a step on every detection
    (eq. 11, anywhere on the run within sensing range) and every tick a step ends where the robot already is;
    only the trap detector's timeout starts an escape. The reference `fastep` is measured against."""

    method = 'fastep_paper'
    paper_policy = True
