"""Nav2's navigation actions on the planner (issue "Commanded like Nav2", item 1), over DDS with rclpy's
ActionClient as a Nav2 client uses them: accept, feedback, result with Nav2's error codes, preemption, cancel,
rejection while not active. nav2_msgs is built by interfaces/build.sh (make)."""

from __future__ import annotations

import math
import time
from typing import Any

import pytest
from nav_msgs.msg import Odometry

from fastep_testing.graph import Graph, Helper, distance, odom_xy, stamp, write

pytest.importorskip('nav2_msgs.action', reason='nav2_msgs is built by make (interfaces/build.sh)')

NS = '/r1'
FAST = {'alpha1': 1.0, 'alpha2': 1.0, 'max_speed': 2.0, 'algorithm': 'fastep_route', 'robot_radius': 0.5}
WORLD = """\
name: action_world
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [10, 10], radius: 1.5}
robots:
  - {name: r1, model: point_mass, start: [2, 10], goal: [18, 10], radius: 0.5}
"""
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6   # action_msgs/GoalStatus


def pose(x: float, y: float) -> Any:
    from msg_tools.convert import point_to_pose_stamped
    return point_to_pose_stamped((x, y))


def send(h: Helper, client: Any, goal: Any, feedback: list[Any] | None = None) -> Any:
    """Send a goal; its goal handle once accepted or rejected."""
    future = client.send_goal_async(goal, feedback_callback=None if feedback is None else
                                    (lambda msg: feedback.append(msg.feedback)))
    h.spin_until(future.done, 30.0, 'the goal to be answered')
    return future.result()


def result(h: Helper, handle: Any, timeout: float = 90.0, graph: Graph | None = None) -> Any:
    """The result of an accepted goal; on a timeout, what the planner said (status, its log's end)."""
    future = handle.get_result_async()

    def what() -> str:
        from msg_tools.convert import diagnostic_to_dict
        log = graph.log('planner')[-2000:] if graph is not None else ''
        said = [(d['message'], d.get('reason', ''), d.get('t', '')) for d in
                map(diagnostic_to_dict, h.records.get(f'{NS}/status', []))]
        changes = [s for i, s in enumerate(said) if i == 0 or s[:2] != said[i - 1][:2]][-8:]
        odom = h.records.get(f'{NS}/odom', [])
        where = [(round(stamp(m), 2), *(round(v, 3) for v in odom_xy(m))) for m in odom[-200::40]]
        return (f'the action result (last status {h.status(NS)}; status changes {changes}; odometry {where}; '
                f'planner log: {log!r})')
    h.spin_until(future.done, timeout, what)
    return future.result()


def now_xy(h: Helper, odom: list[Any]) -> tuple[float, float]:
    """Where the robot is now: its first odometry stamped after this call (the test's odometry queue lagged the
    action's result by a second under load, and a reached goal looked 1.2 m short)."""
    since = time.time()
    h.spin_until(lambda: bool(odom) and stamp(odom[-1]) >= since, 30.0, 'odometry stamped now')
    return odom_xy(odom[-1])


