"""Nav2's compute_path_to_pose and compute_path_through_poses served by the planner (issue "Nav2's own client", item
3): the exact shortest route over what the robot knows, as nav_msgs/Path, with Nav2 Jazzy's error codes, computed
off the control tick. In the test's process, on the test's clock (fastep_testing.in_process): the node's callbacks
called directly, a robot standing where its odometry says."""

from __future__ import annotations

import math
import threading
from typing import Any, Callable, Iterator

import numpy as np
import pytest

from fastep_core.geometry import Circle, Segment
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.world import World
from fastep_testing.in_process import DT, TickClock, planner_node
from fastep_testing.planning_gate import WAIT, wait_for
from msg_tools import convert

pytest.importorskip('nav2_msgs.action', reason='nav2_msgs is built by make (interfaces/build.sh)')

WORKSPACE = (0.0, 0.0, 20.0, 20.0)
RADIUS, MARGIN = 0.5, 0.2      # robot_radius, clearance_margin (the default): the route keeps 0.7 m where it can
START, GOAL = (2.0, 10.0), (18.0, 10.0)
CIRCLE = Circle((10.0, 10.0), 1.5)
TICKS = 400                    # 20 s of the test's clock, twice planning_timeout: every goal ends well within


class Handle:
    """What the path servers read of rclpy's ServerGoalHandle: the request and whether a cancel was asked."""

    def __init__(self, request: Any) -> None:
        self.request, self.is_cancel_requested = request, False

    def publish_feedback(self, feedback: Any) -> None:
        raise AssertionError('the path actions have no feedback')


class Robot:
    """A planner standing at `at` (a point mass; its odometry every tick) in WORKSPACE with `obstacles`."""

    def __init__(self, context: Any, obstacles: tuple[Any, ...] = (CIRCLE,), at: tuple[float, float] = START,
                 odometry: bool = True, **params: Any) -> None:
        params = {'model': 'point_mass', 'robot_radius': RADIUS, **params}
        self.node = node = planner_node(context, workspace=list(WORKSPACE), algorithm='fastep_route', **params)
        self.clock = TickClock(node, [*at, 0.0])
        self.odometry = odometry
        self.world = World(WORKSPACE, obstacles)
        node.inputs.on_obstacles(convert.obstacles_to_marker_array(list(obstacles)))
        if odometry:
            self.tick()
            wait_for(lambda: node.planning is not None and node.planning.plan is not None, 'the first pass')

    def paths(self, kind: str = 'compute_path_to_pose') -> Any:
        assert self.node.actions is not None
        return self.node.actions.handled_by[kind]

    def tick(self) -> None:
        if self.odometry:
            self.clock.tick()
        else:
            self.clock.now += DT
            self.node.on_control()

    def send(self, kind: str, goal: Any) -> tuple[Handle, Any]:
        """A goal of `kind` handed over to its server, as the action thread hands it: its handle and Future."""
        from rclpy.task import Future

        from fastep_ros.planner_threads import ActionGoal
        assert self.node.actions is not None
        handle, done = Handle(goal), Future()
        self.paths(kind).start(ActionGoal(kind, handle, done, self.node.actions.epoch), True)
        return handle, done

    def until(self, done: Any, most: int = TICKS) -> tuple[str, Any]:
        """Control ticks (each once the worker is idle: its speed is not the test's clock's) until `done`."""
        worker = self.paths().worker
        for _ in range(most):
            if done.done():
                how, result = done.result()
                return how, result
            wait_for(lambda: worker.idle, 'the path worker')
            self.tick()
        raise AssertionError(f'no result within {most} ticks')

    def ask(self, kind: str, goal: Any) -> tuple[str, Any]:
        return self.until(self.send(kind, goal)[1])


@pytest.fixture
def robot(context: Any) -> Iterator[Robot]:
    made = Robot(context)
    try:
        yield made
    finally:
        made.node.destroy_node()


