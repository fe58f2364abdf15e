"""Nav2's behaviours served by the planner (issue "Nav2's own client", item 3): spin, backup and drive_on_heading end
where odometry shows the angle or distance asked, within the planner's limits, and end as Nav2's do on a collision
ahead, a time allowance run out, a bad input or a cancel. In the test's process, on the test's clock
(fastep_testing.in_process): the node's callbacks called directly, a base doing exactly what it is told."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from fastep_core.geometry import Segment
from fastep_testing.in_process import DT, planner_node
from fastep_testing.planning_gate import wait_for
from msg_tools import convert

pytest.importorskip('nav2_msgs.action', reason='nav2_msgs is built by make (interfaces/build.sh)')

LIMITS = {'max_speed': 0.5, 'max_reverse_speed': 0.3, 'max_turn_rate': 1.0, 'max_acceleration': 1.0,
          'max_turn_acceleration': 2.0}
START = (10.0, 10.0, 0.7)   # x, y, heading: off the map's axes, so "backward" is not -x by accident


class Handle:
    """What the behaviours read and call of rclpy's ServerGoalHandle: the request, cancel, feedback."""

    def __init__(self, request: Any) -> None:
        self.request, self.is_cancel_requested = request, False
        self.feedback: list[Any] = []

    def publish_feedback(self, feedback: Any) -> None:
        self.feedback.append(feedback)


class Base:
    """A base driving exactly the command it is told for DT each tick: a diff drive's (v, omega) along its arc, a
    point mass's map-frame (vx, vy) (heading 0, so body and map frame agree); odometry of where it is, each tick."""

    def __init__(self, node: Any, start: tuple[float, ...]) -> None:
        self.node, self.now, self.state = node, 100.0, np.array(start, dtype=float)
        self.twist = np.zeros(2)
        self.states, self.commands = [self.state.copy()], [np.zeros(2)]
        node.now = lambda: self.now   # the test's clock

    def tick(self) -> None:
        node = self.node
        count, passes = node.control_count, 0 if node.planning is None else node.planning.passes
        if len(self.state) == 3:
            odom = convert.state_to_odometry(self.state, convert.seconds_to_stamp(self.now),
                                             linear=(float(self.twist[0]), 0.0), angular=float(self.twist[1]))
        else:
            odom = convert.state_to_odometry(self.state, convert.seconds_to_stamp(self.now),
                                             linear=(float(self.twist[0]), float(self.twist[1])))
        node.inputs.on_odom(odom)
        node.on_control()
        command = self.twist = np.array(node.last_command[:2], dtype=float)
        if len(self.state) == 3:
            x, y, theta = self.state
            v, omega = command
            turn = omega * DT
            chord = v * DT * np.sinc(turn / (2.0 * math.pi))   # the exact arc
            self.state = np.array([x + chord * math.cos(theta + 0.5 * turn),
                                   y + chord * math.sin(theta + 0.5 * turn), theta + turn])
        else:
            self.state = self.state + DT * command
        self.states.append(self.state.copy())
        self.commands.append(command)
        self.now += DT
        if node.control_count > count:   # the pass on this tick's snapshot (one pass a snapshot: none waits)
            wait_for(lambda: node.planning is not None and node.planning.passes > passes and
                     node.planning.pass_started is None, 'the pass')

    def until(self, done: Any, most: int) -> int:
        for k in range(most):
            if done():
                return k
            self.tick()
        raise AssertionError(f'not within {most} ticks: status {self.node.reports.status()}')

    def settle(self, ticks: int = 20) -> None:
        """Ticks until the robot stands (the brake after a behaviour's end), then a few more."""
        self.until(lambda: not np.any(self.commands[-1]), 200)
        for _ in range(ticks):
            self.tick()


def make(context: Any, model: str = 'diff_drive', obstacles: tuple[Any, ...] = (), start: tuple[float, ...] = START,
         **params: Any) -> tuple[Any, Base]:
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model=model, algorithm='fastep',
                        robot_radius=0.3, **{**LIMITS, **params})
    base = Base(node, start)
    node.inputs.on_obstacles(convert.obstacles_to_marker_array(list(obstacles)))
    base.tick()
    return node, base


