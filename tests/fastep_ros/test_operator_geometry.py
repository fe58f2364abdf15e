"""Geometry an operator or a localizer gives the planner, checked before it is used: a localization pose (and a map
-> odom from TF) that puts the robot off the map is refused with a status that says so, and the planner never
faults on it. Planners built in this process, their callbacks called directly, every tick planning in it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from builtin_interfaces.msg import Time as TimeMsg
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.parameter import Parameter
from rclpy.time import Time

from fastep_core.geometry import Circle
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_ros.planner import PlannerNode
from msg_tools import convert, frames

WAITING = 'waiting for localization on /r1/amcl_pose (map -> r1/odom): '
SPEC = LaserSpec(range=8.0, fov=2 * math.pi, beams=360, noise=0.01)
DT = 0.05


def planner(context: Any, **params: Any) -> PlannerNode:
    values = {'planning_thread': False, 'workspace': [0.0, 0.0, 20.0, 20.0], **params}
    node = PlannerNode(context=context, namespace='/r1',
                       parameter_overrides=[Parameter(k, value=v) for k, v in values.items()])
    node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
    node.on_goal(convert.point_to_pose_stamped((3.0, 12.0)))
    return node


def odometry(x: float, y: float, t: float = 0.0) -> Any:
    return convert.state_to_odometry([x, y], convert.seconds_to_stamp(t), frame_id='r1/odom',
                                     child_frame_id='r1/base_link')


def localization(x: float, y: float, t: float = 0.0) -> PoseWithCovarianceStamped:
    pose = PoseWithCovarianceStamped()
    pose.header.frame_id = 'map'
    pose.header.stamp = convert.seconds_to_stamp(t)
    pose.pose.pose.position.x, pose.pose.pose.position.y = x, y
    return pose


def frozen(context: Any, **params: Any) -> PlannerNode:
    """A planner on simulated time standing at 1 s: the odometry stamped then is not predicted forward."""
    node = planner(context, use_sim_time=True, **params)
    clock: Any = node.get_clock()
    clock.set_ros_time_override(Time(seconds=1, clock_type=clock.clock_type))
    return node


@pytest.mark.parametrize('x, y, said', [
    (1e300, 1e300, '(1e+300, 1e+300) is outside the map [0, 20] x [0, 20] by more than 1 m'),
    (21.5, 10.0, '(21.5, 10) is outside the map [0, 20] x [0, 20] by more than 1 m'),
    (10.0, -3.0, '(10, -3) is outside the map [0, 20] x [0, 20] by more than 1 m'),
])
def test_a_localization_pose_off_the_map_is_refused_and_status_says_so(context: Any, x: float, y: float,
                                                                       said: str) -> None:
    """Not used: with no pose taken yet the robot waits, naming the refusal; with one, it drives on that one and
    status warns (the planner is not told the robot is at (1e300, 1e300), so no plan fails or faults on it)."""
    node = frozen(context, localization_topic='amcl_pose')
    try:
        node.inputs.on_odom(odometry(1.0, 1.0, 1.0))
        node.inputs.on_localization(localization(x, y))
        node.on_control()
        assert node.reports.status() == (DiagnosticStatus.WARN, 'waiting', WAITING + 'localization pose refused: ' +
                                         said)
        assert node.inputs.map_from_odom.localizations == 0 and not node.last_command.any()
        node.inputs.on_localization(localization(3.0, 2.0))   # a usable pose: taken, the robot drives
        node.on_control()
        assert node.reports.status()[:2] == (DiagnosticStatus.OK, 'kinematic') and node.last_command.any()
        taken = node.inputs.map_from_odom.transform
        node.inputs.on_localization(localization(x, y))
        node.on_control()
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.WARN, 'kinematic')
        assert f'localization pose refused: {said} (the last pose taken is kept)' in reason
        assert node.inputs.map_from_odom.transform == taken and node.inputs.map_from_odom.localizations == 1
        state, _ = node.inputs.state(node.now())
        assert state is not None and state[:2] == pytest.approx([3.0, 2.0])
        node.inputs.on_localization(localization(3.0, 2.0))   # usable again: the warning goes
        node.on_control()
        assert node.reports.status()[:2] == (DiagnosticStatus.OK, 'kinematic')
    finally:
        node.destroy_node()


def test_a_localization_pose_just_inside_the_margin_is_taken_just_outside_refused(context: Any) -> None:
    """Within the margin (fastep_ros.limits.LOCALIZATION_MARGIN, 1 m) of the map (a robot at its edge) a pose is
    taken, a centimetre beyond it refused; before any map is known only an absurd distance (or a pose that is not
    finite) is refused."""
    node = planner(context, localization_topic='amcl_pose')
    try:
        node.inputs.on_odom(odometry(1.0, 1.0))
        node.inputs.on_localization(localization(20.99, 10.0))
        assert node.inputs.localization_problem == '' and node.inputs.map_from_odom.localizations == 1
        node.inputs.on_localization(localization(20.7, -0.7))   # 0.99 m from the corner
        assert node.inputs.localization_problem == '' and node.inputs.map_from_odom.localizations == 2
        node.inputs.on_localization(localization(21.01, 10.0))
        assert node.inputs.localization_problem == 'localization pose refused: (21.01, 10) is outside the map ' \
                                                   '[0, 20] x [0, 20] by more than 1 m'
        node.inputs.on_localization(localization(20.75, -0.75))   # 1.06 m from the corner
        assert node.inputs.localization_problem.startswith('localization pose refused: (20.75, -0.75)')
        assert node.inputs.map_from_odom.localizations == 2
    finally:
        node.destroy_node()
    node = PlannerNode(context=context, namespace='/r1', parameter_overrides=[
        Parameter('planning_thread', value=False), Parameter('localization_topic', value='amcl_pose')])
    try:   # no workspace and no /map yet
        node.inputs.on_odom(odometry(1.0, 1.0))
        node.inputs.on_localization(localization(500.0, -40.0))
        assert node.inputs.localization_problem == '' and node.inputs.map_from_odom.localizations == 1
        node.inputs.on_localization(localization(1e300, 1e300))
        assert node.inputs.localization_problem == 'localization pose refused: (1e+300, 1e+300) is 1.41421e+300 m ' \
                                                   'from the map frame\'s origin, farther than any map (100000 m)'
        node.inputs.on_localization(localization(math.nan, 1.0))
        assert node.inputs.localization_problem == 'localization pose ignored: position is not finite'
        assert node.inputs.map_from_odom.localizations == 1
    finally:
        node.destroy_node()


def test_map_to_odom_from_tf_that_puts_the_robot_off_the_map_is_refused(context: Any) -> None:
    """map -> odom composed with the newest odometry: base_link off the map is refused as a pose is, the last
    transform taken kept (none: the robot waits)."""
    tf_message = frames.tf_message_class()
    assert tf_message is not None
    node = frozen(context, map_to_odom_from_tf=True)

    def map_to_odom(pose: frames.Pose2D) -> None:
        node.tf.take(tf_message(transforms=[frames.transform_stamped('map', 'r1/odom', pose, TimeMsg())]))

    refused = 'map -> r1/odom from /tf refused: base_link at (1e+300, 1) is outside the map [0, 20] x [0, 20] by ' \
              'more than 1 m'
    try:
        node.inputs.on_odom(odometry(1.0, 1.0, 1.0))
        map_to_odom((1e300, 0.0, 0.0))
        node.on_control()
        assert node.reports.status() == (DiagnosticStatus.WARN, 'waiting',
                                         f'waiting for localization on /tf (map -> r1/odom): {refused}')
        assert not node.last_command.any()
        map_to_odom((2.0, 1.0, 0.0))   # usable: the robot is at (3, 2)
        node.on_control()
        assert node.reports.status()[:2] == (DiagnosticStatus.OK, 'kinematic') and node.last_command.any()
        map_to_odom((1e300, 0.0, 0.0))
        node.on_control()
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.WARN, 'kinematic')
        assert f'{refused} (the last pose taken is kept)' in reason
        state, _ = node.inputs.state(node.now())
        assert state is not None and state[:2] == pytest.approx([3.0, 2.0])
        map_to_odom((-1.2, 0.0, 0.0))   # the robot at (-0.2, 1): within the margin, taken
        node.on_control()
        assert node.reports.status()[:2] == (DiagnosticStatus.OK, 'kinematic')
        state, _ = node.inputs.state(node.now())
        assert state is not None and state[:2] == pytest.approx([-0.2, 1.0])
    finally:
        node.destroy_node()


def test_after_a_refused_pose_a_good_one_is_taken_and_the_robot_drives_to_its_goal(context: Any) -> None:
    """A first pose off the map: the robot holds (status says why, however many ticks); the next good pose is
    taken and the robot arrives at its goal."""
    node = planner(context, localization_topic='amcl_pose', use_sim_time=True)
    clock: Any = node.get_clock()
    state, messages = np.array([2.0, 2.0]), []
    try:
        for k in range(1, 801):
            t = k * DT
            clock.set_ros_time_override(Time(nanoseconds=int(round(t * 1e9)), clock_type=clock.clock_type))
            node.inputs.on_odom(odometry(float(state[0]), float(state[1]), t))
            if k == 1:
                node.inputs.on_localization(localization(1e300, 1e300, t))
            elif k == 20:
                node.inputs.on_localization(localization(float(state[0]), float(state[1]), t))
            node.on_control()
            status = node.reports.status()
            messages.append(status[1])
            if k < 20:
                assert status == (DiagnosticStatus.WARN, 'waiting', WAITING + 'localization pose refused: '
                                  '(1e+300, 1e+300) is outside the map [0, 20] x [0, 20] by more than 1 m')
                assert not node.last_command.any()
            if messages[-1] in ('arrived', 'failed'):
                break
            state = state + node.last_command * DT
        assert messages[-1] == 'arrived', node.reports.status()
        assert math.dist(state, (3.0, 12.0)) < 0.3
    finally:
        node.destroy_node()


def test_a_localizer_that_jumps_far_away_and_back_never_faults_the_planner(context: Any) -> None:
    """The finding: amcl_pose at (1e300, 1e300) while scans come (a simulated robot's pose tolerances 0, as
    fastep-launch sets them) placed the scans there; back at the true pose, the exact path met the walls seen from
    (1e300, 1e300), whose ends had rounded to one point: ZeroDivisionError, the goal failed. Now the far pose is
    refused, and the robot drives on to the goal."""
    node = planner(context, localization_topic='amcl_pose', use_sim_time=True, algorithm='fastep_route',
                   workspace=[0.0, 0.0, 24.0, 20.0], localization_tolerance=[0.0, 0.0], odometry_drift=[0.0, 0.0])
    node.on_goal(convert.point_to_pose_stamped((21.0, 10.0)))
    clock: Any = node.get_clock()
    rng = np.random.default_rng(7)
    box = Circle((12.0, 10.0), 1.5)   # not on the map: only the scans show it
    state, messages, closest = np.array([3.0, 10.0]), [], math.inf
    try:
        for k in range(1, 1601):
            t = k * DT
            clock.set_ros_time_override(Time(nanoseconds=int(round(t * 1e9)), clock_type=clock.clock_type))
            node.inputs.on_odom(odometry(float(state[0]), float(state[1]), t))
            if k in (1, 60):
                node.inputs.on_localization(localization(float(state[0]), float(state[1]), t))
            elif k == 20:
                node.inputs.on_localization(localization(1e300, 1e300, t))
            reading = scan(SPEC, (float(state[0]), float(state[1]), 0.0), rng, t, np.array([box.center]),
                           np.array([box.radius]))
            node.inputs.on_scan(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(t),
                                                           frame_id='r1/base_link'))
            node.on_control()
            messages.append(node.reports.status()[1])
            if messages[-1] in ('arrived', 'failed'):
                break
            state = state + node.last_command * DT
            closest = min(closest, math.dist(state, box.center) - box.radius - 0.5)
        assert messages[-1] == 'arrived', node.reports.status()
        assert 'failed' not in messages and closest > 0.0
    finally:
        node.destroy_node()
