"""Goals: a refused goal leaves the goal under way alone and says why; one goal subscription that volatile
publishers (RViz, `ros2 topic pub`) and latched ones (fastep-launch) both reach without an incompatible-QoS
event on either side, and a planner started after a latched goal was sent still gets it."""

from __future__ import annotations

import math
import time
from typing import Any, Callable

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseStamped
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy

from fastep_core.geometry import Circle
from fastep_ros.goals import CatchUp
from fastep_ros.planner import PlannerNode
from msg_tools import convert
from msg_tools.interface import LATCHED, RELIABLE

TL, VOLATILE = DurabilityPolicy.TRANSIENT_LOCAL, DurabilityPolicy.VOLATILE
A, B, C = (1,), (2,), (3,)   # publisher gids


# ----------------------------------------------------------------------------------------------- the rule

def test_volatile_except_to_catch_up_with_latched_publishers_and_never_beside_a_volatile_one() -> None:
    rule = CatchUp(timeout=5.0)
    assert rule.look([], 0.0) == VOLATILE                       # nobody yet (rmw's BEST_AVAILABLE: latched)
    assert rule.look([(A, True)], 1.0) == TL                    # a latched publisher: get its history
    rule.heard_goal()
    assert rule.look([(A, True)], 1.25) == VOLATILE             # its goal came: caught up
    assert rule.look([(A, True), (B, False)], 2.0) == VOLATILE  # RViz comes: nothing to catch up with
    assert rule.look([(A, True), (B, False), (C, True)], 3.0) == VOLATILE   # a new latched one beside RViz
    assert rule.look([(A, True), (C, True)], 4.0) == TL         # RViz gone: catch up with C
    assert rule.look([(A, True), (C, True)], 8.9) == TL
    assert rule.look([(A, True), (C, True)], 9.0) == VOLATILE   # C sent nothing in 5 s: its later goals come live
    assert rule.look([(A, True), (C, True)], 60.0) == VOLATILE


def test_a_publisher_that_comes_back_is_caught_up_with_again() -> None:
    rule = CatchUp(timeout=5.0)
    assert rule.look([(A, True)], 0.0) == TL
    assert rule.look([(A, True)], 5.0) == VOLATILE
    assert rule.look([], 6.0) == VOLATILE
    assert rule.look([(A, True)], 7.0) == TL


# ----------------------------------------------------------------------------------------------- refused goals


# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(context: Any, **params: Any) -> PlannerNode:
    overrides = [Parameter('workspace', value=[0.0, 0.0, 10.0, 10.0]),
                 *(Parameter(k, value=v) for k, v in {**SYNCHRONOUS, **params}.items())]
    return PlannerNode(context=context, parameter_overrides=overrides)


def test_a_refused_goal_leaves_the_goal_under_way_alone_and_says_why(context: Any) -> None:
    node = make(context)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([Circle((5.0, 5.0), 1.0)]))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        node.on_goal(convert.point_to_pose_stamped((8.0, 2.0)))
        node.on_control()
        assert node.reports.status()[:2] == (DiagnosticStatus.OK, 'kinematic')
        for goal, frame, words in (((math.nan, 1.0), 'map', 'not finite'), ((5.0, 5.0), 'map', 'inside an obstacle'),
                                   ((3.0, 3.0), 'odom', "frame 'odom'")):
            node.on_goal(convert.point_to_pose_stamped(goal, frame_id=frame))
            node.on_control()
            level, message, reason = node.reports.status()
            assert (level, message) == (DiagnosticStatus.WARN, 'kinematic'), reason
            assert words in reason and 'still driving to (8, 2)' in reason, reason
            assert node.goal == (8.0, 2.0) and np.any(node.last_command != 0.0)
        node.on_goal(convert.point_to_pose_stamped((8.0, 8.0)))   # a good one is taken, the warning is gone
        node.on_control()
        assert node.reports.status()[:2] == (DiagnosticStatus.OK, 'kinematic') and node.goal == (8.0, 8.0)
    finally:
        node.destroy_node()


def test_a_refused_goal_with_none_under_way_is_a_failure_as_before(context: Any) -> None:
    node = make(context)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        node.on_goal(convert.point_to_pose_stamped((50.0, 5.0)))
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.ERROR, 'failed') and 'outside the map' in reason
    finally:
        node.destroy_node()


def test_goals_at_any_rate_log_a_line_a_second_and_a_long_frame_is_not_echoed_whole(context: Any) -> None:
    """Issue "Faults", item 11 and a borderline one: goals at 1 kHz wrote a "new goal" line each (130 MB of log an
    hour); a 10 KB goal frame went whole into status."""
    node = make(context)
    lines: list[str] = []
    node.goal_info.log = node.goal_warning.log = lines.append
    now = [0.0]   # the lines' wall clock, the test's: 500 goals come within a second however busy the machine
    node.goal_info.clock = node.goal_warning.clock = lambda: now[0]
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        for i in range(500):
            node.on_goal(convert.point_to_pose_stamped((2.0 + i * 0.01, 2.0)))
        assert lines == ['new goal (2, 2)'] and node.goal == (6.99, 2.0)   # every goal taken, one line
        now[0] += 1.0   # a second later
        node.on_goal(convert.point_to_pose_stamped((8.0, 8.0)))
        assert lines[1] == 'new goal (8, 8) (499 more such lines left out before it)'
        node.on_goal(convert.point_to_pose_stamped((3.0, 3.0), frame_id='x' * 10_000))
        reason = node.reports.status()[2]
        assert len(reason) < 300 and "goal frame 'xxxx" in reason and '(10000 characters)' in reason, reason
    finally:
        node.destroy_node()