def pose(x: float, y: float, yaw: float | None = None, frame: str = 'map') -> Any:
    msg = convert.point_to_pose_stamped((x, y), frame_id=frame)
    if yaw is not None:
        msg.pose.orientation.z, msg.pose.orientation.w = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
    return msg


def to_pose(goal: Any, start: Any | None = None) -> Any:
    from nav2_msgs.action import ComputePathToPose
    request = ComputePathToPose.Goal(goal=goal)
    if start is not None:
        request.start, request.use_start = start, True
    return request


def through(*goals: Any) -> Any:
    from nav2_msgs.action import ComputePathThroughPoses
    return ComputePathThroughPoses.Goal(goals=list(goals))


def points(path: Any) -> np.ndarray:
    return np.array([(p.pose.position.x, p.pose.position.y) for p in path.poses])


def headings(path: Any) -> np.ndarray:
    return np.array([convert.quaternion_to_yaw(p.pose.orientation) for p in path.poses])


def length(xy: np.ndarray) -> float:
    return float(np.hypot(*np.diff(xy, axis=0).T).sum())


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs(np.angle(np.exp(1j * (a - b))))


# ------------------------------------------------------------------------------------------------ the route
def test_the_path_round_a_circle_is_the_exact_shortest_route_keeping_the_clearance(robot: Robot) -> None:
    how, result = robot.ask('compute_path_to_pose', to_pose(pose(*GOAL, yaw=0.5 * math.pi)))
    assert (how, result.error_code, result.error_msg) == ('succeeded', 0, '')
    path = result.path
    assert path.header.frame_id == 'map' and {p.header.frame_id for p in path.poses} == {'map'}
    assert convert.stamp_to_seconds(path.header.stamp) == pytest.approx(100.0 + DT, abs=1e-6)   # when it came
    xy = points(path)
    assert xy[0] == pytest.approx(START) and xy[-1] == pytest.approx(GOAL)   # from where the robot stands
    best = shortest_path(robot.world, START, GOAL, RADIUS + MARGIN)
    assert best is not None and best.length > math.dist(START, GOAL) + 0.2   # round the circle
    assert length(xy) == pytest.approx(best.length, rel=1e-3)   # on the exact lines and arcs, 5 cm apart
    steps = np.hypot(*np.diff(xy, axis=0).T)
    assert steps.max() <= 0.05 + 1e-9 and steps.min() > 0.045
    assert float(robot.world.obstacles.clearance(xy).min()) >= RADIUS + MARGIN - 1e-6
    # Each pose heads along the path (to the next pose, within the 5 cm chord's turn), the last as the goal asked.
    along = np.arctan2(*np.diff(xy, axis=0).T[::-1])
    assert angle_between(headings(path)[:-1], along).max() < 0.05
    assert headings(path)[-1] == pytest.approx(0.5 * math.pi)
    assert 0.0 <= result.planning_time.sec + 1e-9 * result.planning_time.nanosec < 1.0


def test_a_path_starts_at_the_given_start_with_use_start(robot: Robot) -> None:
    how, result = robot.ask('compute_path_to_pose', to_pose(pose(*GOAL), start=pose(4.0, 4.0)))
    assert (how, result.error_code) == ('succeeded', 0)
    xy = points(result.path)
    assert xy[0] == pytest.approx((4.0, 4.0)) and xy[-1] == pytest.approx(GOAL)
    best = shortest_path(robot.world, (4.0, 4.0), GOAL, RADIUS + MARGIN)
    assert best is not None and length(xy) == pytest.approx(best.length, rel=1e-3)


def test_a_start_a_little_inside_the_radius_backs_out_as_the_route_does(robot: Robot) -> None:
    near = (10.0, 10.0 + 1.5 + RADIUS - 0.03)   # 3 cm inside the radius, less than exact_path.BACK_OUT
    how, result = robot.ask('compute_path_to_pose', to_pose(pose(*GOAL), start=pose(*near)))
    assert (how, result.error_code) == ('succeeded', 0)
    xy = points(result.path)
    assert xy[0] == pytest.approx(near) and xy[-1] == pytest.approx(GOAL)
    assert float(robot.world.obstacles.clearance(xy[3:]).min()) >= RADIUS - 1e-6   # out within a few poses


