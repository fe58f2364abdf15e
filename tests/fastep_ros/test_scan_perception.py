"""A planner that perceives with a LaserScan (`scan`): obstacles missing from its map, and movers, seen and avoided;
its belief on `tracked_obstacles`. The node is built in this process, its callbacks called directly, the robot
driven on the planner's own simulated clock, and each scan cast against the true world (fastep_core.sensing)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from rclpy.parameter import Parameter
from rclpy.time import Time
from visualization_msgs.msg import MarkerArray

from fastep_core.geometry import Circle
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_ros.planner import PlannerNode
from msg_tools import convert

SPEC = LaserSpec(range=8.0, fov=2 * math.pi, beams=360, noise=0.01)
KNOWN = Circle((10.0, 16.0), 1.0)     # on the map
UNKNOWN = Circle((12.0, 10.0), 1.5)   # not on the map, on the straight run from (3, 10) to (21, 10)


# Every control tick plans, so a handler's effect is seen at once (the planning thread: test_planning_thread.py).
SYNCHRONOUS = {'planning_thread': False}


def make(context: Any, **params: Any) -> PlannerNode:
    overrides = [Parameter('workspace', value=[0.0, 0.0, 24.0, 20.0]), Parameter('use_sim_time', value=True),
                 *(Parameter(k, value=v) for k, v in {**SYNCHRONOUS, **params}.items())]
    return PlannerNode(context=context, parameter_overrides=overrides)


def drive(node: PlannerNode, scans: bool, mover: tuple[np.ndarray, np.ndarray] | None = None,
          ticks: int = 1600) -> tuple[np.ndarray, float, list[MarkerArray]]:
    """Drive the point mass from (3, 10) to (21, 10); returns where it ended, the smallest gap it kept to the true
    obstacles (surface to body), and what it published on tracked_obstacles."""
    clock: Any = node.get_clock()
    published: list[MarkerArray] = []
    node.inputs.tracked_pub.publish = published.append  # type: ignore[method-assign]  # keep what the planner believes
    rng = np.random.default_rng(7)
    node.inputs.on_obstacles(convert.obstacles_to_marker_array([KNOWN]))
    state, dt, closest = np.array([3.0, 10.0]), 0.05, math.inf
    node.on_goal(convert.point_to_pose_stamped((21.0, 10.0)))
    for k in range(1, ticks):
        t = k * dt
        clock.set_ros_time_override(Time(nanoseconds=int(round(t * 1e9)), clock_type=clock.clock_type))
        node.inputs.on_odom(convert.state_to_odometry(state, convert.seconds_to_stamp(t)))
        circles, radii = [KNOWN.center, UNKNOWN.center], [KNOWN.radius, UNKNOWN.radius]
        if mover is not None:
            circles.append(tuple(mover[0] + mover[1] * t))
            radii.append(0.6)
        if scans:
            reading = scan(SPEC, (state[0], state[1], 0.0), rng, t, np.array(circles), np.array(radii))
            node.inputs.on_scan(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(t)))
        node.on_control()
        if node.reports.status()[1] == 'arrived':
            break
        state = state + node.last_command * dt
        gaps = np.hypot(*(np.array(circles) - state).T) - np.array(radii)
        closest = min(closest, float(gaps.min()) - 0.5)
    return state, closest, published


def test_an_obstacle_missing_from_the_map_is_seen_in_the_scans_and_avoided(context: Any) -> None:
    blind = make(context, algorithm='fastep_route')
    try:
        _, closest, _ = drive(blind, scans=False, ticks=600)
        assert closest < 0.0   # without scans it drives into the obstacle its map lacks
    finally:
        blind.destroy_node()
    node = make(context, algorithm='fastep_route')
    try:
        end, closest, published = drive(node, scans=True)
        assert node.reports.status()[1] == 'arrived' and np.hypot(*(end - (21.0, 10.0))) <= 0.1
        assert closest >= 0.0
        assert node.inputs.scan_perception.scans > 100
        believed = convert.marker_array_to_obstacles(published[-1])
        seen = [o for o in believed if isinstance(o, Circle)]
        assert any(math.dist(o.center, UNKNOWN.center) < 0.1 and abs(o.radius - UNKNOWN.radius) < 0.1 for o in seen)
    finally:
        node.destroy_node()


def test_a_mover_missing_from_the_map_is_tracked_and_shown(context: Any) -> None:
    node = make(context, algorithm='fastep')
    try:
        # Crossing the robot's run at x = 17, upwards at 0.4 m/s, on the robot's line at about t = 15 s.
        end, closest, published = drive(node, scans=True, mover=(np.array([17.0, 4.0]), np.array([0.0, 0.4])))
        assert node.reports.status()[1] == 'arrived' and closest >= 0.0
        tracks = [m for msg in published for m in msg.markers if m.ns == convert.TRACKS_NS]
        assert tracks, 'the mover was never tracked'
        arrows = [m for msg in published for m in msg.markers if m.ns == convert.TRACK_VELOCITIES_NS]
        vy = [a.points[1].y - a.points[0].y for a in arrows[-20:]]
        assert np.median(vy) == np.clip(np.median(vy), 0.3, 0.5)   # its velocity, about 0.4 m/s upwards
    finally:
        node.destroy_node()


def test_a_scan_that_is_not_one_is_ignored_with_a_reason(context: Any) -> None:
    node = make(context)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([KNOWN]))
        node.inputs.on_odom(convert.state_to_odometry([3.0, 10.0]))
        bad = convert.scan_to_laser_scan(scan(SPEC, (3.0, 10.0, 0.0), np.random.default_rng(0)))
        bad.angle_increment = 0.0
        node.inputs.on_scan(bad)
        assert node.inputs.scan_problem == 'scan ignored: laser scan angle_increment is 0'
        assert node.inputs.scan_perception.scans == 0
        good = convert.scan_to_laser_scan(scan(SPEC, (3.0, 10.0, 0.0), np.random.default_rng(0)))
        good.ranges[0] = math.nan   # one reading that is not a return: taken as none (REP-117)
        node.inputs.on_scan(good)
        assert node.inputs.scan_problem == '' and node.inputs.scan_perception.scans == 1
    finally:
        node.destroy_node()


def test_a_scanner_that_cannot_see_the_way_is_used_and_said_so(context: Any) -> None:
    """Issue "Faults", item 3, on the node: a user's narrow or sparse scanner is not refused (its returns still stop
    the robot: the guard reads them), but status says it cannot see the robot's way."""
    node = make(context)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([KNOWN]))
        node.inputs.on_odom(convert.state_to_odometry([3.0, 10.0]))
        narrow = LaserSpec(range=8.0, fov=0.01, beams=100, noise=0.0)
        node.inputs.on_scan(convert.scan_to_laser_scan(scan(narrow, (3.0, 10.0, 0.0), np.random.default_rng(0))))
        assert node.inputs.scan_problem.startswith("the scan cannot see the robot's way: its beams span 0.01 rad")
        assert node.inputs.scan_perception.scans == 1
        node.inputs.on_scan(convert.scan_to_laser_scan(scan(SPEC, (3.0, 10.0, 0.0), np.random.default_rng(0))))
        assert node.inputs.scan_problem == ''
    finally:
        node.destroy_node()


