"""Scans placed by TF, and no scan ignored in silence (fastep_ros.sensors): a planner built in this process, its
callbacks called directly, the robot driven on the planner's own simulated clock, each scan cast against the
true world from where the laser truly is, in the laser's own frame `base_laser`."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.parameter import Parameter
from rclpy.time import Time
from tf2_msgs.msg import TFMessage

from fastep_core.geometry import Circle
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_ros.common import StartupError
from fastep_ros.planner import PlannerNode
from fastep_ros.sensors import ScanSource
from msg_tools import convert, frames

SPEC = LaserSpec(range=8.0, fov=2 * math.pi, beams=360, noise=0.01)
KNOWN = Circle((10.0, 16.0), 1.0)     # on the map
UNKNOWN = Circle((12.0, 10.0), 1.5)   # not on the map, on the straight run from (3, 10) to (21, 10)
DT = 0.05


def make(context: Any, **params: Any) -> PlannerNode:
    overrides = [Parameter('workspace', value=[0.0, 0.0, 24.0, 20.0]), Parameter('use_sim_time', value=True),
                 Parameter('planning_thread', value=False), Parameter('max_speed', value=1.0),
                 *(Parameter(k, value=v) for k, v in params.items())]
    return PlannerNode(context=context, parameter_overrides=overrides)


def static_tf(node: PlannerNode, mount: frames.Pose2D, child: str = 'base_laser') -> None:
    """base_link -> child on /tf_static, as robot_state_publisher sends it (handed to the node's listener)."""
    node.tf.take_static(TFMessage(transforms=[frames.transform_stamped('base_link', child, mount,
                                                                       convert.seconds_to_stamp(0.0))]))


def drive(node: PlannerNode, mount: frames.Pose2D, ticks: int, start: int = 1, state: np.ndarray | None = None,
          on_tick: Any = None) -> tuple[np.ndarray, float, list[float], list[str]]:
    """Drive the point mass toward (21, 10) from (3, 10) (or `state`), its laser at `mount` scanning in frame
    base_laser; returns where it ended, the smallest gap it kept to the true obstacles, its speed at each tick
    and the status messages."""
    clock: Any = node.get_clock()
    rng = np.random.default_rng(7)
    state = np.array([3.0, 10.0]) if state is None else state
    closest, speeds, messages = math.inf, [], []
    circles, radii = np.array([KNOWN.center, UNKNOWN.center]), np.array([KNOWN.radius, UNKNOWN.radius])
    for k in range(start, start + ticks):
        t = k * DT
        clock.set_ros_time_override(Time(nanoseconds=int(round(t * 1e9)), clock_type=clock.clock_type))
        if on_tick is not None:
            on_tick(k)
        node.inputs.on_odom(convert.state_to_odometry(state, convert.seconds_to_stamp(t)))
        laser = frames.compose((float(state[0]), float(state[1]), 0.0), mount)
        reading = scan(SPEC, laser, rng, t, circles, radii)
        node.inputs.on_scan(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(t), frame_id='base_laser'))
        node.on_control()
        messages.append(node.reports.status()[1])
        if messages[-1] == 'arrived':
            break
        speeds.append(float(np.hypot(*node.last_command)))
        state = state + node.last_command * DT
        closest = min(closest, float((np.hypot(*(circles - state).T) - radii).min()) - 0.5)
    return state, closest, speeds, messages


def start(node: PlannerNode) -> None:
    node.inputs.on_obstacles(convert.obstacles_to_marker_array([KNOWN]))
    node.on_goal(convert.point_to_pose_stamped((21.0, 10.0)))


@pytest.mark.parametrize('mount', [(0.0, 0.0, 0.0), (0.2, 0.0, 0.0)])
def test_scans_in_a_frame_of_their_own_are_placed_by_tf_static_and_the_box_is_gone_round(context: Any,
                                                                                        mount: frames.Pose2D) -> None:
    node = make(context, algorithm='fastep_route')
    try:
        static_tf(node, mount)
        start(node)
        end, closest, _, messages = drive(node, mount, 1600)
        assert messages[-1] == 'arrived' and np.hypot(*(end - (21.0, 10.0))) <= 0.1
        assert closest >= 0.0 and 'blind' not in messages
        assert node.inputs.scan_problem == '' and node.inputs.scan_perception.scans > 100
    finally:
        node.destroy_node()