def test_a_footprint_is_planned_with_its_inscribed_radius_and_the_outline_margin(context: Any) -> None:
    from fastep_core.planning.outline import FOOTPRINT_MARGIN
    boxed = Robot(context, model='diff_drive', footprint='[[0.5, 0.2], [0.5, -0.2], [-0.5, -0.2], [-0.5, 0.2]]')
    try:
        how, result = boxed.ask('compute_path_to_pose', to_pose(pose(*GOAL)))
        assert (how, result.error_code) == ('succeeded', 0)
        kept = 0.2 + FOOTPRINT_MARGIN + MARGIN   # not the circumscribed 0.54 m
        xy = points(result.path)
        assert kept - 1e-6 <= float(boxed.world.obstacles.clearance(xy).min()) < kept + 0.01
        best = shortest_path(boxed.world, START, GOAL, kept)
        assert best is not None and length(xy) == pytest.approx(best.length, rel=1e-3)
    finally:
        boxed.node.destroy_node()


def test_a_goal_in_odom_is_put_in_the_map_frame_through_tf(robot: Robot) -> None:
    from builtin_interfaces.msg import Time
    from tf2_msgs.msg import TFMessage

    from msg_tools import frames
    robot.node.tf.take_static(TFMessage(transforms=[frames.transform_stamped('map', 'odom', (1.0, 2.0, 0.5 * math.pi),
                                                                             Time())]))
    # (8, -17) heading 0 in odom is (18, 10) heading pi/2 in map.
    how, result = robot.ask('compute_path_to_pose', to_pose(pose(8.0, -17.0, yaw=0.0, frame='odom')))
    assert (how, result.error_code) == ('succeeded', 0)
    assert points(result.path)[-1] == pytest.approx(GOAL) and headings(result.path)[-1] == pytest.approx(0.5 * math.pi)
    how, result = robot.ask('compute_path_to_pose', to_pose(pose(1.0, 1.0, frame='nowhere')))
    assert (how, result.error_code) == ('aborted', 202)
    assert result.error_msg == "goal frame 'nowhere': no transform to 'map' on /tf or /tf_static"


def test_the_path_through_poses_passes_each_pose_in_order(robot: Robot) -> None:
    via = [(10.0, 14.0), (18.0, 10.0), (18.0, 10.0), (4.0, 16.0)]   # a pose given twice: a leg of no length
    how, result = robot.ask('compute_path_through_poses', through(*(pose(*p) for p in via)))
    assert (how, result.error_code) == ('succeeded', 0)
    xy = points(result.path)
    hits = [int(np.flatnonzero(np.hypot(*(xy - p).T) < 1e-9)[0]) for p in via]
    assert hits == sorted(hits) and hits[0] > 0 and hits[-1] == len(xy) - 1
    assert len(np.flatnonzero(np.hypot(*(xy - via[1]).T) < 1e-9)) == 1   # each via pose once
    legs = [shortest_path(robot.world, a, b, RADIUS + MARGIN) for a, b in zip([START, *via], via)]
    assert length(xy) == pytest.approx(sum(leg.length for leg in legs if leg is not None), rel=1e-3)
    assert np.hypot(*np.diff(xy, axis=0).T).max() <= 0.05 + 1e-9


# ------------------------------------------------------------------------------------------------ refusals
WALLS = tuple(Segment(a, b) for a, b in [((14.0, 8.0), (18.0, 8.0)), ((18.0, 8.0), (18.0, 12.0)),
                                         ((18.0, 12.0), (14.0, 12.0)), ((14.0, 12.0), (14.0, 8.0))])


