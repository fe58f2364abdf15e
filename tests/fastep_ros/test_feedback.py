"""Navigation feedback as Nav2 fills it (issue "Nav2's own client", item 1): distance_remaining is the way left along
the route the robot follows, falling as it drives and matching what it then drives; the ETA and navigation_time
from it and the node's clock. In the test's process, on the test's clock (fastep_testing.in_process): the node's
callbacks called directly, a point-mass base doing exactly what it is told."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from fastep_core.geometry import Circle
from fastep_testing.in_process import DT, GoalHandle, PointMassBase, planner_node
from fastep_testing.planning_gate import wait_for
from msg_tools import convert

pytest.importorskip('nav2_msgs.action', reason='nav2_msgs is built by make (interfaces/build.sh)')

START, GOAL = (2.0, 10.0), (18.0, 10.0)
TICKS = 2000   # 100 s of the test's clock: the drive takes about 20


def drive(context: Any, kind: str, goal: Any, **params: Any) -> tuple[PointMassBase, GoalHandle, Any]:
    """A goal of `kind` driven to its end round a circle on the direct line: the base, the handle, the result."""
    from rclpy.task import Future

    from fastep_ros.planner_threads import ActionGoal
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model='point_mass', algorithm='fastep_route',
                        robot_radius=0.5, alpha1=1.0, alpha2=1.0, max_speed=1.0, **params)
    try:
        base = PointMassBase(node, START)
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 10.0), 1.5)]))
        base.tick()
        handle, done = GoalHandle(goal, base), Future()
        node.actions.start(ActionGoal(kind, handle, done, node.actions.epoch), True)
        for _ in range(TICKS):
            if done.done():
                break
            base.tick()
        assert done.done(), f'the goal did not end within {TICKS} ticks: {node.reports.status()}'
        return base, handle, done.result()
    finally:
        node.destroy_node()


def driven_after(path: list[np.ndarray]) -> np.ndarray:
    """For each point of the path, the length driven from there to the end."""
    steps = np.hypot(*np.diff(np.array(path), axis=0).T)
    return np.concatenate([np.cumsum(steps[::-1])[::-1], [0.0]])


def seconds(duration: Any) -> float:
    return float(duration.sec + duration.nanosec * 1e-9)


def check_distances(base: PointMassBase, handle: GoalHandle, least: float) -> list[tuple[float, float]]:
    """distance_remaining against what is then driven (within 5 % or 0.2 m), never rising; (told, driven) pairs."""
    left = driven_after(base.path)
    pairs = [(float(f.distance_remaining), float(left[i])) for i, f in handle.feedback]
    assert len(pairs) > 100, len(pairs)
    assert max(t for t, _ in pairs[:3]) > least, pairs[:3]   # the way round the circle, longer than the straight run
    for k, (told, driven) in enumerate(pairs):
        assert abs(told - driven) <= max(0.05 * driven, 0.2), (k, told, driven)
    told = [t for t, _ in pairs]
    assert all(b <= a + 0.05 for a, b in zip(told, told[1:])), max(b - a for a, b in zip(told, told[1:]))
    assert told[-1] < 0.3
    return pairs


def test_distance_remaining_follows_the_route_round_an_obstacle_and_falls_as_the_robot_drives(context: Any) -> None:
    from nav2_msgs.action import NavigateToPose
    goal = NavigateToPose.Goal(pose=convert.point_to_pose_stamped(GOAL))
    base, handle, (how, result) = drive(context, 'navigate_to_pose', goal)
    assert (how, result.error_code) == ('succeeded', 0)
    assert math.dist(base.path[-1], GOAL) < 0.3
    check_distances(base, handle, 16.1)
    # The time: navigation_time on the node's clock since the goal came; the ETA within the time then taken.
    end = len(base.path) - 1
    first_index, first = handle.feedback[0]
    assert seconds(handle.feedback[-1][1].navigation_time) == pytest.approx((handle.feedback[-1][0] - 1) * DT,
                                                                            abs=2 * DT)
    ratios = [seconds(f.estimated_time_remaining) / ((end - i) * DT) for i, f in handle.feedback if end - i > 40]
    assert 0.7 < float(np.median(ratios)) < 1.3, np.percentile(ratios, [0, 50, 100])
    assert first.number_of_recoveries == 0


def test_distance_remaining_through_poses_adds_the_legs_after_the_pose_driven_to(context: Any) -> None:
    from nav2_msgs.action import NavigateThroughPoses
    poses = [convert.point_to_pose_stamped(p) for p in ((10.0, 14.0), GOAL)]
    base, handle, (how, result) = drive(context, 'navigate_through_poses', NavigateThroughPoses.Goal(poses=poses))
    assert (how, result.error_code) == ('succeeded', 0)
    check_distances(base, handle, math.dist((10.0, 14.0), GOAL))
    left = [f.number_of_poses_remaining for _, f in handle.feedback]
    assert left[0] == 2 and left[-1] == 1 and sorted(left, reverse=True) == left


# ------------------------------------------------------------------------------------------------ every goal ends
TIMEOUT = 2.0   # s: planning_timeout of these tests (40 ticks of the test's clock)


def stalled_node(context: Any) -> tuple[Any, PointMassBase, Any]:
    """A planner whose passes all wait at a gate (planning that never ends) from the next tick on."""
    from fastep_testing.planning_gate import Gate
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model='point_mass', algorithm='fastep_route',
                        robot_radius=0.5, planning_timeout=TIMEOUT)
    base = PointMassBase(node, START)
    node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((10.0, 10.0), 1.5)]))
    base.tick()
    wait_for(lambda: node.planning is not None and node.planning.plan is not None and
             node.planning.pass_started is None, 'the first plan')
    assert node.navigator is not None
    return node, base, Gate.holding(node.navigator)


def tick_without_passes(base: PointMassBase) -> None:
    """A control tick while the pass under way does not end (the base stands: the robot is stopped)."""
    base.node.inputs.on_odom(convert.state_to_odometry([*base.xy, 0.0], convert.seconds_to_stamp(base.now)))
    base.node.on_control()
    base.now += DT


def ticks_until(base: PointMassBase, done: Any, most: int) -> int:
    for k in range(most):
        if done():
            return k
        tick_without_passes(base)
    raise AssertionError(f'not within {most} ticks: status {base.node.reports.status()}')


@pytest.mark.parametrize('stage', ['planning', 'taking'])
def test_a_goal_whose_planning_stalls_ends_aborted_with_nav2_s_timeout_within_planning_timeout(context: Any,
                                                                                                stage: str) -> None:
    """planning: the goal taken, its passes never end; taking: a pass under way never ends, so the planning side
    never takes the goal. Either way: ABORTED, ComputePathToPose TIMEOUT (207), within planning_timeout."""
    from nav2_msgs.action import NavigateToPose
    from rclpy.task import Future

    from fastep_ros.planner_threads import ActionGoal
    node, base, gate = stalled_node(context)
    try:
        handle, done = GoalHandle(NavigateToPose.Goal(pose=convert.point_to_pose_stamped(GOAL)), base), Future()
        if stage == 'taking':
            tick_without_passes(base)
            assert gate.entered.wait(30.0)   # a pass under way that does not end, before the goal comes
        node.actions.start(ActionGoal('navigate_to_pose', handle, done, node.actions.epoch), True)
        if stage == 'planning':
            run = node.actions.run
            wait_for(lambda: node.goal_msg is run.sent, 'the goal taken')
        ticks = ticks_until(base, done.done, int(3 * TIMEOUT / DT))
        assert ticks <= TIMEOUT / DT + 3, ticks
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 207), (how, result.error_code, result.error_msg)
        assert 'planning timed out' in result.error_msg and f'planning_timeout {TIMEOUT:g} s' in result.error_msg
        if stage == 'planning':
            level, message, reason = node.reports.status()
            assert (message, reason) == ('failed', result.error_msg)
    finally:
        gate.open.set()
        node.destroy_node()


def test_a_goal_pose_goal_whose_planning_stalls_fails_and_the_next_goal_drives(context: Any) -> None:
    node, base, gate = stalled_node(context)
    try:
        node.on_goal(convert.point_to_pose_stamped(GOAL))
        ticks = ticks_until(base, lambda: bool(node.plan_failed), int(3 * TIMEOUT / DT))
        assert ticks <= TIMEOUT / DT + 3, ticks
        level, message, reason = node.reports.status()
        assert (message, reason.split(':')[0]) == ('failed', 'planning timed out'), (message, reason)
        gate.open.set()   # the pass ends: the planning side fails the goal too
        wait_for(lambda: node.navigator is not None and node.navigator.mode.value == 'failed', 'the goal failed')
        assert node.navigator.reason == node.plan_failed
        node.on_goal(convert.point_to_pose_stamped((18.0, 4.0)))   # a new goal: driven to
        for _ in range(5):
            base.tick()
        assert node.plan_failed == '' and node.reports.status()[1] in ('kinematic', 'avoiding')
        assert any(node.last_command)
    finally:
        gate.open.set()
        node.destroy_node()


def test_an_unreachable_goal_ends_aborted_no_valid_path(context: Any) -> None:
    """A goal walled in (reachable by no path): ABORTED, ComputePathToPose NO_VALID_PATH (208), at once."""
    from nav2_msgs.action import NavigateToPose
    from rclpy.task import Future

    from fastep_core.geometry import Segment
    from fastep_ros.planner_threads import ActionGoal
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model='point_mass', algorithm='fastep_route',
                        robot_radius=0.5, planning_timeout=TIMEOUT)
    try:
        base = PointMassBase(node, START)
        corners = [(14.0, 8.0), (18.0, 8.0), (18.0, 12.0), (14.0, 12.0)]
        walls = [Segment(corners[i], corners[(i + 1) % 4]) for i in range(4)]
        node.inputs.on_obstacles(convert.obstacles_to_marker_array(walls))
        base.tick()
        handle, done = GoalHandle(NavigateToPose.Goal(pose=convert.point_to_pose_stamped((16.0, 10.0))), base), Future()
        node.actions.start(ActionGoal('navigate_to_pose', handle, done, node.actions.epoch), True)
        for _ in range(int(3 * TIMEOUT / DT)):
            if done.done():
                break
            base.tick()
        assert done.done(), node.reports.status()
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 208), (how, result.error_code, result.error_msg)
    finally:
        node.destroy_node()