def send(node: Any, kind: str, goal: Any) -> tuple[Handle, Any]:
    """A goal handed over as the action thread hands it (taken on the next control tick)."""
    from rclpy.task import Future

    from fastep_ros.planner_threads import ActionGoal
    handle, done = Handle(goal), Future()
    node.actions.side.post(ActionGoal(kind, handle, done, node.actions.epoch))
    return handle, done


def duration(seconds: float) -> Any:
    from builtin_interfaces.msg import Duration
    return Duration(sec=int(seconds), nanosec=int(round((seconds - int(seconds)) * 1e9)))


def backup_goal(x: float, speed: float, allowance: float = 30.0, y: float = 0.0) -> Any:
    from geometry_msgs.msg import Point
    from nav2_msgs.action import BackUp
    return BackUp.Goal(target=Point(x=x, y=y), speed=speed, time_allowance=duration(allowance))


def within_limits(base: Base) -> None:
    """Every command sent within the planner's speed and acceleration limits (a tick's rounding allowed)."""
    commands = np.array(base.commands)
    v, omega = commands[:, 0], commands[:, 1]
    assert v.max() <= LIMITS['max_speed'] + 1e-9 and -v.min() <= LIMITS['max_reverse_speed'] + 1e-9
    assert np.abs(omega).max() <= LIMITS['max_turn_rate'] + 1e-9
    assert np.abs(np.diff(v)).max() <= LIMITS['max_acceleration'] * DT + 1e-9
    assert np.abs(np.diff(omega)).max() <= LIMITS['max_turn_acceleration'] * DT + 1e-9


def yaw_turned(base: Base) -> float:
    return float(base.state[2] - START[2])


# ------------------------------------------------------------------------------------------------ spin
@pytest.mark.parametrize('target', [math.pi / 2, -math.pi / 2])
def test_spin_turns_in_place_by_target_yaw_and_stops_there_within_the_turn_limits(context: Any, target: float) -> None:
    from nav2_msgs.action import Spin
    node, base = make(context)
    try:
        handle, done = send(node, 'spin', Spin.Goal(target_yaw=target, time_allowance=duration(10.0)))
        ticks = base.until(done.done, 400)
        how, result = done.result()
        assert (how, result.error_code) == ('succeeded', 0), result.error_msg
        base.settle()
        assert yaw_turned(base) == pytest.approx(target, abs=0.01)
        assert math.dist(base.state[:2], START[:2]) < 1e-9   # in place
        # At 1 rad/s after a ramp at 2 rad/s^2 and a stop: pi/2 in about 2.1 s, never much longer.
        assert ticks * DT < 2.6, ticks
        assert float(result.total_elapsed_time.sec) + result.total_elapsed_time.nanosec * 1e-9 == \
            pytest.approx(ticks * DT, abs=2 * DT)
        within_limits(base)
        turned = [f.angular_distance_traveled * math.copysign(1.0, target) for f in handle.feedback]
        assert len(turned) > 10 and all(b >= a - 1e-6 for a, b in zip(turned, turned[1:]))
        assert turned[0] < 0.2 and turned[-1] == pytest.approx(abs(target), abs=0.01)
    finally:
        node.destroy_node()


def test_a_point_mass_spin_is_refused_saying_it_has_no_heading(context: Any) -> None:
    from nav2_msgs.action import Spin
    node, base = make(context, model='point_mass', start=START[:2])
    try:
        _, done = send(node, 'spin', Spin.Goal(target_yaw=1.0))
        base.tick()
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', Spin.Result.UNKNOWN)
        assert 'point_mass' in result.error_msg and 'heading' in result.error_msg
        assert not np.any(base.commands[-1])
    finally:
        node.destroy_node()