@pytest.mark.parametrize('kind, goal, code, words', [
    ('compute_path_to_pose', to_pose(pose(25.0, 10.0)), 204, 'goal (25, 10) is outside the map [0, 0, 20, 20]'),
    ('compute_path_to_pose', to_pose(pose(10.0, 10.0)), 206, 'goal (10, 10) is occupied: inside an obstacle'),
    ('compute_path_to_pose', to_pose(pose(10.0, 11.8)), 206, 'goal (10, 11.8) is occupied: 0.3 m from an obstacle'),
    ('compute_path_to_pose', to_pose(pose(*GOAL), start=pose(10.0, 11.0)), 205,
     'start (10, 11) is occupied: inside an obstacle'),
    ('compute_path_to_pose', to_pose(pose(*GOAL), start=pose(10.0, 11.9)), 205,
     'start (10, 11.9) is occupied: 0.4 m from an obstacle, robot radius 0.5 m'),
    ('compute_path_to_pose', to_pose(pose(*GOAL), start=pose(-1.0, 11.0)), 203, 'start (-1, 11) is outside the map'),
    ('compute_path_to_pose', to_pose(pose(16.0, 10.0)), 208, 'no valid path'),
    ('compute_path_to_pose', to_pose(pose(math.nan, 10.0)), 200, 'goal (nan, 10.0) is not finite'),
    ('compute_path_through_poses', through(), 309, 'no viapoints given'),
    ('compute_path_through_poses', through(pose(4.0, 4.0), pose(30.0, 4.0)), 304, 'goal 1 (30, 4) is outside'),
    ('compute_path_through_poses', through(pose(4.0, 4.0), pose(16.0, 10.0)), 308, 'no valid path'),
])
def test_a_path_that_cannot_be_ends_aborted_with_nav2_s_code_and_why(context: Any, kind: str, goal: Any, code: int,
                                                                     words: str) -> None:
    walled = Robot(context, obstacles=(CIRCLE, *WALLS))
    try:
        how, result = walled.ask(kind, goal)
        assert (how, result.error_code) == ('aborted', code), result.error_msg
        assert words in result.error_msg and '\n' not in result.error_msg
        assert not result.path.poses
    finally:
        walled.node.destroy_node()


def test_without_a_robot_pose_a_path_from_the_robot_ends_tf_error_at_once(context: Any) -> None:
    blind = Robot(context, odometry=False)
    try:
        handle, done = blind.send('compute_path_to_pose', to_pose(pose(*GOAL)))
        assert done.done()
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 202)
        assert result.error_msg == 'no robot pose to start from (waiting for odometry on /odom); give a start with ' \
                                   'use_start'
    finally:
        blind.node.destroy_node()


# ------------------------------------------------------------------------------------------------ off the tick
class Held:
    """The path computation held until the test releases it (or its goal ends): a path as slow as the test wants."""

    def __init__(self, paths: Any) -> None:
        self.release, self.entered, self.real = threading.Event(), threading.Event(), paths.compute
        paths.compute = self

    def __call__(self, request: Any, stop: Callable[[], bool]) -> Any:
        self.entered.set()
        while not (self.release.wait(0.002) or stop()):
            pass
        return self.real(request, stop)


def test_the_control_tick_runs_on_while_a_slow_path_is_computed(robot: Robot) -> None:
    held = Held(robot.paths())
    try:
        robot.node.on_goal(convert.point_to_pose_stamped((18.0, 4.0)))   # driving meanwhile
        handle, done = robot.send('compute_path_to_pose', to_pose(pose(*GOAL)))
        for _ in range(10):   # the new goal dropped the plan: the path waits for the next pass's world
            if held.entered.wait(0.5):
                break
            robot.tick()
        assert held.entered.is_set() and not done.done()
        commands = []
        for _ in range(40):   # 2 s of the test's clock, the path not done: each tick returns, commanding
            robot.tick()
            commands.append(float(np.hypot(*robot.node.last_command[:2])))
        assert not done.done() and robot.paths().worker.computing is not None
        assert min(commands[10:]) > 0.1, commands
        held.release.set()
        how, result = robot.until(done)
        assert (how, result.error_code) == ('succeeded', 0) and points(result.path)[-1] == pytest.approx(GOAL)
        assert result.planning_time.sec >= 2   # on the node's clock, from when the goal came
    finally:
        held.release.set()