def test_scans_that_tf_cannot_place_hold_the_robot_saying_why_until_the_transform_comes(context: Any) -> None:
    node = make(context, algorithm='fastep_route')
    try:
        start(node)
        _, _, speeds, messages = drive(node, (0.2, 0.0, 0.0), 100)
        assert max(speeds) == 0.0 and set(messages) == {'blind'}   # held still from the first scan on
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.ERROR, 'blind')
        assert reason.startswith("scan frame 'base_laser': no transform from 'base_link' to 'base_laser'")
        scan_task = next(task for task in node.reports.diagnostic_tasks() if task.task == 'scan')
        assert scan_task.level == DiagnosticStatus.ERROR and 'base_laser' in scan_task.values['reason']
        # While the first scans wait (scan_timeout after the first was heard) it said WARN, not OK.
        static_tf(node, (0.2, 0.0, 0.0))
        end, closest, _, messages = drive(node, (0.2, 0.0, 0.0), 1600, start=101)
        assert messages[-1] == 'arrived' and closest >= 0.0 and np.hypot(*(end - (21.0, 10.0))) <= 0.1
    finally:
        node.destroy_node()


def test_the_first_scans_waiting_for_their_transform_are_a_warning(context: Any) -> None:
    node = make(context, scan_timeout=2.0)
    try:
        start(node)
        _, _, speeds, messages = drive(node, (0.0, 0.0, 0.0), 10)
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.WARN, 'blind') and reason.startswith('waiting for a usable scan')
        assert max(speeds) == 0.0
    finally:
        node.destroy_node()


def test_a_tf_mount_outside_the_robot_is_not_used_and_an_error(context: Any) -> None:
    node = make(context, robot_radius=0.22, scan_timeout=0.5)
    try:
        static_tf(node, (3.0, 0.0, 0.0))
        start(node)
        _, _, speeds, _ = drive(node, (3.0, 0.0, 0.0), 30)
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.ERROR, 'blind') and max(speeds) == 0.0
        assert 'TF puts the laser 3 m from base_link, outside the robot (robot_radius 0.22 m + 0.1 m)' in reason
        assert node.inputs.scan_perception.scans == 0
    finally:
        node.destroy_node()


def test_a_laser_mount_outside_the_robot_is_refused_at_start_in_one_line(context: Any) -> None:
    with pytest.raises(StartupError) as error:
        make(context, robot_radius=0.22, laser_mount=[3.0, 0.0, 0.0])
    assert str(error.value) == 'parameter laser_mount [3.0, 0.0, 0.0] puts the laser 3 m from base_link, outside ' \
                               'the robot (robot_radius 0.22 m + 0.1 m)'
    with pytest.raises(StartupError, match='scan_mode must be one of auto, required, ignored'):
        make(context, scan_mode='sometimes')


def test_the_laser_mount_parameter_overrides_tf(context: Any) -> None:
    node = make(context, algorithm='fastep_route', laser_mount=[0.2, 0.0, 0.0])
    try:
        static_tf(node, (0.0, 0.0, 0.0))   # what TF says is not taken: laser_mount is
        start(node)
        end, closest, _, messages = drive(node, (0.2, 0.0, 0.0), 1600)
        assert messages[-1] == 'arrived' and closest >= 0.0
    finally:
        node.destroy_node()


def test_scans_that_stop_coming_or_are_not_scans_hold_the_robot(context: Any) -> None:
    node = make(context, algorithm='fastep_route', scan_timeout=0.5)
    try:
        static_tf(node, (0.0, 0.0, 0.0))
        start(node)
        state, _, speeds, _ = drive(node, (0.0, 0.0, 0.0), 40)
        assert speeds[-1] > 0.5   # under way on its scans

        take = node.inputs.scans.take

        def broken(msg: Any, now: float) -> Any:   # every scan from now on is not one
            msg.angle_increment = 0.0
            return take(msg, now)
        node.inputs.scans.take = broken   # type: ignore[method-assign]  # a stand-in: every scan malformed
        state, _, speeds, _ = drive(node, (0.0, 0.0, 0.0), 60, start=41, state=state)
        level, message, reason = node.reports.status()
        assert (level, message) == (DiagnosticStatus.ERROR, 'blind')
        assert reason == 'scan ignored: laser scan angle_increment is 0; held still'
        assert speeds[-1] == 0.0
    finally:
        node.destroy_node()