def test_navigate_through_poses_to_pose_preempt_cancel_and_refuse_as_nav2(graph: Graph) -> None:
    from nav2_msgs.action import NavigateThroughPoses, NavigateToPose
    from rclpy.action import ActionClient
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', WORLD)))
    graph.start('plant', 'plant', NS, model='point_mass', start=[2.0, 10.0])
    graph.start('planner', 'planner', NS, model='point_mass', **FAST)
    h = graph.helper = Helper(graph.domain)
    h.record_status(NS)
    odom = h.record(f'{NS}/odom', Odometry)
    h.wait_status(NS, lambda s: s['message'] == 'idle', 60.0, 'the planner to know the world')
    through = ActionClient(h.node, NavigateThroughPoses, f'{NS}/navigate_through_poses')
    to_pose = ActionClient(h.node, NavigateToPose, f'{NS}/navigate_to_pose')
    h.spin_until(lambda: through.server_is_ready() and to_pose.server_is_ready(), 30.0, 'the action servers')

    # Through two poses round the circle: feedback counts the poses left, the distance shrinks; success at the last.
    feedback: list[Any] = []
    goal = NavigateThroughPoses.Goal(poses=[pose(10.0, 14.0), pose(18.0, 10.0)])
    handle = send(h, through, goal, feedback)
    assert handle.accepted
    done = result(h, handle, graph=graph)
    assert (done.status, done.result.error_code, done.result.error_msg) == (SUCCEEDED, 0, '')
    assert distance(now_xy(h, odom), (18.0, 10.0)) < 0.2
    left = [f.number_of_poses_remaining for f in feedback]
    assert left[0] == 2 and left[-1] == 1 and sorted(left, reverse=True) == left, left
    assert feedback[0].distance_remaining > feedback[-1].distance_remaining >= 0.0
    assert all(f.current_pose.header.frame_id == 'map' for f in feedback)
    assert feedback[-1].navigation_time.sec + feedback[-1].navigation_time.nanosec * 1e-9 > 1.0

    # A goal preempted by a new one: aborted with 0 (Nav2's), saying so; the new one is cancelled on its way: the
    # robot stops.
    first = send(h, to_pose, NavigateToPose.Goal(pose=pose(2.0, 10.0)))
    h.spin_for(1.0)
    second = send(h, to_pose, NavigateToPose.Goal(pose=pose(2.0, 6.0)))
    preempted = result(h, first, graph=graph)
    assert (preempted.status, preempted.result.error_code, preempted.result.error_msg) == \
        (ABORTED, 0, 'preempted by a new goal')
    h.spin_for(1.0)
    before = len(odom)
    cancel = second.cancel_goal_async()
    h.spin_until(cancel.done, 30.0, 'the cancel to be answered')
    canceled = result(h, second, graph=graph)
    assert canceled.status == CANCELED
    h.spin_for(2.0)
    still = now_xy(h, odom)
    h.spin_for(1.0)
    assert distance(now_xy(h, odom), still) < 0.01, 'the robot kept moving after the cancel'
    # ... and it braked within its acceleration limit (max_acceleration, 2.5 m/s^2), not at once: the command steps
    # down once a control period (0.05 s), which the point mass (50 Hz odometry) follows at once, so the speed is
    # compared over windows, allowing three control periods: under load DDS delivered two of the steps to the
    # plant within one of its 0.02 s integration steps (a drop of 0.235 m/s in 0.04 s).
    speeds = [(m.header.stamp.sec + m.header.stamp.nanosec * 1e-9, math.hypot(m.twist.twist.linear.x,
                                                                            m.twist.twist.linear.y))
              for m in odom[before - 1:]]
    assert max(v for _, v in speeds[:10]) > 0.5, 'the robot was not moving when cancelled'
    for i, (t0, v0) in enumerate(speeds):
        for t1, v1 in speeds[i + 1:]:
            assert v0 - v1 <= 2.5 * (t1 - t0 + 0.15) + 1e-6, (t1 - t0, v0 - v1)
    assert h.status(NS)['message'] == 'idle' and 'canceled' in h.status(NS)['reason']

    # A goal inside the circle: aborted at once with Nav2's GOAL_OCCUPIED (ComputePathToPose: 206) and why.
    refused = result(h, send(h, to_pose, NavigateToPose.Goal(pose=pose(10.0, 10.0))), 30.0)
    assert (refused.status, refused.result.error_code) == (ABORTED, 206)
    assert 'occupied' in refused.result.error_msg

    # A goal in the robot's own frame, 1.5 m ahead (the plant's TF: map -> r1/odom -> r1/base_link): reached there.
    here = now_xy(h, odom)
    ahead = pose(1.5, 0.0)
    ahead.header.frame_id = 'r1/base_link'
    reached = result(h, send(h, to_pose, NavigateToPose.Goal(pose=ahead)), graph=graph)
    assert reached.status == SUCCEEDED, reached.result.error_msg
    assert distance(now_xy(h, odom), (here[0] + 1.5, here[1])) < 0.2   # a point mass's base_link faces +x
    in_odom = pose(here[0], here[1] - 1.0)   # the plant's map -> r1/odom is the identity (simulation)
    in_odom.header.frame_id = 'r1/odom'
    back = result(h, send(h, to_pose, NavigateToPose.Goal(pose=in_odom)), graph=graph)
    assert back.status == SUCCEEDED and distance(now_xy(h, odom), (here[0], here[1] - 1.0)) < 0.2
    unknown = pose(1.0, 0.0)
    unknown.header.frame_id = 'nowhere'
    lost = result(h, send(h, to_pose, NavigateToPose.Goal(pose=unknown)), 30.0)
    # No transform: 0, as Nav2's navigators end a goal they cannot transform (fastep says why in error_msg).
    assert (lost.status, lost.result.error_code) == (ABORTED, 0) and "'nowhere'" in lost.result.error_msg
    assert math.isfinite(now_xy(h, odom)[0])