def test_a_boxed_robot_spinning_by_a_wall_ends_collision_ahead_before_a_corner_reaches_it(context: Any) -> None:
    from nav2_msgs.action import Spin
    # A 1.0 x 0.4 box heading along x, its side 0.1 m from a wall along y = 9.7: turning swings a corner into it.
    wall = Segment((5.0, 9.7), (15.0, 9.7))
    node, base = make(context, obstacles=(wall,), start=(10.0, 10.0, 0.0),
                      footprint='[[0.5, 0.2], [0.5, -0.2], [-0.5, -0.2], [-0.5, 0.2]]')
    try:
        _, done = send(node, 'spin', Spin.Goal(target_yaw=math.pi / 2, time_allowance=duration(10.0)))
        base.until(done.done, 200)
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', Spin.Result.COLLISION_AHEAD), result.error_msg
        base.settle()
        corners = node.footprint.placed(*(np.array([s[i] for s in base.states]) for i in range(3)))
        assert float(corners[..., 1].min()) > 9.7   # never over the wall
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ backup
def test_backup_ends_the_distance_asked_behind_along_the_heading_at_the_speed_asked(context: Any) -> None:
    node, base = make(context)
    try:
        handle, done = send(node, 'backup', backup_goal(0.5, 0.2))
        base.until(done.done, 400)
        how, result = done.result()
        assert (how, result.error_code) == ('succeeded', 0), result.error_msg
        base.settle()
        moved = base.state[:2] - np.array(START[:2])
        heading = np.array([math.cos(START[2]), math.sin(START[2])])
        assert float(moved @ heading) == pytest.approx(-0.5, abs=0.01)              # behind ...
        assert abs(float(moved @ np.array([-heading[1], heading[0]]))) < 1e-9      # ... straight
        assert base.state[2] == pytest.approx(START[2], abs=1e-12)
        assert -np.array(base.commands)[:, 0].max() <= 0.0 and np.array(base.commands)[:, 0].min() == \
            pytest.approx(-0.2)   # at the speed asked, never forward
        within_limits(base)
        travelled = [f.distance_traveled for f in handle.feedback]
        assert len(travelled) > 10 and all(b >= a - 1e-9 for a, b in zip(travelled, travelled[1:]))
        assert travelled[-1] == pytest.approx(0.5, abs=0.01)
    finally:
        node.destroy_node()


def test_backup_faster_than_max_reverse_speed_backs_up_at_max_reverse_speed(context: Any) -> None:
    node, base = make(context)
    try:
        _, done = send(node, 'backup', backup_goal(-0.6, -2.0))   # signs ignored, as Nav2's
        base.until(done.done, 400)
        assert done.result()[0] == 'succeeded'
        assert np.array(base.commands)[:, 0].min() == pytest.approx(-LIMITS['max_reverse_speed'])
        base.settle()
        assert math.dist(base.state[:2], START[:2]) == pytest.approx(0.6, abs=0.01)
    finally:
        node.destroy_node()


def test_backup_toward_a_wall_ends_collision_ahead_and_stops_short_of_it(context: Any) -> None:
    from nav2_msgs.action import BackUp
    # A wall across the way 1.5 m behind the robot's centre (1.2 m from its disc); backing up 2 m would cross it.
    # The motion ahead is looked at SIMULATE_AHEAD (2 s, 0.6 m at 0.3 m/s): the robot backs up 0.6 m, then stops.
    heading = np.array([math.cos(START[2]), math.sin(START[2])])
    behind = np.array(START[:2]) - 1.5 * heading
    across = np.array([-heading[1], heading[0]])
    wall = Segment(tuple(behind - 2.0 * across), tuple(behind + 2.0 * across))
    node, base = make(context, obstacles=(wall,))
    try:
        _, done = send(node, 'backup', backup_goal(2.0, 0.3))
        base.until(done.done, 400)
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', BackUp.Result.COLLISION_AHEAD), result.error_msg
        assert 'collision ahead' in result.error_msg
        base.settle()
        gaps = [float(np.dot(behind - s[:2], -heading)) for s in base.states]   # the wall's distance behind
        assert 0.3 + 0.4 < min(gaps) < 0.3 + 0.7   # backed up, and stopped short of the wall by half a metre
        assert gaps[-1] == min(gaps)
        within_limits(base)
    finally:
        node.destroy_node()