def test_without_scans_nothing_changes_and_ignored_scans_are_not_followed(context: Any) -> None:
    node = make(context)
    try:
        assert node.inputs.scans.hold(node.now()) == (DiagnosticStatus.OK, '')   # never heard: the map alone
        assert node.inputs.scan_sub is not None
    finally:
        node.destroy_node()
    node = make(context, scan_mode='ignored')
    try:
        assert node.inputs.scan_sub is None
        node.inputs.on_scan(convert.scan_to_laser_scan(scan(SPEC, (3.0, 10.0, 0.0), np.random.default_rng(0)),
                                                       frame_id='base_laser'))
        assert node.inputs.scans.hold(node.now()) == (DiagnosticStatus.OK, '')
    finally:
        node.destroy_node()


def test_required_scans_that_never_come_hold_the_robot_warn_then_error() -> None:
    values = {'scan_mode': 'required', 'laser_mount': None, 'robot_radius': 0.3, 'transform_tolerance': 0.3,
              'scan_timeout': 1.0}
    source = ScanSource(values, 'base_link', '/r1/scan', 10.0, lambda *_: frames.IDENTITY)
    assert source.hold(10.5) == (DiagnosticStatus.WARN, 'no scan on /r1/scan (scan_mode required): held still')
    assert source.hold(11.5)[0] == DiagnosticStatus.ERROR


def test_a_scan_waits_for_the_transform_of_its_stamp_within_the_tolerance() -> None:
    """A moving mount on /tf: the scan of 1.0 s is placed once /tf has a transform at or after its stamp."""
    from msg_tools.tf_buffer import TfBuffer
    buffer = TfBuffer()
    values = {'scan_mode': 'auto', 'laser_mount': None, 'robot_radius': 0.3, 'transform_tolerance': 0.3,
              'scan_timeout': 1.0}
    source = ScanSource(values, 'base_link', 'scan', 0.0, buffer.lookup_at)
    buffer.add([frames.transform_stamped('base_link', 'turret', (0.1, 0.0, 0.0), convert.seconds_to_stamp(0.9))])
    msg = convert.scan_to_laser_scan(scan(SPEC, (0.0, 0.0, 0.0), np.random.default_rng(0)),
                                     convert.seconds_to_stamp(1.0), frame_id='turret')
    assert source.take(msg, 1.0) is None and 'not yet available' in source.waiting and source.pending
    assert source.problem == ''   # waiting is not given up
    buffer.add([frames.transform_stamped('base_link', 'turret', (0.1, 0.0, 0.2), convert.seconds_to_stamp(1.1))])
    placed = source.retry(1.1)
    assert placed is not None and placed.mount == pytest.approx((0.1, 0.0, 0.1)) and source.waiting == ''
    late = convert.scan_to_laser_scan(scan(SPEC, (0.0, 0.0, 0.0), np.random.default_rng(0)),
                                      convert.seconds_to_stamp(1.5), frame_id='turret')
    assert source.take(late, 1.5) is None and source.retry(1.7) is None and source.pending
    assert source.retry(1.9) is None and not source.pending and 'not yet available' in source.problem   # given up


def test_a_localization_that_only_sends_poses_it_cannot_take_is_waited_for_naming_why(context: Any) -> None:
    from geometry_msgs.msg import PoseWithCovarianceStamped
    node = PlannerNode(context=context, namespace='/r1', parameter_overrides=[
        Parameter('planning_thread', value=False), Parameter('localization_topic', value='amcl_pose'),
        Parameter('workspace', value=[0.0, 0.0, 24.0, 20.0])])
    try:
        start(node)
        node.inputs.on_odom(convert.state_to_odometry([3.0, 10.0], frame_id='r1/odom', child_frame_id='r1/base_link'))
        pose = PoseWithCovarianceStamped()
        pose.header.frame_id = 'r1/odom'   # not a map pose
        node.inputs.on_localization(pose)
        node.on_control()
        assert node.reports.status() == (DiagnosticStatus.WARN, 'waiting', (
            "waiting for localization on /r1/amcl_pose (map -> r1/odom): localization pose ignored: frame "
            "'r1/odom' is not the map frame 'map'"))
        assert not node.last_command.any()
    finally:
        node.destroy_node()