def placed_at(node: PlannerNode) -> list[tuple[float, ...]]:
    """The poses the node's scans are placed at from now on (filled as they are perceived)."""
    poses: list[tuple[float, ...]] = []
    update = node.inputs.scan_perception.update

    def kept(msg: Any, t: float, pose: Any, *args: Any) -> Any:
        poses.append(tuple(pose))
        return update(msg, t, pose, *args)
    node.inputs.scan_perception.update = kept   # type: ignore[method-assign]  # see the pose the scan is placed at
    return poses


def test_a_scan_is_placed_where_the_robot_was_at_its_stamp(context: Any) -> None:
    """Off lock step, a scan is perceived from the pose the odometry gives for its stamp (interpolated), not from
    where the robot is when it is perceived: a turning robot does not smear what it sees."""
    node = make(context, model='diff_drive', robot_radius=0.3, use_sim_time=False)
    poses = placed_at(node)
    try:
        node.inputs.on_obstacles(convert.obstacles_to_marker_array([KNOWN]))
        reading = scan(SPEC, (3.0, 10.0, 0.0), np.random.default_rng(0), 0.0, np.array([KNOWN.center]),
                       np.array([KNOWN.radius]))
        now = node.now()
        for stamp, state in ((now - 0.2, [2.0, 10.0, 0.0]), (now - 0.1, [4.0, 10.0, 1.0])):
            node.inputs.on_odom(convert.state_to_odometry(state, convert.seconds_to_stamp(stamp)))
        node.inputs.on_scan(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(now - 0.15)))
        assert poses and poses[-1] == pytest.approx((3.0, 10.0, 0.5), abs=1e-4)   # stamps are whole ns
        node.inputs.on_scan(convert.scan_to_laser_scan(reading, convert.seconds_to_stamp(now - 0.05)))
        assert poses[-1] == pytest.approx((4.0, 10.0, 1.0))   # newer than the odometry: the state now
    finally:
        node.destroy_node()


def test_a_scan_in_a_frame_of_its_own_needs_laser_mount_and_is_placed_at_it(context: Any) -> None:
    reading = scan(SPEC, (3.25, 10.0, 0.0), np.random.default_rng(0), 0.0, np.array([KNOWN.center]),
                   np.array([KNOWN.radius]))
    for mount in (None, [0.25, 0.0, 0.0]):
        extra = {} if mount is None else {'laser_mount': mount}
        node = make(context, model='diff_drive', robot_radius=0.3, use_sim_time=False, **extra)
        poses = placed_at(node)
        try:
            node.inputs.on_obstacles(convert.obstacles_to_marker_array([KNOWN]))
            node.inputs.on_odom(convert.state_to_odometry([3.0, 10.0, 0.0], convert.seconds_to_stamp(node.now())))
            stamp = convert.seconds_to_stamp(node.now())
            node.inputs.on_scan(convert.scan_to_laser_scan(reading, stamp, frame_id='laser'))
            if mount is None:
                problem = node.inputs.scan_problem
                assert not poses and "frame 'laser'" in problem and 'laser_mount' in problem
            else:
                assert poses[-1] == pytest.approx((3.25, 10.0, 0.0), abs=1e-6) and node.inputs.scan_problem == ''
        finally:
            node.destroy_node()