def test_a_goal_is_rejected_while_the_planner_is_not_active(graph: Graph) -> None:
    """Configured (its action servers are made by configure, as Nav2's are) but not active: rejected."""
    from lifecycle_msgs.msg import Transition
    from lifecycle_msgs.srv import ChangeState
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionClient
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', WORLD)))
    graph.start('planner', 'planner', NS, model='point_mass', autostart=False, **FAST)
    h = graph.helper = Helper(graph.domain)
    change = h.node.create_client(ChangeState, f'{NS}/planner/change_state')
    h.spin_until(change.service_is_ready, 30.0, 'the lifecycle service')
    configured = change.call_async(ChangeState.Request(transition=Transition(id=Transition.TRANSITION_CONFIGURE)))
    h.spin_until(configured.done, 30.0, 'configure')
    assert configured.result().success
    client = ActionClient(h.node, NavigateToPose, f'{NS}/navigate_to_pose')
    h.spin_until(client.server_is_ready, 30.0, 'the action server')
    assert not send(h, client, NavigateToPose.Goal(pose=pose(18.0, 10.0))).accepted


def test_follow_waypoints_reports_the_one_it_missed(graph: Graph) -> None:
    """follow_waypoints with stop_on_failure false: the middle waypoint lies inside the circle (refused, Nav2's
    GOAL_OCCUPIED), the robot goes on to the last; SUCCEEDED with that waypoint in missed_waypoints. Then, with
    stop_on_failure true, the same list ends ABORTED at that waypoint, with 0 as Nav2's waypoint follower."""
    from nav2_msgs.action import FollowWaypoints
    from rcl_interfaces.srv import SetParameters
    from rclpy.action import ActionClient
    from rclpy.parameter import Parameter
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', WORLD)))
    graph.start('plant', 'plant', NS, model='point_mass', start=[2.0, 10.0])
    graph.start('planner', 'planner', NS, model='point_mass', stop_on_failure=False, **FAST)
    h = graph.helper = Helper(graph.domain)
    h.record_status(NS)
    odom = h.record(f'{NS}/odom', Odometry)
    h.wait_status(NS, lambda s: s['message'] == 'idle', 60.0, 'the planner to know the world')
    client = ActionClient(h.node, FollowWaypoints, f'{NS}/follow_waypoints')
    h.spin_until(client.server_is_ready, 30.0, 'the action server')
    feedback: list[Any] = []
    waypoints = [pose(6.0, 13.0), pose(10.0, 10.0), pose(14.0, 13.0)]
    done = result(h, send(h, client, FollowWaypoints.Goal(poses=waypoints), feedback))
    assert (done.status, done.result.error_code) == (SUCCEEDED, 0)
    assert [(m.index, m.error_code) for m in done.result.missed_waypoints] == [(1, 206)]
    assert distance(now_xy(h, odom), (14.0, 13.0)) < 0.2
    assert {f.current_waypoint for f in feedback} >= {0, 2}
    set_stop = h.node.create_client(SetParameters, f'{NS}/planner/set_parameters')
    request = SetParameters.Request(parameters=[Parameter('stop_on_failure', value=True).to_parameter_msg()])
    h.spin_until(set_stop.service_is_ready, 30.0, 'the parameter service')
    answer = set_stop.call_async(request)
    h.spin_until(answer.done, 30.0, 'the parameter set')
    stopped = result(h, send(h, client, FollowWaypoints.Goal(poses=waypoints[::-1])))
    assert (stopped.status, stopped.result.error_code) == (ABORTED, 0)
    assert [m.index for m in stopped.result.missed_waypoints] == [1] and 'waypoint 1' in stopped.result.error_msg