def test_backup_toward_laser_returns_off_the_map_ends_collision_ahead_short_of_them(context: Any) -> None:
    from nav2_msgs.action import BackUp

    from fastep_core.planning.safety.guard import ScanReturns
    from fastep_core.planning.safety.guard_inputs import GuardInputs
    # Nothing on the map; the latest scan's returns (as perception leaves them) in a row 1.2 m behind the robot.
    heading = np.array([math.cos(START[2]), math.sin(START[2])])
    across = np.array([-heading[1], heading[0]])
    row = np.array(START[:2]) - 1.2 * heading + np.linspace(-1.0, 1.0, 41)[:, None] * across
    node, base = make(context)
    try:
        assert node.navigator is not None
        node.navigator.guard_inputs = GuardInputs(0.0, ScanReturns(row, np.array(START[:2]), 0.3))
        _, done = send(node, 'backup', backup_goal(2.0, 0.3))
        base.until(done.done, 400)
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', BackUp.Result.COLLISION_AHEAD), result.error_msg
        assert 'laser' in result.error_msg
        base.settle()
        gap = min(float(np.hypot(*(row - s[:2]).T).min()) for s in base.states)
        assert 0.3 + 0.4 < gap < 0.3 + 0.7, gap   # stopped half a metre short of the returns ...
        assert math.dist(base.state[:2], START[:2]) > 0.3   # ... having backed up (2 s ahead looked at: 0.6 m)
    finally:
        node.destroy_node()


def test_backup_past_its_time_allowance_ends_timeout_and_brakes(context: Any) -> None:
    from nav2_msgs.action import BackUp
    node, base = make(context)
    try:
        _, done = send(node, 'backup', backup_goal(2.0, 0.1, allowance=3.0))
        ticks = base.until(done.done, 400)
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', BackUp.Result.TIMEOUT), result.error_msg
        assert ticks * DT == pytest.approx(3.0, abs=3 * DT)
        base.settle()
        assert 0.2 < math.dist(base.state[:2], START[:2]) < 0.35   # 3 s at 0.1 m/s, then braked
        within_limits(base)
    finally:
        node.destroy_node()


def test_a_backup_whose_odometry_stops_ends_tf_error_saying_why(context: Any) -> None:
    from nav2_msgs.action import BackUp
    node, base = make(context)
    try:
        _, done = send(node, 'backup', backup_goal(2.0, 0.2))
        base.until(lambda: base.commands[-1][0] < -0.1, 100)
        for _ in range(int(2.0 / DT)):   # no odometry from here on: the planner holds the robot (odom_timeout)
            if done.done():
                break
            node.on_control()
            base.now += DT
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', BackUp.Result.TF_ERROR), result.error_msg
        assert 'odometry' in result.error_msg
    finally:
        node.destroy_node()


@pytest.mark.parametrize('kind, goal, code', [
    ('backup', dict(x=0.5, speed=0.2, y=0.1), 'INVALID_INPUT'),
    ('backup', dict(x=0.5, speed=0.0), 'INVALID_INPUT'),
    ('backup', dict(x=math.nan, speed=0.2), 'INVALID_INPUT'),
    ('backup', dict(x=0.5, speed=math.inf), 'INVALID_INPUT'),
    ('drive_on_heading', dict(x=0.5, speed=-0.2), 'INVALID_INPUT'),
    ('drive_on_heading', dict(x=0.5, speed=0.2, y=-1.0), 'INVALID_INPUT'),
    ('spin', dict(target_yaw=math.nan), 'UNKNOWN'),
])
def test_a_goal_that_cannot_be_driven_is_refused_at_once_with_nav2_s_code(context: Any, kind: str,
                                                                          goal: dict[str, float],
                                                                          code: str) -> None:
    from geometry_msgs.msg import Point
    from nav2_msgs.action import BackUp, DriveOnHeading, Spin
    action = {'backup': BackUp, 'drive_on_heading': DriveOnHeading, 'spin': Spin}[kind]
    request = action.Goal(target_yaw=goal['target_yaw']) if kind == 'spin' else \
        action.Goal(target=Point(x=goal['x'], y=goal.get('y', 0.0)), speed=goal['speed'])
    node, base = make(context)
    try:
        _, done = send(node, kind, request)
        base.tick()
        how, result = done.result()
        assert (how, result.error_code) == ('aborted', getattr(action.Result, code)), result.error_msg
        assert result.error_msg.startswith(f'{kind} refused: ')
        for _ in range(5):
            base.tick()
        assert not np.any(base.commands)   # never moved
    finally:
        node.destroy_node()