# ----------------------------------------------------------------------------------------------- over DDS

def spin_until(executor: Any, predicate: Callable[[], bool], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f'timed out after {timeout:g} s waiting for {what}')
        executor.spin_once(timeout_sec=0.02)


def test_volatile_and_latched_goal_publishers_without_incompatible_qos_events(context: Any) -> None:
    """A latched goal sent before the planner starts reaches it; then RViz's kind of publisher (volatile) comes
    and its goal is taken too; neither publisher ever sees an incompatible subscription (each end of a DDS match
    detects an incompatibility, so the planner's end had none either)."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    events: list[tuple[str, Any]] = []

    def listening(name: str) -> PublisherEventCallbacks:
        return PublisherEventCallbacks(incompatible_qos=lambda info: events.append((name, info)))

    user = rclpy.create_node('user', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(user)
    planner = None
    try:
        latched = user.create_publisher(PoseStamped, '/goal_pose', LATCHED, event_callbacks=listening('latched'))
        latched.publish(convert.point_to_pose_stamped((8.0, 8.0)))
        planner = make(context)
        executor.add_node(planner)
        planner.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        planner.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        spin_until(executor, lambda: planner.goal == (8.0, 8.0), 30.0, 'the latched goal')
        # Caught up: the subscription is volatile again, as it stays while nothing is left to catch up with.
        spin_until(executor, lambda: planner.goal_sub.durability == DurabilityPolicy.VOLATILE, 30.0,
                   'the end of the catch-up')
        volatile = user.create_publisher(PoseStamped, '/goal_pose', RELIABLE, event_callbacks=listening('volatile'))
        spin_until(executor, lambda: volatile.get_subscription_count() >= 1, 30.0, 'the planner to match RViz')
        executor.spin_once(timeout_sec=0.5)

        def taken() -> bool:
            volatile.publish(convert.point_to_pose_stamped((2.0, 8.0)))
            executor.spin_once(timeout_sec=0.1)
            return planner.goal == (2.0, 8.0)
        spin_until(executor, taken, 30.0, 'the volatile goal')
        end = time.monotonic() + 1.0   # four more looks at the graph, with both publishers on it
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        assert planner.goal_sub.durability == DurabilityPolicy.VOLATILE
        assert events == []
    finally:
        executor.shutdown()
        if planner is not None:
            planner.destroy_node()
        user.destroy_node()


def test_a_volatile_publisher_that_comes_during_a_catch_up_ends_it(context: Any) -> None:
    """A latched publisher with nothing sent yet (fastep-launch before the goals) keeps the subscription
    transient-local for up to CATCH_UP seconds; RViz started in that time turns it volatile at once (the planner
    does not warn; RViz's end may see the one match it had), and RViz's goals are taken."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    user = rclpy.create_node('user', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(user)
    planner = None
    try:
        user.create_publisher(PoseStamped, '/goal_pose', LATCHED)   # sends nothing
        planner = make(context)
        executor.add_node(planner)
        planner.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        planner.inputs.on_odom(convert.state_to_odometry([1.0, 1.0]))
        spin_until(executor, lambda: planner.goal_sub.durability == DurabilityPolicy.TRANSIENT_LOCAL, 30.0,
                   'the catch-up')
        volatile = user.create_publisher(PoseStamped, '/goal_pose', RELIABLE)
        spin_until(executor, lambda: planner.goal_sub.durability == DurabilityPolicy.VOLATILE, 30.0,
                   'the subscription to turn volatile')

        def taken() -> bool:
            volatile.publish(convert.point_to_pose_stamped((2.0, 8.0)))
            executor.spin_once(timeout_sec=0.1)
            return planner.goal == (2.0, 8.0)
        spin_until(executor, taken, 30.0, 'the volatile goal')
    finally:
        executor.shutdown()
        if planner is not None:
            planner.destroy_node()
        user.destroy_node()


def test_a_diff_drive_goal_s_orientation_is_the_heading_to_end_in(context: Any) -> None:
    node = make(context, model='diff_drive', robot_radius=0.3)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0, 0.0]))
        node.on_goal(convert.point_to_pose_stamped((8.0, 2.0), yaw=2.5))
        nav = node.navigator
        assert nav is not None and nav.goal_heading is not None and math.isclose(nav.goal_heading, 2.5)
        node.on_goal(convert.point_to_pose_stamped((8.0, 2.0), yaw=-1.0))   # the same place, another heading
        assert nav.goal_heading is not None and math.isclose(nav.goal_heading, -1.0)
        zero = convert.point_to_pose_stamped((8.0, 3.0))
        zero.pose.orientation.w = 0.0   # a quaternion of zero length says no heading
        node.on_goal(zero)
        assert nav.goal_heading is None and node.goal == (8.0, 3.0)
        bad = convert.point_to_pose_stamped((8.0, 4.0))
        bad.pose.orientation.z = math.nan
        node.on_goal(bad)
        node.on_control()
        level, _, reason = node.reports.status()
        assert level == DiagnosticStatus.WARN and 'goal orientation' in reason and node.goal == (8.0, 3.0)
    finally:
        node.destroy_node()


def test_a_point_mass_goal_has_no_heading(context: Any) -> None:
    node = make(context)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        node.on_goal(convert.point_to_pose_stamped((8.0, 2.0), yaw=2.5))
        assert node.navigator is not None and node.navigator.goal_heading is None
    finally:
        node.destroy_node()
