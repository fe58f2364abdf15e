"""follow_path as Nav2's controller_server serves it (issue "Nav2's own client", items 3 and 4): a given path driven
along its shape to its last pose, feedback distance_to_goal along it, a path update while driving, FollowPath's
error codes; and the codes Nav2 gives 0 where fastep gave its own (preemption, a failed waypoint list, a missing
transform), stop_on_failure false as Nav2's stock params. In the test's process, on the test's clock
(fastep_testing.in_process): the node's callbacks called directly, a point-mass base doing exactly what it is told."""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
import pytest

from fastep_core.geometry import Circle
from fastep_testing.in_process import GoalHandle, PointMassBase, planner_node
from msg_tools import convert

pytest.importorskip('nav2_msgs.action', reason='nav2_msgs is built by make (interfaces/build.sh)')

START = (2.0, 10.0)
CORNER, END = (10.0, 10.0), (10.0, 16.0)   # the bend: the straight run from START to END is 3 m from it
TICKS = 1200   # 60 s of the test's clock: a path of 14 m takes about 16
SPACING = 0.05   # m between the path's poses, as a grid planner's (Nav2's NavFn, Smac) on a 5 cm costmap


def polyline(*corners: Sequence[float], spacing: float = SPACING) -> np.ndarray:
    """Points every `spacing` along the legs between the corners, the corners among them."""
    points = [np.array(corners[0], dtype=float)]
    for a, b in zip(corners, corners[1:]):
        a, b = np.array(a, dtype=float), np.array(b, dtype=float)
        steps = max(1, int(math.ceil(np.hypot(*(b - a)) / spacing)))
        points += [a + (b - a) * k / steps for k in range(1, steps + 1)]
    return np.array(points)


def path_msg(points: np.ndarray, frame: str = 'map') -> Any:
    """A nav_msgs/Path through the points, in `frame` (the poses' headers too, as Nav2's planners fill them)."""
    from nav_msgs.msg import Path
    msg = Path()
    msg.header.frame_id = frame
    for x, y in points:
        pose = convert.point_to_pose_stamped((float(x), float(y)))
        pose.header.frame_id = frame
        msg.poses.append(pose)
    return msg


def follow_goal(points: np.ndarray, frame: str = 'map') -> Any:
    from nav2_msgs.action import FollowPath
    return FollowPath.Goal(path=path_msg(points, frame), controller_id='FollowPath', goal_checker_id='goal_checker')


def robot(context: Any, obstacles: Sequence[Any] = (), **params: Any) -> tuple[Any, PointMassBase]:
    """A point-mass planner on a 20 m square, the base standing at START, one tick made."""
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model='point_mass', algorithm='fastep_route',
                        robot_radius=0.5, alpha1=1.0, alpha2=1.0, max_speed=1.0, **params)
    base = PointMassBase(node, START)
    node.inputs.on_obstacles(convert.obstacles_to_marker_array(list(obstacles)))
    base.tick()
    return node, base


def send(node: Any, base: PointMassBase, kind: str, goal: Any) -> tuple[GoalHandle, Any]:
    """The goal handed to the executor as the action thread hands it: its handle and its `done` Future."""
    from rclpy.task import Future

    from fastep_ros.planner_threads import ActionGoal
    handle, done = GoalHandle(goal, base), Future()
    node.actions.start(ActionGoal(kind, handle, done, node.actions.epoch), True)
    return handle, done


def run_until(base: PointMassBase, done: Any, most: int = TICKS) -> Any:
    for _ in range(most):
        if done.done():
            break
        base.tick()
    assert done.done(), f'the goal did not end within {most} ticks: {base.node.reports.status()}'
    return done.result()


