"""`initialpose` (issue "Nav2's own client", item 3): BasicNavigator.setInitialPose sets the planner's map -> odom
where it has no localizer of its own, at the pose's stamp through the odometry kept; a pose that is not one is
refused, and a planner with a localizer leaves it to that. In the test's process, on the test's clock: the node's
callbacks called directly (fastep_testing.in_process)."""

from __future__ import annotations

import math
from typing import Any

import pytest
from geometry_msgs.msg import PoseWithCovarianceStamped
from rclpy.serialization import deserialize_message

from fastep_ros.planner import PlannerNode
from fastep_testing.in_process import DT, planner_node
from msg_tools import convert

START = (1.0, 2.0, 0.0)   # base_link in odom (and in map, the identity, before an initial pose)


class Robot:
    """A diff-drive base whose odometry (in `odom`) the test sets, a tick at a time on the test's clock."""

    def __init__(self, node: PlannerNode) -> None:
        self.node, self.now, self.odom = node, 100.0, START
        node.now = lambda: self.now   # type: ignore[method-assign]  # the test's clock
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
        self.tick()

    def tick(self, odom: tuple[float, float, float] | None = None) -> float:
        """The odometry now (at `odom` if given), a control tick; its stamp."""
        self.now += DT
        self.odom = odom or self.odom
        self.node.inputs.on_odom(convert.state_to_odometry(self.odom, convert.seconds_to_stamp(self.now),
                                                           frame_id='odom'))
        self.node.on_control()
        return self.now

    def map_pose(self) -> tuple[float, float, float]:
        state, problem = self.node.inputs.state(self.now)
        assert state is not None, problem
        return float(state[0]), float(state[1]), float(state[2])


def initial_pose(x: float, y: float, yaw: float, stamp: float = 0.0, frame: str = 'map') -> PoseWithCovarianceStamped:
    """What BasicNavigator.setInitialPose publishes for a PoseStamped of this pose (stamp 0: unset)."""
    msg = PoseWithCovarianceStamped()
    msg.header.frame_id = frame
    if stamp > 0.0:
        msg.header.stamp = convert.seconds_to_stamp(stamp)
    msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
    msg.pose.pose.orientation.z, msg.pose.pose.orientation.w = math.sin(0.5 * yaw), math.cos(0.5 * yaw)
    return msg


def make(context: Any, **params: Any) -> tuple[PlannerNode, Robot]:
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model='diff_drive', robot_radius=0.3, **params)
    return node, Robot(node)


def status_values(node: PlannerNode) -> dict[str, Any]:
    """The key/values of the status the node publishes now."""
    from diagnostic_msgs.msg import DiagnosticStatus
    sent: list[bytes] = []
    publisher = node.reports.status_pub
    real = publisher.publish
    publisher.publish = sent.append
    try:
        node.reports.publish(force=True)
    finally:
        publisher.publish = real
    return convert.diagnostic_to_dict(deserialize_message(sent[-1], DiagnosticStatus))


def test_set_initial_pose_moves_the_planners_map_pose_of_the_robot_at_the_pose_s_stamp(context: Any) -> None:
    node, robot = make(context)
    try:
        assert robot.map_pose() == pytest.approx(START)   # no localizer: map -> odom the identity
        given_at = robot.tick()
        # The robot drives 1 m along odom's x after the stamp the pose was given for; the pose comes after that.
        robot.tick((2.0, 2.0, 0.0))
        node.inputs.initial_pose.on_initial_pose(initial_pose(5.0, 6.0, math.pi / 2, stamp=given_at))
        robot.tick()
        # base_link was at (5, 6) facing +y at the stamp; it has driven 1 m ahead since: (5, 7).
        assert robot.map_pose() == pytest.approx((5.0, 7.0, math.pi / 2), abs=1e-9)
        assert status_values(node)['initial_pose'].startswith('taken: (5.000, 6.000, 1.571)')
        # Unstamped (BasicNavigator with a PoseStamped left unstamped): the pose of now.
        node.inputs.initial_pose.on_initial_pose(initial_pose(8.0, 3.0, 0.0))
        robot.tick()
        assert robot.map_pose() == pytest.approx((8.0, 3.0, 0.0), abs=1e-9)
        robot.tick((3.0, 2.0, 0.0))   # and odometry moves it from there
        assert robot.map_pose() == pytest.approx((9.0, 3.0, 0.0), abs=1e-9)
    finally:
        node.destroy_node()


@pytest.mark.parametrize('pose, why', [
    (initial_pose(math.nan, 6.0, 0.0), 'not finite'),
    (initial_pose(5.0, 6.0, math.nan), 'not finite'),
    (initial_pose(40.0, 6.0, 0.0), 'outside the map'),
    (initial_pose(5.0, 6.0, 0.0, frame='odom'), "frame 'odom' is not the map frame"),
], ids=['nan position', 'nan heading', 'off the map', 'unknown frame'])
def test_an_initial_pose_that_is_not_one_is_refused_and_changes_nothing(context: Any, pose: Any, why: str) -> None:
    node, robot = make(context)
    try:
        node.inputs.initial_pose.on_initial_pose(initial_pose(5.0, 6.0, 0.0))   # one taken before
        robot.tick()
        before = robot.map_pose()
        node.inputs.initial_pose.on_initial_pose(pose)
        robot.tick()
        assert robot.map_pose() == pytest.approx(before)
        said = status_values(node)['initial_pose']
        assert said.startswith('refused: ') and why in said, said
    finally:
        node.destroy_node()


@pytest.mark.parametrize('localizer', [{'localization_topic': 'amcl_pose'}, {'map_to_odom_from_tf': True}],
                         ids=['localization_topic', 'map -> odom from TF'])
def test_with_a_localizer_initialpose_is_left_to_it_and_changes_nothing(context: Any,
                                                                        localizer: dict[str, Any]) -> None:
    node, robot = make(context, **localizer)
    try:
        before = node.inputs.state(robot.now)
        assert before[0] is None and 'waiting for localization' in before[1]   # none yet: the robot waits
        node.inputs.initial_pose.on_initial_pose(initial_pose(5.0, 6.0, 0.0))
        robot.tick()
        assert node.inputs.map_from_odom.transform is None
        state, problem = node.inputs.state(robot.now)
        assert state is None and 'waiting for localization' in problem
        assert node.inputs.initial_pose.left_said and 'initial_pose' not in status_values(node)
    finally:
        node.destroy_node()


def test_odometry_in_the_map_frame_has_nothing_for_an_initial_pose_to_correct(context: Any) -> None:
    node = planner_node(context, workspace=[0.0, 0.0, 20.0, 20.0], model='diff_drive', robot_radius=0.3)
    try:
        node.inputs.on_odom(convert.state_to_odometry(START, convert.seconds_to_stamp(1.0)))   # frame map
        node.inputs.initial_pose.on_initial_pose(initial_pose(5.0, 6.0, 0.0))
        assert node.inputs.map_from_odom.transform is None
        assert 'odometry is in the map frame' in node.inputs.initial_pose.status
    finally:
        node.destroy_node()
