"""`initialpose`: a pose of the robot given by hand (RViz's "2D Pose Estimate", BasicNavigator.setInitialPose).

geometry_msgs/PoseWithCovarianceStamped on `initialpose` in the planner's namespace, where nav2_simple_commander's
BasicNavigator publishes it (and Nav2's amcl reads it). A planner with no localizer of its own (no
localization_topic, map_to_odom_from_tf false: its map -> odom is the identity) takes it as a localization pose:
map -> odom is set so that base_link's map pose at the message's stamp (through the odometry kept:
frames.MapFromOdom; unstamped: now) is the pose given, and its covariance bounds the poses scans are placed at, as
a localization pose's does. It is refused as localization poses are (PlannerInputs.on_localization), with one
warning line: not finite, off the map (LOCALIZATION_MARGIN), a frame other than the map frame (amcl ignores those
too); and where the odometry is in the map frame (its poses are map poses: nothing to correct). With a localizer
(localization_topic set, or map -> odom from TF: amcl, slam_toolbox), initialpose is the localizer's to read: the
planner leaves it alone and says so once. Status' `initial_pose` says the last one taken (or refused).
"""

from __future__ import annotations

import math
from typing import Any

from geometry_msgs.msg import PoseWithCovarianceStamped

from fastep_ros.common import shown
from fastep_ros.planner_threads import Localized
from msg_tools import convert, frames

__all__ = ['INITIAL_POSE', 'InitialPose']

INITIAL_POSE = 'initialpose'   # relative: the planner's namespace, as BasicNavigator(namespace=...) publishes it
QUEUE = 10                     # reliable, volatile: BasicNavigator's publisher (RViz's matches it too)


class InitialPose:
    """The `initialpose` subscription of a planner's inputs (fastep_ros.planner_inputs.PlannerInputs), made with its
    other subscriptions; on the executor."""

    def __init__(self, inputs: Any) -> None:
        self.inputs = inputs
        node = inputs.node
        self.localizer = inputs.localization_topic or \
            (f'/tf ({node.frame_id} -> {inputs.odom_frame_id})' if inputs.map_to_odom_from_tf else '')
        self.status = ''        # what status' initial_pose says ('' before one came)
        self.left_said = False  # the line that says a localizer reads it, once
        self.sub = node.ros.create_subscription(PoseWithCovarianceStamped, INITIAL_POSE, self.on_initial_pose, QUEUE)

    def on_initial_pose(self, msg: PoseWithCovarianceStamped) -> None:
        inputs, node = self.inputs, self.inputs.node
        logger = node.ros.get_logger()
        if self.localizer:
            if not self.left_said:
                self.left_said = True
                logger.info(f'{self.sub.topic_name} left to the localizer (on {self.localizer}): map -> odom is its')
            return
        problem = self.problem(msg)
        if problem:
            self.status = f'refused: {problem}'
            logger.warning(f'{self.sub.topic_name} refused: {problem}', throttle_duration_sec=1.0)
            node.reports.changed()
            return
        x, y, yaw = frames.odometry_pose(msg)
        stamp = convert.stamp_to_seconds(msg.header.stamp)
        at = stamp if stamp > 0.0 else node.now()
        inputs.map_from_odom.add_localization(at, (x, y, yaw))
        inputs.localization_problem = ''
        # Its covariance bounds the poses scans are placed at from now on, and the odometry's drift starts again.
        node.change(Localized(tuple(msg.pose.covariance), inputs.localization_sigmas))
        self.status = f'taken: ({x:.3f}, {y:.3f}, {yaw:.3f}) at {at:.3f} s'
        logger.info(f'{self.sub.topic_name}: base_link at ({x:g}, {y:g}) heading {yaw:g} rad in {node.frame_id} at '
                    f'{at:.3f} s: map -> {inputs.odom_frame_id} set from it')
        node.reports.changed()

    def problem(self, msg: PoseWithCovarianceStamped) -> str:
        """Why an initial pose cannot be taken ('' when it can)."""
        inputs, node = self.inputs, self.inputs.node
        frame = msg.header.frame_id.lstrip('/')
        if frame not in ('', node.frame_id):
            return f'frame {shown(frame)} is not the map frame {node.frame_id!r}'
        odom = inputs.odom
        if odom is not None and odom.frame_id == node.frame_id:
            return f'the odometry is in the map frame {node.frame_id!r}: its poses are map poses, nothing to correct'
        try:
            x, y, _ = frames.odometry_pose(msg)
        except ValueError as exc:
            return f'pose {exc}'
        if not (math.isfinite(x) and math.isfinite(y)):
            return f'({x:g}, {y:g}) is not finite'
        return inputs.off_map((x, y))