def test_a_moving_mount_on_tf_is_taken_at_each_scans_stamp(context: Any) -> None:
    """A turret on /tf (base_link -> turret turning at 1 rad/s, 0.1 m ahead): each scan is placed at the turret's
    pose of its stamp, the transform of a later stamp waited for."""
    node = make(context, model='diff_drive', robot_radius=0.3)
    clock: Any = node.get_clock()
    poses: list[tuple[float, ...]] = []
    update = node.inputs.scan_perception.update

    def kept(msg: Any, t: float, pose: Any, *args: Any) -> Any:
        poses.append(tuple(pose))
        return update(msg, t, pose, *args)
    node.inputs.scan_perception.update = kept   # type: ignore[method-assign]  # a stand-in recording the poses
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([KNOWN]))
        reading = scan(SPEC, (3.0, 10.0, 0.0), np.random.default_rng(0))
        for k in range(1, 6):
            t = k * DT
            clock.set_ros_time_override(Time(nanoseconds=int(round(t * 1e9)), clock_type=clock.clock_type))
            node.inputs.on_odom(convert.state_to_odometry([3.0, 10.0, 0.0], convert.seconds_to_stamp(t)))
            node.tf.take(TFMessage(transforms=[frames.transform_stamped(
                'base_link', 'turret', (0.1, 0.0, t - DT), convert.seconds_to_stamp(t - DT))]))
            node.inputs.on_scan(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(t - 0.5 * DT),
                                                           frame_id='turret'))
        # Each scan waits for the turret's next transform (it comes with the next tick), the last still waits.
        assert len(poses) == 4
        for k, pose in enumerate(poses, start=1):
            assert pose == pytest.approx((3.1, 10.0, (k - 0.5) * DT), abs=1e-6)   # the turret's yaw at the stamp
        assert node.inputs.scans.pending and 'not yet available' in node.inputs.scans.waiting
    finally:
        node.destroy_node()


def test_a_scan_stamped_far_from_the_clock_is_not_used(context: Any) -> None:
    node = make(context)
    try:
        clock: Any = node.get_clock()
        clock.set_ros_time_override(Time(nanoseconds=10 * 10**9, clock_type=clock.clock_type))
        start(node)
        node.inputs.on_odom(convert.state_to_odometry([3.0, 10.0], convert.seconds_to_stamp(10.0)))
        node.inputs.on_scan(convert.scan_to_laser_scan(scan(SPEC, (3.0, 10.0, 0.0), np.random.default_rng(0)),
                                                       convert.seconds_to_stamp(6.8)))
        assert node.inputs.scan_problem == 'scan ignored: stamped 3.20 s ago (scan_timeout 1 s)'
        assert node.inputs.scan_perception.scans == 0
    finally:
        node.destroy_node()


def test_scans_at_20_hz_that_tf_never_places_are_given_up_after_the_tolerance() -> None:
    """More scans wait than are kept (PENDING): the wait is timed from the first scan not placed, not per scan."""
    from msg_tools.tf_buffer import TfBuffer
    values = {'scan_mode': 'auto', 'laser_mount': None, 'robot_radius': 0.3, 'transform_tolerance': 0.32,
              'scan_timeout': 1.0}
    source = ScanSource(values, 'base_link', 'scan', 0.0, TfBuffer().lookup_at)
    reading = scan(SPEC, (0.0, 0.0, 0.0), np.random.default_rng(0))
    for k in range(1, 9):   # 0.05 .. 0.40 s
        t = k * DT
        source.take(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(t), frame_id='base_laser'), t)
        assert (source.problem == '') == (t - DT < 0.32), t   # the first came at 0.05 s
    assert "'base_laser'" in source.problem and source.hold(1.2)[0] == DiagnosticStatus.ERROR


def test_a_footprint_sets_how_far_the_robot_reaches() -> None:
    from fastep_ros.sensors import check_laser_mount, robot_reach
    pytest.importorskip('fastep_core.footprint')
    values = {'robot_radius': 0.22, 'footprint': '[[0.25, 0.2], [-0.25, 0.2], [-0.25, -0.2], [0.25, -0.2]]'}
    reach, what = robot_reach(values)
    assert reach == pytest.approx(math.hypot(0.25, 0.2)) and what == "the footprint's circumscribed radius"
    assert check_laser_mount([0.4, 0.0, 0.0], values) == (0.4, 0.0, 0.0)   # within 0.32 + 0.1 m
    with pytest.raises(StartupError, match="outside the robot \\(the footprint's circumscribed radius 0.32"):
        check_laser_mount([0.5, 0.0, 0.0], values)