def test_a_canceled_backup_ends_canceled_and_brakes_to_a_stop_within_the_limits(context: Any) -> None:
    node, base = make(context)
    try:
        handle, done = send(node, 'backup', backup_goal(2.0, 0.3))
        base.until(lambda: base.commands[-1][0] <= -0.3, 100)   # at full speed
        handle.is_cancel_requested = True
        base.tick()
        how, result = done.result()
        assert (how, result.error_code) == ('canceled', 0)
        at = len(base.commands)
        base.settle()
        braking = np.array(base.commands[at - 1:])[:, 0]
        assert braking[0] == pytest.approx(-0.3) and braking[-1] == 0.0
        assert all(b >= a for a, b in zip(braking, braking[1:]))   # slowing, never again faster
        stopped = int(np.flatnonzero(braking == 0.0)[0])
        assert stopped <= round(0.3 / (LIMITS['max_acceleration'] * DT)) + 1   # at max_acceleration
        within_limits(base)
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ drive_on_heading
def test_drive_on_heading_drives_the_distance_asked_ahead(context: Any) -> None:
    from geometry_msgs.msg import Point
    from nav2_msgs.action import DriveOnHeading
    node, base = make(context)
    try:
        handle, done = send(node, 'drive_on_heading',
                            DriveOnHeading.Goal(target=Point(x=1.0), speed=0.4, time_allowance=duration(20.0)))
        base.until(done.done, 400)
        assert done.result()[0] == 'succeeded', done.result()[1].error_msg
        base.settle()
        moved = base.state[:2] - np.array(START[:2])
        assert float(moved @ np.array([math.cos(START[2]), math.sin(START[2])])) == pytest.approx(1.0, abs=0.01)
        assert handle.feedback[-1].distance_traveled == pytest.approx(1.0, abs=0.01)
        within_limits(base)
    finally:
        node.destroy_node()


def test_a_point_mass_backs_up_along_minus_x_of_its_base(context: Any) -> None:
    node, base = make(context, model='point_mass', start=START[:2])
    try:
        _, done = send(node, 'backup', backup_goal(0.5, 0.2))
        base.until(done.done, 400)
        assert done.result()[0] == 'succeeded', done.result()[1].error_msg
        base.settle()
        assert base.state[0] == pytest.approx(START[0] - 0.5, abs=0.01) and base.state[1] == pytest.approx(START[1])
    finally:
        node.destroy_node()


def test_without_a_planning_thread_the_control_tick_sends_the_behaviour_s_command_as_it_is(context: Any) -> None:
    # planning_thread false (as in lock step): the navigator is asked on the control tick, and the behaviour instead.
    node, base = make(context, planning_thread=False)
    try:
        assert node.planning is None
        _, done = send(node, 'backup', backup_goal(0.5, 0.2))
        base.until(done.done, 400)
        assert done.result()[0] == 'succeeded', done.result()[1].error_msg
        base.settle()
        assert math.dist(base.state[:2], START[:2]) == pytest.approx(0.5, abs=0.01)
        within_limits(base)
    finally:
        node.destroy_node()


# ------------------------------------------------------------------------------------------------ with navigation
def test_a_behaviour_preempts_the_navigation_goal_under_way_and_a_navigation_goal_ends_a_behaviour(
        context: Any) -> None:
    from nav2_msgs.action import NavigateToPose, Spin
    node, base = make(context)
    try:
        _, navigating = send(node, 'navigate_to_pose',
                             NavigateToPose.Goal(pose=convert.point_to_pose_stamped((16.0, 16.0))))
        base.until(lambda: abs(base.commands[-1][0]) > 0.2, 200)   # under way
        _, spinning = send(node, 'spin', Spin.Goal(target_yaw=3.0, time_allowance=duration(20.0)))
        base.tick()
        how, result = navigating.result()
        assert (how, result.error_code) == ('aborted', 0) and 'preempted by a spin goal' in result.error_msg
        base.until(lambda: abs(base.commands[-1][1]) > 0.5 and abs(base.commands[-1][0]) < 1e-9, 100)  # turning
        assert not spinning.done()
        _, again = send(node, 'navigate_to_pose', NavigateToPose.Goal(pose=convert.point_to_pose_stamped((16.0, 16.0))))
        base.tick()
        how, result = spinning.result()
        assert (how, result.error_code) == ('aborted', 0) and 'preempted by a navigate_to_pose goal' in result.error_msg
        base.until(again.done, 1000)
        assert again.result()[0] == 'succeeded'
        assert math.dist(base.state[:2], (16.0, 16.0)) < 0.3
    finally:
        node.destroy_node()
