"""A planner node built in the test's process and driven by the test: its clock, its odometry, a base that obeys.

The node's callbacks are called directly (no executor spins it); the planning thread, where the node runs one,
plans each tick's snapshot as it would on a robot, and ObedientBase waits for that pass before its next tick.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np
from rclpy.parameter import Parameter

from fastep_ros.planner import PlannerNode
from fastep_testing.planning_gate import wait_for
from msg_tools import convert

__all__ = ['DT', 'GoalHandle', 'LoggedLines', 'ObedientBase', 'PointMassBase', 'TickClock', 'planner_node']

DT = 0.05   # s: the control period (control_rate_hz 20)


def planner_node(context: Any, **params: Any) -> PlannerNode:
    """A planner node in `context` with these parameters (the rest at their defaults)."""
    return PlannerNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


class TickClock:
    """The test's node clock: a control tick every DT, each with a fresh odometry of a robot standing at `at`."""

    def __init__(self, node: PlannerNode, at: Sequence[float], start: float = 100.0) -> None:
        self.node, self.at, self.now = node, [float(v) for v in at], start
        node.now = lambda: self.now   # type: ignore[method-assign]  # the test's clock

    def tick(self) -> None:
        self.now += DT
        self.node.inputs.on_odom(convert.state_to_odometry(self.at, convert.seconds_to_stamp(self.now)))
        self.node.on_control()


class ObedientBase:
    """A diff-drive base doing exactly what it is told, tick by tick, on the test's clock: from (1, 10) heading
    along x to a goal at (95, 10) in an empty world (far: the approach law's speed, gain x distance, is higher
    than any limit a test sets)."""

    def __init__(self, node: PlannerNode) -> None:
        self.node, self.now, self.state = node, 100.0, np.array([1.0, 10.0, 0.0])
        self.v = self.omega = 0.0   # what it drives at, as its odometry's twist says
        node.now = lambda: self.now   # type: ignore[method-assign]  # the test's clock
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        node.on_goal(convert.point_to_pose_stamped((95.0, 10.0)))

    def odometry(self, stamp: float, state: np.ndarray) -> None:
        self.node.inputs.on_odom(convert.state_to_odometry(state, convert.seconds_to_stamp(stamp),
                                                           linear=(self.v, 0.0), angular=self.omega))

    def tick(self) -> float:
        """One control tick: the odometry now, the command driven for DT; the command's speed."""
        node = self.node
        self.odometry(self.now, self.state)
        node.on_control()
        v, omega = self.v, self.omega = float(node.last_command[0]), float(node.last_command[1])
        self.state = self.state + DT * np.array([v * np.cos(self.state[2]), v * np.sin(self.state[2]), omega])
        self.now += DT
        # The pass on this tick's snapshot ends before the next tick (50 ms of a robot's time; here, at once).
        wait_for(lambda: node.plan_tick == node.control_count and node.planning is not None and
                 node.planning.pass_started is None, 'the pass')
        return v


class PointMassBase:
    """A point-mass base driving exactly the map-frame velocity it is told, for DT each tick, on the test's clock;
    the feedback of the action goal under way every tick (the executor sends one every FEEDBACK_PERIOD wall
    seconds). `path`: where it was at each tick; `speeds`: the speed it drove each tick."""

    def __init__(self, node: PlannerNode, at: Sequence[float]) -> None:
        self.node, self.now, self.xy, self.v = node, 100.0, np.array(at, dtype=float), np.zeros(2)
        self.path = [self.xy.copy()]
        self.speeds: list[float] = []
        node.now = lambda: self.now   # type: ignore[method-assign]  # the test's clock

    def tick(self) -> None:
        node = self.node
        assert node.planning is not None and node.actions is not None
        count, passes = node.control_count, node.planning.passes
        node.inputs.on_odom(convert.state_to_odometry([*self.xy, 0.0], convert.seconds_to_stamp(self.now),
                                                      linear=(float(self.v[0]), float(self.v[1]))))
        node.on_control()
        run = node.actions.run
        if run is not None and run.taken:
            node.actions.publish_feedback(run, 0.0)
        self.v = np.array(node.last_command[:2], dtype=float)
        self.speeds.append(float(np.hypot(*self.v)))
        self.xy = self.xy + DT * self.v
        self.path.append(self.xy.copy())
        self.now += DT
        if node.control_count > count:   # the pass on this tick's snapshot (one pass a snapshot: none waits)
            wait_for(lambda: node.planning is not None and node.planning.passes > passes and
                     node.planning.pass_started is None, 'the pass')


class GoalHandle:
    """What NavigateActions reads and calls of rclpy's ServerGoalHandle: the request, cancel, feedback (each with
    the base's path index when it was sent)."""

    def __init__(self, request: Any, base: PointMassBase) -> None:
        self.request, self.base, self.is_cancel_requested = request, base, False
        self.feedback: list[tuple[int, Any]] = []

    def publish_feedback(self, feedback: Any) -> None:
        self.feedback.append((len(self.base.path) - 1, feedback))


class LoggedLines:
    """The node's logger, its info, warning and error lines kept in `lines` as (level, text) (the rest as it was)."""

    def __init__(self, node: PlannerNode) -> None:
        self.real, self.lines = node.get_logger(), []
        node.get_logger = lambda: self   # type: ignore[method-assign]  # the test reads what the node logs

    def info(self, text: str, **_: Any) -> None:
        self.lines.append(('info', text))

    def warning(self, text: str, **_: Any) -> None:
        self.lines.append(('warning', text))

    def error(self, text: str, **_: Any) -> None:
        self.lines.append(('error', text))

    def __getattr__(self, name: str) -> Any:
        return getattr(self.real, name)