def distance_to(points: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Each of `xy` to the nearest point of the polyline `points` (its segments)."""
    a, d = points[:-1], np.diff(points, axis=0)
    rel = xy[:, None, :] - a[None]
    with np.errstate(invalid='ignore', divide='ignore'):   # a segment of no length: its start
        t = np.nan_to_num(np.clip((rel * d[None]).sum(-1) / (d * d).sum(-1)[None], 0.0, 1.0))
    return np.hypot(*(rel - t[..., None] * d[None]).transpose(2, 0, 1)).min(axis=1)


def left_along(points: np.ndarray, xy: np.ndarray) -> float:
    """The length of the polyline `points` from the point nearest `xy` to its end."""
    a, d = points[:-1], np.diff(points, axis=0)
    lengths = np.hypot(*d.T)
    t = np.clip(((xy - a) * d).sum(-1) / (lengths * lengths), 0.0, 1.0)
    k = int(np.argmin(np.hypot(*(xy - a - t[:, None] * d).T)))
    return float(lengths[k] * (1.0 - t[k]) + lengths[k + 1:].sum())


# ------------------------------------------------------------------------------------------------ simplified
def test_the_path_is_simplified_to_its_bends_and_a_grid_path_s_steps_are_not_kept() -> None:
    from fastep_ros.navigate_actions import PATH_TOLERANCE, simplified
    points = polyline(START, CORNER, END)
    assert [tuple(points[i]) for i in simplified(points, PATH_TOLERANCE)] == [START, CORNER, END]
    # A diagonal as a 5 cm grid draws it: steps of one cell, all within a cell of the line: its two ends only.
    stairs = np.array([(0.05 * ((k + 1) // 2), 0.05 * (k // 2)) for k in range(200)])
    assert list(simplified(stairs, PATH_TOLERANCE)) == [0, 199]
    # An arc of radius 2 m: poses every 0.9 m or so, each chord within the tolerance of the arc.
    angles = np.linspace(0.0, math.pi, 400)
    arc = np.column_stack([2.0 * np.cos(angles), 2.0 * np.sin(angles)])
    kept = simplified(arc, PATH_TOLERANCE)
    assert 5 < len(kept) < 15 and kept[0] == 0 and kept[-1] == 399
    assert distance_to(arc[kept], arc).max() <= PATH_TOLERANCE + 1e-9


# ------------------------------------------------------------------------------------------------ following
def test_a_path_with_a_bend_is_followed_along_its_shape_to_its_last_pose(context: Any) -> None:
    """The robot keeps to the path (within 0.2 m everywhere, through the bend, not the straight run 3 m from
    it), ends SUCCEEDED at its last pose without stopping on the way; distance_to_goal is the path left from the
    robot's projection, falling; speed what the base drives."""
    points = polyline(START, CORNER, END)
    node, base = robot(context)
    try:
        handle, done = send(node, base, 'follow_path', follow_goal(points))
        how, result = run_until(base, done)
        assert (how, result.error_code, result.error_msg) == ('succeeded', 0, '')
        driven = np.array(base.path)
        assert math.dist(driven[-1], END) <= 0.1
        off = distance_to(points, driven)
        assert off.max() < 0.2, (off.max(), driven[int(np.argmax(off))])
        assert distance_to(driven, np.array([CORNER])).min() < 0.2   # through the bend
        moving = np.array(base.speeds[5:])
        first_slow = int(np.argmax(moving < 0.3))
        assert math.dist(base.path[5 + first_slow], END) < 1.0, 'the robot slowed down on the way'

        told = [(i, float(f.distance_to_goal), float(f.speed)) for i, f in handle.feedback]
        assert len(told) > 200
        assert told[0][1] == pytest.approx(float(np.hypot(*np.diff(points, axis=0).T).sum()), abs=0.1)
        for i, distance, speed in told:
            assert distance == pytest.approx(left_along(points, driven[i]), abs=0.05), (i, distance)
            assert speed == pytest.approx(base.speeds[i - 1], abs=1e-6)   # the odometry's twist: last command
        distances = [d for _, d, _ in told]
        assert all(b <= a + 0.02 for a, b in zip(distances, distances[1:]))
        assert distances[-1] < 0.15
    finally:
        node.destroy_node()


def test_a_path_update_mid_way_keeps_the_robot_moving_and_ends_the_old_goal_with_0(context: Any) -> None:
    """Half-way along the first leg a new path (from where the robot is, a different bend): the old goal ends
    ABORTED with 0 (Nav2's SimpleActionServer), the robot drives on without slowing (a path update, not a new
    start), along the new path to its end."""
    node, base = robot(context)
    try:
        first, first_done = send(node, base, 'follow_path', follow_goal(polyline(START, CORNER, END)))
        while math.dist(base.xy, START) < 4.0:
            base.tick()
            assert not first_done.done()
        ticks = len(base.speeds)
        here = tuple(base.xy)
        update = polyline(here, (12.0, 10.0), (12.0, 4.0))
        goal = follow_goal(update)
        node.actions.on_goal_request(goal)   # as the action thread takes it: the path's points read there
        second, second_done = send(node, base, 'follow_path', goal)
        assert not node.actions._path_points   # taken by the executor with the goal
        how, result = first_done.result()
        assert (how, result.error_code) == ('aborted', 0) and 'path update' in result.error_msg
        how, result = run_until(base, second_done)
        assert (how, result.error_code) == ('succeeded', 0), result.error_msg
        after = np.array(base.speeds[ticks:ticks + 40])   # the 2 s after the update
        assert after.min() > 0.8, after.min()
        driven = np.array(base.path[ticks:])
        assert distance_to(update, driven).max() < 0.2
        assert math.dist(base.xy, (12.0, 4.0)) <= 0.1
    finally:
        node.destroy_node()


def test_a_path_in_odom_is_put_in_map_through_tf_when_it_comes(context: Any) -> None:
    """map -> odom a quarter turn and an offset: the path given in odom is driven where it lies in map."""
    from builtin_interfaces.msg import Time
    from tf2_msgs.msg import TFMessage

    from msg_tools import frames
    node, base = robot(context)
    try:
        node.tf.take_static(TFMessage(transforms=[frames.transform_stamped('map', 'odom', (10.0, 10.0, 0.5 * math.pi),
                                                                             Time())]))
        # In odom: (0, 8) -> (0, 0) -> (-6, 0); in map: (2, 10) -> (10, 10) -> (10, 4).
        in_odom = polyline((0.0, 8.0), (0.0, 0.0), (-6.0, 0.0))
        _, done = send(node, base, 'follow_path', follow_goal(in_odom, frame='odom'))
        how, result = run_until(base, done)
        assert (how, result.error_code) == ('succeeded', 0), result.error_msg
        assert distance_to(polyline(START, CORNER, (10.0, 4.0)), np.array(base.path)).max() < 0.2
        assert math.dist(base.xy, (10.0, 4.0)) <= 0.1
    finally:
        node.destroy_node()

# ------------------------------------------------------------------------------------------------ error codes
@pytest.mark.parametrize('case, words', [('empty', 'empty'), ('nan', 'not finite'), ('outside', 'outside the map')])
def test_a_path_that_cannot_be_driven_is_invalid_path_at_once(context: Any, case: str, words: str) -> None:
    points = np.zeros((0, 2)) if case == 'empty' else polyline(START, (10.0, 30.0) if case == 'outside' else CORNER)
    if case == 'nan':
        points[7, 1] = math.nan
    node, base = robot(context)
    try:
        _, done = send(node, base, 'follow_path', follow_goal(points))
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 103), (how, result.error_code, result.error_msg)
        assert words in result.error_msg
        for _ in range(10):
            base.tick()
        assert not any(node.last_command)
    finally:
        node.destroy_node()