def test_the_navigation_client_drives_a_robot_with_basic_navigator_s_verbs(graph: Graph,
                                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """fastep_ros.navigation_client: go_to_pose, is_task_complete with feedback, get_result; a cancel_task."""
    from fastep_ros.navigation_client import NavigationClient
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', WORLD)))
    graph.start('plant', 'plant', NS, model='point_mass', start=[2.0, 10.0])
    graph.start('planner', 'planner', NS, model='point_mass', **FAST)
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    nav = NavigationClient(namespace=NS, domain_id=graph.domain, server_timeout=60.0)
    try:
        # As BasicNavigator's waitUntilNav2Active: a goal before activation is rejected (at load 10 its servers,
        # made by configure, were up a while before the planner was active)
        nav.wait_until_active('planner')
        assert nav.go_to_pose(18.0, 10.0)
        seen = []
        deadline = time.monotonic() + 90.0
        while not nav.is_task_complete() and time.monotonic() < deadline:
            if nav.get_feedback() is not None:
                seen.append(nav.get_feedback().distance_remaining)
        assert nav.get_result() == 'succeeded' and nav.result_message() == ''
        assert seen and seen[0] > seen[-1]
        assert nav.go_to_pose(2.0, 14.0)
        for _ in range(10):
            nav.is_task_complete()
        assert nav.cancel_task()
        deadline = time.monotonic() + 30.0
        while not nav.is_task_complete() and time.monotonic() < deadline:
            pass
        assert nav.get_result() == 'canceled'
    finally:
        nav.close()


def test_a_speed_limit_caps_max_speed_as_nav2_s_speed_filter_sends_it(context: Any) -> None:
    """nav2_msgs/SpeedLimit on speed_limit: a percentage of max_speed or m/s caps the navigator's max_speed; 0
    lifts it; the max_speed parameter stays what it was; a bad limit is ignored."""
    from nav2_msgs.msg import SpeedLimit
    from rclpy.parameter import Parameter

    from fastep_ros.planner import PlannerNode
    node = PlannerNode(context=context, parameter_overrides=[Parameter('max_speed', value=2.0),
                                                             Parameter('planning_thread', value=False)])
    try:
        for percentage, value, expected in ((True, 25.0, 0.5), (False, 1.2, 1.2), (False, 3.0, 2.0), (True, 0.0, 2.0),
                                            (True, 150.0, 2.0), (False, math.nan, 2.0), (False, 0.7, 0.7)):
            node.on_speed_limit(SpeedLimit(percentage=percentage, speed_limit=value))
            assert node.params.max_speed == pytest.approx(expected), (percentage, value)
        assert node.get_parameter('max_speed').value == 2.0
        node.set_parameters([Parameter('max_speed', value=0.5)])   # a new max_speed is capped by the limit kept
        assert node.params.max_speed == 0.5 and node.configured_max_speed == 0.5
        node.set_parameters([Parameter('max_speed', value=1.5)])
        assert node.params.max_speed == pytest.approx(0.7)
    finally:
        node.destroy_node()


def start_robot(graph: Graph, **params: Any) -> tuple[Helper, list[Any]]:
    """Map, plant and planner on WORLD; the helper once the planner knows the world and the odometry is heard."""
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', WORLD)))
    graph.start('plant', 'plant', NS, model='point_mass', start=[2.0, 10.0])
    graph.start('planner', 'planner', NS, model='point_mass', **{**FAST, **params})
    h = graph.helper = Helper(graph.domain)
    h.record_status(NS)
    odom = h.record(f'{NS}/odom', Odometry)
    h.wait_status(NS, lambda s: s['message'] == 'idle', 60.0, 'the planner to know the world')
    h.wait_heard(f'{NS}/odom')
    return h, odom


def client_for(h: Helper, action: Any, name: str) -> Any:
    from rclpy.action import ActionClient
    client = ActionClient(h.node, action, f'{NS}/{name}')
    h.spin_until(client.server_is_ready, 30.0, f'the {name} server')
    return client


def test_follow_waypoints_misses_every_refused_waypoint_and_the_next_goal_runs(graph: Graph) -> None:
    """stop_on_failure false and as many waypoints as a goal may have, every one inside the circle: each is a
    MissedWaypoint with GOAL_OCCUPIED (once each, in order), the goal SUCCEEDS at once, nothing recursed; a valid
    goal after it is driven to."""
    from nav2_msgs.action import FollowWaypoints

    from fastep_ros.limits import GOAL_POSES_MAX
    h, odom = start_robot(graph, stop_on_failure=False)
    client = client_for(h, FollowWaypoints, 'follow_waypoints')
    inside = [pose(9.5 + (i % 100) * 0.01, 10.0) for i in range(GOAL_POSES_MAX)]
    done = result(h, send(h, client, FollowWaypoints.Goal(poses=inside)), 60.0, graph)
    assert (done.status, done.result.error_code) == (SUCCEEDED, 0), done.result.error_msg
    missed = done.result.missed_waypoints
    assert [m.index for m in missed] == list(range(GOAL_POSES_MAX))
    assert {m.error_code for m in missed} == {206}
    assert missed[7].goal.pose.position.x == pytest.approx(9.57)
    after = result(h, send(h, client, FollowWaypoints.Goal(poses=[pose(4.0, 10.0)])), graph=graph)
    assert (after.status, after.result.error_code, list(after.result.missed_waypoints)) == (SUCCEEDED, 0, [])
    assert distance(now_xy(h, odom), (4.0, 10.0)) < 0.2
    log = graph.log('planner')
    assert 'RecursionError' not in log and 'Traceback' not in log, log[-3000:]


def test_a_pose_list_is_refused_whole_before_the_robot_moves(graph: Graph) -> None:
    """A NaN third pose, and one pose more than a goal may have, end the goal ABORTED at once (the pose and the
    bound named), for navigate_through_poses and follow_waypoints (stop_on_failure) alike; the robot never moves."""
    from nav2_msgs.action import FollowWaypoints, NavigateThroughPoses

    from fastep_ros.limits import GOAL_POSES_MAX
    h, odom = start_robot(graph, stop_on_failure=True)
    through = client_for(h, NavigateThroughPoses, 'navigate_through_poses')
    waypoints = client_for(h, FollowWaypoints, 'follow_waypoints')
    start = now_xy(h, odom)
    first = len(odom)

    def still() -> None:
        now_xy(h, odom)   # the odometry up to now
        moved = max(distance(odom_xy(m), start) for m in odom[first:])
        assert moved < 0.01, f'the robot moved {moved:.3f} m for goals refused'

    poses = [pose(6.0, 13.0), pose(14.0, 13.0), pose(math.nan, 10.0)]
    nan = result(h, send(h, through, NavigateThroughPoses.Goal(poses=poses)), 30.0, graph)
    still()
    assert (nan.status, nan.result.error_code) == (ABORTED, 200)
    assert 'pose 2' in nan.result.error_msg and 'not finite' in nan.result.error_msg, nan.result.error_msg
    stopped = result(h, send(h, waypoints, FollowWaypoints.Goal(poses=poses)), 30.0, graph)
    assert (stopped.status, stopped.result.error_code) == (ABORTED, 0)
    assert [(m.index, m.error_code) for m in stopped.result.missed_waypoints] == [(2, 200)]
    assert 'waypoint 2' in stopped.result.error_msg and 'not finite' in stopped.result.error_msg

    too_many = [pose(4.0, 10.0)] * (GOAL_POSES_MAX + 1)
    for client, action in ((through, NavigateThroughPoses), (waypoints, FollowWaypoints)):
        long = result(h, send(h, client, action.Goal(poses=too_many)), 30.0, graph)
        assert (long.status, long.result.error_code) == (ABORTED, 200)
        assert f'{GOAL_POSES_MAX + 1} poses' in long.result.error_msg, long.result.error_msg
        assert str(GOAL_POSES_MAX) in long.result.error_msg.replace(f'{GOAL_POSES_MAX + 1}', '')

    h.spin_for(1.0)
    still()


def test_ended_goals_are_released_soon_after_their_result(graph: Graph) -> None:
    """Goals cancelled as soon as accepted: each result is there at once (CANCELED, or ABORTED for the ones a
    newer goal preempted), and within a minute the server has forgotten them (a result asked for then is
    UNKNOWN; the status array lists only the goals since), where rclpy's default keeps them 15 minutes."""
    from action_msgs.msg import GoalStatus, GoalStatusArray
    from nav2_msgs.action import NavigateThroughPoses
    from rclpy.action.client import ClientGoalHandle
    from rclpy.qos import qos_profile_action_status_default
    h, _ = start_robot(graph)
    through = client_for(h, NavigateThroughPoses, 'navigate_through_poses')
    statuses = h.record(f'{NS}/navigate_through_poses/_action/status', GoalStatusArray,
                        qos_profile_action_status_default)
    handles: list[ClientGoalHandle] = []
    for _ in range(10):
        handle = send(h, through, NavigateThroughPoses.Goal(poses=[pose(4.0, 10.0 + 0.01 * j) for j in range(100)]))
        assert handle.accepted
        cancel = handle.cancel_goal_async()
        h.spin_until(cancel.done, 30.0, 'the cancel to be answered')
        handles.append(handle)
    for handle in handles:
        assert result(h, handle, 30.0, graph).status in (CANCELED, ABORTED)

    def forgotten(handle: ClientGoalHandle) -> bool:
        answer = handle.get_result_async()
        h.spin_until(answer.done, 30.0, 'a result to be answered')
        return bool(answer.result().status == GoalStatus.STATUS_UNKNOWN)
    h.spin_until(lambda: all(forgotten(handle) for handle in handles), 60.0, 'the ended goals to be released')

    last = send(h, through, NavigateThroughPoses.Goal(poses=[pose(4.0, 10.0)]))
    uuid = bytes(last.goal_id.uuid)
    h.spin_until(lambda: any(bytes(s.goal_info.goal_id.uuid) == uuid for m in statuses[-1:] for s in m.status_list),
                 30.0, 'the status array with the new goal')
    assert len(statuses[-1].status_list) == 1, [s.status for s in statuses[-1].status_list]