def test_a_path_not_done_within_planning_timeout_ends_timeout(context: Any) -> None:
    slow = Robot(context, planning_timeout=1.0)
    held = Held(slow.paths())
    try:
        handle, done = slow.send('compute_path_through_poses', through(pose(*GOAL)))
        assert held.entered.wait(WAIT)
        ticks = 0
        while not done.done() and ticks < 100:
            slow.tick()
            ticks += 1
        assert 1.0 / DT - 2 <= ticks <= 1.0 / DT + 2, ticks
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', 307)
        assert result.error_msg.startswith('planning timed out: no path within 1.0') and \
            'planning_timeout 1 s' in result.error_msg
        wait_for(lambda: slow.paths().worker.idle, 'the worker drops it')   # stopped between legs
    finally:
        held.release.set()
        slow.node.destroy_node()


def test_a_canceled_goal_ends_canceled_and_the_next_one_is_computed(robot: Robot) -> None:
    held = Held(robot.paths())
    try:
        handle, done = robot.send('compute_path_to_pose', to_pose(pose(*GOAL)))
        assert held.entered.wait(WAIT)
        robot.tick()
        handle.is_cancel_requested = True
        robot.tick()
        assert done.done() and done.result()[0] == 'canceled' and done.result()[1].error_code == 0
        wait_for(lambda: robot.paths().worker.idle, 'the worker drops it')
        held.release.set()
        how, result = robot.ask('compute_path_to_pose', to_pose(pose(4.0, 16.0)))
        assert (how, result.error_code) == ('succeeded', 0) and points(result.path)[-1] == pytest.approx((4.0, 16.0))
    finally:
        held.release.set()


def test_a_goal_waiting_is_ended_by_a_newer_one_of_its_action(robot: Robot) -> None:
    """As Nav2's SimpleActionServer: one goal computed, one waiting an action; a newer one ends the waiting one."""
    held = Held(robot.paths())
    try:
        first = robot.send('compute_path_to_pose', to_pose(pose(*GOAL)))[1]
        assert held.entered.wait(WAIT)
        waiting = robot.send('compute_path_to_pose', to_pose(pose(4.0, 4.0)))[1]
        newest = robot.send('compute_path_to_pose', to_pose(pose(4.0, 16.0)))[1]
        assert waiting.done() and waiting.result()[0] == 'aborted' and waiting.result()[1].error_code == 0
        assert 'preempted by a newer goal' in waiting.result()[1].error_msg
        held.release.set()
        assert robot.until(first)[0] == 'succeeded'
        how, result = robot.until(newest)
        assert how == 'succeeded' and points(result.path)[-1] == pytest.approx((4.0, 16.0))
    finally:
        held.release.set()


def test_a_fault_in_the_computation_ends_the_goal_aborted_in_one_line(robot: Robot) -> None:
    def broken(request: Any, stop: Callable[[], bool]) -> Any:
        raise RuntimeError('the geometry broke\nsecond line')
    robot.paths().compute = broken
    how, result = robot.ask('compute_path_to_pose', to_pose(pose(*GOAL)))
    assert (how, result.error_code) == ('aborted', 200)
    assert result.error_msg == 'path computation failed: RuntimeError: the geometry broke'


def test_destroy_ends_a_goal_under_way_and_joins_the_worker(context: Any) -> None:
    robot = Robot(context)
    paths = robot.paths()
    held = Held(paths)
    try:
        handle, done = robot.send('compute_path_to_pose', to_pose(pose(*GOAL)))
        assert held.entered.wait(WAIT)
    finally:
        robot.node.destroy_node()   # never released: the goal's end stops the held computation
    assert done.done() and done.result()[0] == 'aborted'
    assert done.result()[1].error_msg == 'the planner is shutting down'
    assert not paths.worker._thread.is_alive()