def test_a_path_in_a_frame_tf_does_not_reach_is_tf_error(context: Any) -> None:
    node, base = robot(context)
    try:
        _, done = send(node, base, 'follow_path', follow_goal(polyline(START, CORNER), frame='nowhere'))
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 102) and "'nowhere'" in result.error_msg, result.error_msg
    finally:
        node.destroy_node()


def test_a_path_ending_inside_an_obstacle_is_no_valid_control(context: Any) -> None:
    node, base = robot(context, obstacles=[Circle(END, 1.0)])
    try:
        _, done = send(node, base, 'follow_path', follow_goal(polyline(START, CORNER, END)))
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 106), (how, result.error_code, result.error_msg)
        assert 'last pose' in result.error_msg
    finally:
        node.destroy_node()


def test_a_path_whose_end_is_walled_in_is_no_valid_control_on_the_way(context: Any) -> None:
    """The path's end walled in (reachable by no way round): ABORTED NO_VALID_CONTROL once the planner finds no
    way to the pose driven to."""
    from fastep_core.geometry import Segment
    corners = [(8.0, 14.0), (12.0, 14.0), (12.0, 18.0), (8.0, 18.0)]
    walls = [Segment(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    node, base = robot(context, obstacles=walls)
    try:
        _, done = send(node, base, 'follow_path', follow_goal(polyline(START, CORNER, END)))
        how, result = run_until(base, done)
        assert (how, result.error_code) == ('aborted', 106), (how, result.error_code, result.error_msg)
    finally:
        node.destroy_node()


def test_preemption_ends_the_goal_under_way_with_0_both_ways(context: Any) -> None:
    """navigate_to_pose preempted by follow_path, follow_path by navigate_to_pose, navigate_to_pose by
    navigate_to_pose: ABORTED with 0 (Nav2's SimpleActionServer: an empty result), error_msg saying why."""
    from nav2_msgs.action import NavigateToPose
    node, base = robot(context)
    try:
        _, to_pose = send(node, base, 'navigate_to_pose', NavigateToPose.Goal(pose=convert.point_to_pose_stamped(END)))
        for _ in range(10):
            base.tick()
        _, path = send(node, base, 'follow_path', follow_goal(polyline(tuple(base.xy), CORNER)))
        assert to_pose.result()[0] == 'aborted' and to_pose.result()[1].error_code == 0
        assert to_pose.result()[1].error_msg == 'preempted by a new goal'
        for _ in range(10):
            base.tick()
        _, again = send(node, base, 'navigate_to_pose', NavigateToPose.Goal(pose=convert.point_to_pose_stamped(END)))
        assert (path.result()[0], path.result()[1].error_code) == ('aborted', 0)
        _, last = send(node, base, 'navigate_to_pose', NavigateToPose.Goal(pose=convert.point_to_pose_stamped(START)))
        assert (again.result()[0], again.result()[1].error_code) == ('aborted', 0)
        how, result = run_until(base, last)
        assert (how, result.error_code) == ('succeeded', 0)
    finally:
        node.destroy_node()


def test_a_goal_that_preempts_and_is_refused_at_once_stops_the_robot(context: Any) -> None:
    """A path refused (empty) that preempted a goal under way: the robot brakes to a stop, not driving on to the
    goal nobody tracks any more (as Nav2's controller_server publishes a zero velocity)."""
    node, base = robot(context)
    try:
        _, running = send(node, base, 'follow_path', follow_goal(polyline(START, CORNER, END)))
        for _ in range(40):
            base.tick()
        assert base.speeds[-1] > 0.5
        _, refused = send(node, base, 'follow_path', follow_goal(np.zeros((0, 2))))
        assert running.result()[1].error_code == 0 and refused.result()[1].error_code == 103
        for _ in range(40):
            base.tick()
        assert base.speeds[-1] == 0.0
    finally:
        node.destroy_node()


def test_a_navigation_goal_in_a_frame_tf_does_not_reach_ends_with_0_as_nav2_s_navigators(context: Any) -> None:
    from nav2_msgs.action import NavigateThroughPoses, NavigateToPose
    node, base = robot(context)
    try:
        lost = convert.point_to_pose_stamped(END)
        lost.header.frame_id = 'nowhere'
        _, to_pose = send(node, base, 'navigate_to_pose', NavigateToPose.Goal(pose=lost))
        _, through = send(node, base, 'navigate_through_poses',
                          NavigateThroughPoses.Goal(poses=[convert.point_to_pose_stamped(CORNER), lost]))
        for done in (to_pose, through):
            how, result = done.result()
            assert (how, result.error_code) == ('aborted', 0) and "'nowhere'" in result.error_msg, result.error_msg
    finally:
        node.destroy_node()


def test_stop_on_failure_is_false_by_default_and_a_failed_waypoint_list_ends_with_0(context: Any) -> None:
    """stop_on_failure false (Nav2's stock nav2_params.yaml): a refused waypoint is missed, the goal SUCCEEDS; true:
    the list ends ABORTED with 0 (Nav2's waypoint follower sets no code), the waypoint missed with its own code."""
    from nav2_msgs.action import FollowWaypoints

    from fastep_ros.planner_params import PARAMETERS
    assert next(p for p in PARAMETERS if p.name == 'stop_on_failure').default is False
    waypoints = [convert.point_to_pose_stamped(p) for p in ((4.0, 10.0), (10.0, 10.0), (4.0, 12.0))]
    node, base = robot(context, obstacles=[Circle(CORNER, 1.0)])
    try:
        assert node.get_parameter('stop_on_failure').value is False
        _, done = send(node, base, 'follow_waypoints', FollowWaypoints.Goal(poses=waypoints))
        how, result = run_until(base, done)
        assert (how, result.error_code) == ('succeeded', 0)
        assert [(m.index, m.error_code) for m in result.missed_waypoints] == [(1, 206)]
    finally:
        node.destroy_node()
    node, base = robot(context, obstacles=[Circle(CORNER, 1.0)], stop_on_failure=True)
    try:
        _, done = send(node, base, 'follow_waypoints', FollowWaypoints.Goal(poses=waypoints))
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 0)
        assert [(m.index, m.error_code) for m in result.missed_waypoints] == [(1, 206)]
        assert 'waypoint 1' in result.error_msg and 'stop_on_failure' in result.error_msg
    finally:
        node.destroy_node()


def test_a_follow_path_goal_canceled_ends_canceled_and_the_robot_brakes_to_a_stop(context: Any) -> None:
    node, base = robot(context)
    try:
        handle, done = send(node, base, 'follow_path', follow_goal(polyline(START, CORNER, END)))
        for _ in range(40):
            base.tick()
        assert base.speeds[-1] > 0.5
        handle.is_cancel_requested = True   # as rclpy marks it once the cancel is accepted
        how, result = run_until(base, done, 5)
        assert (how, result.error_code) == ('canceled', 0)
        for _ in range(40):
            base.tick()
        assert base.speeds[-1] == 0.0 and math.dist(base.xy, CORNER) > 2.0
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ over DDS
def test_follow_path_is_served_over_dds_as_nav2_s_controller_server(graph: Any) -> None:
    """rclpy's ActionClient as BasicNavigator's followPath sends it (controller_id and goal_checker_id of Nav2's
    stock params, ignored): feedback, SUCCEEDED at the path's end."""
    from nav2_msgs.action import FollowPath
    from nav_msgs.msg import Odometry
    from rclpy.action import ActionClient

    from fastep_testing.graph import Helper, odom_xy, write
    world = ('name: follow_world\nworkspace: [0, 0, 20, 20]\nobstacles: []\n'
             'robots:\n  - {name: r1, model: point_mass, start: [2, 10], goal: [18, 10], radius: 0.5}\n')
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', world)))
    graph.start('plant', 'plant', '/r1', model='point_mass', start=[2.0, 10.0])
    graph.start('planner', 'planner', '/r1', model='point_mass', algorithm='fastep_route', robot_radius=0.5,
                max_speed=2.0, alpha1=1.0, alpha2=1.0)
    h = graph.helper = Helper(graph.domain)
    h.record_status('/r1')
    odom = h.record('/r1/odom', Odometry)
    h.wait_status('/r1', lambda s: s['message'] == 'idle', 60.0, 'the planner to know the world')
    client = ActionClient(h.node, FollowPath, '/r1/follow_path')
    h.spin_until(client.server_is_ready, 30.0, 'the follow_path server')
    feedback: list[Any] = []
    points = polyline(START, (6.0, 10.0), (6.0, 13.0))
    future = client.send_goal_async(FollowPath.Goal(path=path_msg(points), controller_id='FollowPath',
                                                    goal_checker_id='general_goal_checker'),
                                    feedback_callback=lambda msg: feedback.append(msg.feedback))
    h.spin_until(future.done, 30.0, 'the goal to be answered')
    handle = future.result()
    assert handle.accepted
    result = handle.get_result_async()
    h.spin_until(result.done, 90.0, lambda: graph.log('planner')[-2000:])
    assert (result.result().status, result.result().result.error_code) == (4, 0), result.result().result.error_msg
    # The odometry reaching this helper may be seconds behind the result at load: wait for it to show the robot
    # at the path's end (it stands there after SUCCEEDED; a robot elsewhere times this out).
    h.spin_until(lambda: math.dist(odom_xy(odom[-1]), (6.0, 13.0)) < 0.2, 30.0,
                 lambda: f'the odometry at the path\'s end (last {odom_xy(odom[-1])})')
    assert feedback and feedback[0].distance_to_goal > feedback[-1].distance_to_goal
    assert max(f.speed for f in feedback) > 0.5

