"""msg_tools.convert: round trips between core types and ROS messages, and rejection of bad values."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from geometry_msgs.msg import Point, PoseStamped, Quaternion, Twist, TwistStamped
from nav_msgs.msg import OccupancyGrid, Odometry
from visualization_msgs.msg import Marker, MarkerArray

from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.kinematics import TractorTrailer
from fastep_core.kinematics.diff_drive import DiffDrive
from fastep_core.world import World
from msg_tools import convert

NAN = float('nan')


@pytest.mark.parametrize('t', [0.0, 1e-9, 0.05, 1.5, 123.456789012, 1e6 + 0.25])
def test_stamp_round_trip(t: float) -> None:
    stamp = convert.seconds_to_stamp(t)
    assert 0 <= stamp.nanosec < 1_000_000_000
    assert convert.stamp_to_seconds(stamp) == pytest.approx(t, abs=1e-9)
    assert convert.stamp_to_seconds(convert.seconds_to_clock(t).clock) == pytest.approx(t, abs=1e-9)


@pytest.mark.parametrize('t', [-1.0, NAN, math.inf])
def test_stamp_rejects_bad_times(t: float) -> None:
    with pytest.raises(ValueError):
        convert.seconds_to_stamp(t)


@pytest.mark.parametrize('yaw', [0.0, 0.3, -2.0, math.pi - 1e-9, -math.pi + 1e-9, 1.0e-7])
def test_yaw_round_trip(yaw: float) -> None:
    assert convert.quaternion_to_yaw(convert.yaw_to_quaternion(yaw)) == pytest.approx(yaw, abs=1e-9)


def test_yaw_wraps_and_normalises() -> None:
    q = convert.yaw_to_quaternion(3 * math.pi / 2)
    assert convert.quaternion_to_yaw(q) == pytest.approx(-math.pi / 2)
    scaled = Quaternion(x=0.0, y=0.0, z=2 * q.z, w=2 * q.w)
    assert convert.quaternion_to_yaw(scaled) == pytest.approx(-math.pi / 2)


@pytest.mark.parametrize('q', [Quaternion(x=0.0, y=0.0, z=NAN, w=1.0), Quaternion(x=0.0, y=0.0, z=0.0, w=0.0)])
def test_quaternion_rejects_bad_values(q: Quaternion) -> None:
    with pytest.raises(ValueError):
        convert.quaternion_to_yaw(q)
    with pytest.raises(ValueError):
        convert.yaw_to_quaternion(NAN)


def test_point_mass_odometry_round_trip() -> None:
    stamp = convert.seconds_to_stamp(2.5)
    msg = convert.state_to_odometry([3.0, -4.5], stamp, child_frame_id='r1/base_link', linear=(0.3, -0.4))
    assert msg.header.frame_id == 'map' and msg.child_frame_id == 'r1/base_link'
    assert convert.quaternion_to_yaw(msg.pose.pose.orientation) == 0.0
    np.testing.assert_array_equal(convert.odometry_to_state(msg), [3.0, -4.5])
    assert convert.odometry_velocity(msg) == pytest.approx((0.3, -0.4))
    assert convert.stamp_to_seconds(msg.header.stamp) == 2.5


def test_tractor_odometry_round_trip_and_map_velocity() -> None:
    state = [1.0, 2.0, math.pi / 2, math.pi / 3]
    msg = convert.state_to_odometry(state, linear=(1.0, 0.25), angular=0.5)
    np.testing.assert_allclose(convert.odometry_to_state(msg, 'tractor_trailer', trailer=state[3]), state)
    # The child-frame twist (1, 0.25) of a robot heading +y is (-0.25, 1) in the map.
    assert convert.odometry_velocity(msg) == pytest.approx((-0.25, 1.0))
    with pytest.raises(ValueError, match='trailer'):
        convert.odometry_to_state(msg, 'tractor_trailer')


def test_diff_drive_odometry_round_trip_and_map_velocity() -> None:
    """Issue 14 item 1: a diff_drive's yaw is its heading and its twist is (v, 0, omega) in the body frame;
    state_to_odometry refused 3 values and odometry_to_state knew no diff_drive."""
    model, state, command = DiffDrive(), np.array([1.0, 2.0, 2.2]), np.array([0.6, -0.9])
    msg = convert.state_to_odometry(state, linear=(command[0], 0.0), angular=command[1])
    np.testing.assert_allclose(convert.odometry_to_state(msg, 'diff_drive'), state)
    assert convert.odometry_velocity(msg) == pytest.approx(tuple(model.velocity(state, command)))
    assert msg.twist.twist.angular.z == command[1]


def test_odometry_velocity_matches_the_model() -> None:
    model = TractorTrailer(1.2, 1.0, 0.1)
    state, command = np.array([0.0, 0.0, 0.7, 0.5]), np.array([0.8, 0.4])
    msg = convert.state_to_odometry(state, linear=(command[0], 0.5 * model.length * command[1]),
                                    angular=command[1])
    assert convert.odometry_velocity(msg) == pytest.approx(tuple(model.velocity(state, command)))


@pytest.mark.parametrize('field', ['x', 'y'])
def test_odometry_with_nan_position_is_rejected(field: str) -> None:
    msg = Odometry()
    msg.pose.pose.orientation.w = 1.0
    setattr(msg.pose.pose.position, field, NAN)
    with pytest.raises(ValueError, match='not finite'):
        convert.odometry_to_state(msg)
    with pytest.raises(ValueError):
        convert.odometry_position(msg)


def test_state_to_odometry_rejects_nan_and_bad_sizes() -> None:
    with pytest.raises(ValueError):
        convert.state_to_odometry([NAN, 0.0])
    with pytest.raises(ValueError):
        convert.state_to_odometry([0.0, 0.0], linear=(math.inf, 0.0))
    with pytest.raises(ValueError):
        convert.state_to_odometry([0.0, 0.0, 0.0, 0.0, 0.0])


def test_trailer_pose_geometry() -> None:
    msg = convert.trailer_pose([5.0, 5.0, 0.0, math.pi / 2], trailer_length=2.0, hitch_offset=0.5)
    # hitch 0.5 behind the tractor (x), trailer axle 2 m behind the hitch along theta1 = +90 deg
    assert (msg.pose.position.x, msg.pose.position.y) == pytest.approx((4.5, 3.0))
    assert convert.trailer_yaw(msg) == pytest.approx(math.pi / 2)


def test_pose_and_path_round_trip() -> None:
    points = [(1.0, 2.0), (3.5, -1.25), (0.0, 0.0)]
    path = convert.waypoints_to_path(points, convert.seconds_to_stamp(1.0))
    assert path.header.frame_id == 'map' and all(p.header.frame_id == 'map' for p in path.poses)
    assert convert.path_to_waypoints(path) == points
    pose = convert.point_to_pose_stamped((NAN, 1.0))
    x, y = convert.pose_stamped_to_point(pose)  # passed on as is: the goal check refuses it
    assert math.isnan(x) and y == 1.0


@pytest.mark.parametrize('model,command,fields', [
    ('point_mass', (0.3, -0.7), ('linear.x', 'linear.y')),
    ('tractor_trailer', (0.9, 0.2), ('linear.x', 'angular.z')),
    ('diff_drive', (0.4, -1.1), ('linear.x', 'angular.z')),
])
def test_command_twist_round_trip(model: str, command: tuple[float, float], fields: tuple[str, str]) -> None:
    twist = convert.command_to_twist(command, model)
    for name, value in zip(fields, command):
        part, axis = name.split('.')
        assert getattr(getattr(twist, part), axis) == value
    np.testing.assert_array_equal(convert.twist_to_command(twist, model), command)
    stamped = TwistStamped()
    stamped.twist = twist
    np.testing.assert_array_equal(convert.twist_to_command(stamped, model), command)


def test_twist_with_nan_is_rejected() -> None:
    twist = Twist()
    twist.linear.x = NAN
    with pytest.raises(ValueError, match='not finite'):
        convert.twist_to_command(twist)
    twist = Twist()
    twist.angular.z = math.inf
    with pytest.raises(ValueError):
        convert.twist_to_command(twist, 'tractor_trailer')
    convert.twist_to_command(twist, 'point_mass')  # angular.z is not used by a point mass


def test_obstacles_round_trip() -> None:
    obstacles = [Circle((25.0, 25.0), 4.0), Segment((10.0, 30.0), (20.0, 30.0)), Circle((1.5, 2.5), 0.25),
                 Segment((0.0, 0.0), (3.0, 4.0))]
    msg = convert.obstacles_to_marker_array(obstacles, convert.seconds_to_stamp(0.0))
    kinds = [m.type for m in msg.markers if m.action == Marker.ADD]
    assert kinds.count(Marker.CYLINDER) == 2 and kinds.count(Marker.LINE_LIST) == 1
    assert all(m.header.frame_id == 'map' for m in msg.markers)
    back = convert.marker_array_to_obstacles(msg)
    assert sorted(map(repr, back)) == sorted(map(repr, obstacles))
    assert convert.marker_array_to_obstacles(convert.obstacles_to_marker_array([])) == []


def test_marker_actions_are_applied_in_order() -> None:
    first = convert.obstacles_to_marker_array([Circle((1.0, 1.0), 1.0)])
    second = convert.obstacles_to_marker_array([Circle((5.0, 5.0), 2.0)])
    joined = MarkerArray(markers=list(first.markers) + list(second.markers))  # DELETEALL in between
    assert convert.marker_array_to_obstacles(joined) == [Circle((5.0, 5.0), 2.0)]
    delete = Marker(ns='circles', id=0, action=Marker.DELETE)
    assert convert.marker_array_to_obstacles(MarkerArray(markers=list(second.markers) + [delete])) == []


@pytest.mark.parametrize('mutate', ['nan_centre', 'zero_radius', 'odd_points', 'nan_point'])
def test_bad_markers_are_rejected(mutate: str) -> None:
    msg = convert.obstacles_to_marker_array([Circle((1.0, 1.0), 1.0), Segment((0.0, 0.0), (1.0, 0.0))])
    circle = next(m for m in msg.markers if m.type == Marker.CYLINDER)
    lines = next(m for m in msg.markers if m.type == Marker.LINE_LIST)
    if mutate == 'nan_centre':
        circle.pose.position.x = NAN
    elif mutate == 'zero_radius':
        circle.scale.x = 0.0
    elif mutate == 'odd_points':
        lines.points.append(Point(x=5.0, y=5.0, z=0.0))
    else:
        lines.points[1].y = NAN
    with pytest.raises(ValueError):
        convert.marker_array_to_obstacles(msg)


def test_occupancy_grid() -> None:
    world = World.from_obstacles([0, 0, 10, 5], [Circle((2.0, 2.0), 1.0), Segment((6.0, 1.0), (9.0, 4.0))])
    grid = convert.world_to_occupancy_grid(world, 0.1, convert.seconds_to_stamp(3.0))
    assert (grid.info.width, grid.info.height) == (100, 50)
    assert grid.header.frame_id == 'map'
    assert convert.occupancy_grid_workspace(grid) == pytest.approx((0.0, 0.0, 10.0, 5.0))
    cells = np.array(grid.data, dtype=np.int8).reshape(grid.info.height, grid.info.width)
    assert set(np.unique(cells)) == {0, 100}

    def at(x: float, y: float) -> int:
        return int(cells[int(y / 0.1), int(x / 0.1)])
    assert at(2.0, 2.0) == 100 and at(2.0, 2.85) == 100 and at(2.0, 3.2) == 0
    assert at(7.52, 2.52) == 100 and at(7.0, 3.5) == 0 and at(0.5, 4.5) == 0
    # circle area ~ pi r^2 (+ the wall's cells)
    assert 0.9 * math.pi / 0.01 < (cells == 100).sum() < 1.1 * math.pi / 0.01 + 3 * math.sqrt(18) / 0.1
    # the wall has no gaps along its length
    for k in range(31):
        x = 6.0 + 0.1 * k
        y = 1.0 + 0.1 * k
        assert (cells[int(y / 0.1) - 1:int(y / 0.1) + 2, int(x / 0.1) - 1:int(x / 0.1) + 2] == 100).any()


def test_occupancy_grid_rounds_odd_sizes_up() -> None:
    world = World.from_obstacles([-1.0, 2.0, 1.25, 3.0], [])
    grid = convert.world_to_occupancy_grid(world, 0.5)
    assert (grid.info.width, grid.info.height) == (5, 2)
    assert convert.occupancy_grid_workspace(grid) == (-1.0, 2.0, 1.5, 3.0)
    with pytest.raises(ValueError):
        convert.world_to_occupancy_grid(world, 0.0)


def test_status_round_trip() -> None:
    msg = convert.make_status('/r1', 'avoiding', 'ok', {'reason': 'stepping around', 'activations': 3,
                                                        'waypoint': np.array([1.5, 2.0]), 'goal': None})
    assert msg.level == DiagnosticStatus.OK and msg.name == '/r1' and msg.message == 'avoiding'
    d = convert.diagnostic_to_dict(msg)
    assert d == {'name': '/r1', 'message': 'avoiding', 'level': 'ok', 'reason': 'stepping around',
                 'activations': '3', 'waypoint': '1.5,2', 'goal': ''}
    assert convert.diagnostic_to_dict(convert.make_status('x', 'failed', 'error'))['level'] == 'error'
    assert convert.make_status('x', 'stale', DiagnosticStatus.WARN).level == DiagnosticStatus.WARN


def test_pose_stamped_default_frame() -> None:
    msg = convert.point_to_pose_stamped((1.0, 2.0), yaw=0.5)
    assert isinstance(msg, PoseStamped) and msg.header.frame_id == 'map'
    assert convert.quaternion_to_yaw(msg.pose.orientation) == pytest.approx(0.5)


def test_occupancy_grid_workspace_survives_float32_resolution() -> None:
    grid = convert.world_to_occupancy_grid(World.from_obstacles([0, 0, 50, 30], []), 0.1)
    grid.info.resolution = float(np.float32(0.1))  # what arrives over DDS
    assert convert.occupancy_grid_workspace(grid) == (0.0, 0.0, 50.0, 30.0)


def _grid(cells: list[list[int]], resolution: float = 0.5, origin: tuple[float, float] = (1.0, 2.0)) -> OccupancyGrid:
    """A grid from rows of cell values, the first row at the bottom (y = origin y), as OccupancyGrid stores it."""
    msg = OccupancyGrid()
    msg.info.resolution = resolution
    msg.info.height, msg.info.width = len(cells), len(cells[0])
    msg.info.origin.position.x, msg.info.origin.position.y = origin
    msg.info.origin.orientation.w = 1.0
    msg.data = [v for row in cells for v in row]
    return msg


def _edges(segments: list[Segment]) -> set[tuple[tuple[float, float], ...]]:
    return {tuple(sorted(((float(s.start[0]), float(s.start[1])), (float(s.end[0]), float(s.end[1])))))
            for s in segments}


def test_occupancy_grid_obstacles_are_the_outline_of_the_occupied_cells() -> None:
    # One 2 x 1 block of occupied cells (100, and 70 >= 65), an unknown cell (-1) and a 64 (free) beside it.
    msg = _grid([[0, 0, 0, 0],
                 [0, 100, 70, -1],
                 [0, 0, 64, 0]])
    segments = convert.occupancy_grid_obstacles(msg)
    assert all(isinstance(s, Segment) for s in segments)
    x0, x1, y0, y1 = 1.5, 2.5, 2.5, 3.0   # the block: columns 1-2, row 1, 0.5 m cells from (1, 2)
    assert _edges(segments) == _edges([Segment((x0, y0), (x1, y0)), Segment((x0, y1), (x1, y1)),
                                       Segment((x0, y0), (x0, y1)), Segment((x1, y0), (x1, y1))])
    # A lower threshold takes the 64 in: an L of three cells, six sides.
    assert len(convert.occupancy_grid_obstacles(msg, occupied_threshold=60)) == 6


def test_occupancy_grid_obstacles_keep_every_free_cell_centre_outside_and_hold_back_nothing() -> None:
    world = World.from_obstacles([0, 0, 10, 8], [Circle((5.0, 4.0), 1.5), Segment((1.0, 1.0), (1.0, 6.0))])
    msg = convert.world_to_occupancy_grid(world, 0.25)
    segments = convert.occupancy_grid_obstacles(msg)
    occupied = np.asarray(msg.data).reshape(msg.info.height, msg.info.width) >= 65
    xs = 0.125 + 0.25 * np.arange(msg.info.width)
    ys = 0.125 + 0.25 * np.arange(msg.info.height)
    gx, gy = np.meshgrid(xs, ys)
    centres = np.stack([gx, gy], axis=-1)
    distance = Obstacles(segments).clearance(centres.reshape(-1, 2)).reshape(occupied.shape)
    # Every cell centre is half a cell from the nearest border at least, and the border of each occupied cell
    # next to a free one is there: its centre is exactly half a cell from the outline.
    assert distance.min() == pytest.approx(0.125)
    edge = occupied & ~np.all([np.roll(occupied, k, axis=a) for a in (0, 1) for k in (1, -1)], axis=0)
    assert np.allclose(distance[edge], 0.125)
    # Runs are merged: far fewer segments than border cell sides.
    assert len(segments) < int(edge.sum())


@pytest.mark.parametrize('change, words', [
    (lambda m: setattr(m, 'data', m.data[:-1]), 'map data has 11 cells, width x height is 4 x 3 = 12'),
    (lambda m: setattr(m.info, 'resolution', 0.0), 'resolution <= 0'),
    (lambda m: setattr(m.info.origin.orientation, 'z', 0.5), 'rotated map origin'),
])
def test_occupancy_grid_obstacles_refuse_a_bad_grid_in_one_line(change: Any, words: str) -> None:
    msg = _grid([[0, 0, 0, 0], [0, 100, 0, 0], [0, 0, 0, 0]])
    change(msg)
    with pytest.raises(ValueError, match=words):
        convert.occupancy_grid_obstacles(msg)


def test_movers_round_trip_through_markers_and_a_bad_one_is_one_line() -> None:
    from fastep_core.planning.others import OtherRobot
    movers = [OtherRobot('mover 2', (1.5, -2.0), (0.25, 0.5), 0.7, mover=True),
              OtherRobot('mover 5', (10.0, 3.0), (0.0, 0.0), 1.2, mover=True)]
    back = convert.marker_array_to_movers(convert.movers_to_marker_array(movers))
    assert [(m.name, m.radius, m.mover) for m in back] == [('mover 2', 0.7, True), ('mover 5', 1.2, True)]
    assert back[0].position == pytest.approx((1.5, -2.0)) and back[0].velocity == pytest.approx((0.25, 0.5))
    bad = convert.movers_to_marker_array(movers)
    bad.markers[1].scale.x = math.nan
    with pytest.raises(ValueError, match='mover marker movers/0'):
        convert.marker_array_to_movers(bad)


def test_laser_scans_round_trip_and_readings_that_are_no_measurement_become_nan() -> None:
    from fastep_core.sensing.laser import LaserSpec, scan
    spec = LaserSpec(range=8.0, fov=2 * math.pi, beams=36, noise=0.0)
    reading = scan(spec, (0.0, 0.0, 0.0), None, 0.0, np.array([[3.0, 0.0]]), np.array([1.0]))
    msg = convert.scan_to_laser_scan(reading)
    back = convert.laser_scan_to_scan(msg)
    assert back.angle_min == pytest.approx(reading.angle_min) and len(back.ranges) == 36
    ahead = int(np.argmin(np.abs(back.angles())))   # the beam along +x hits the circle 2 m away
    assert back.ranges[ahead] == pytest.approx(2.0) and np.isinf(back.ranges[(ahead + 18) % 36])
    msg.ranges[ahead], msg.ranges[ahead + 1], msg.range_min = math.nan, 0.01, 0.05
    msg.ranges[ahead + 2], msg.ranges[ahead + 3] = 9.0, -math.inf
    back = convert.laser_scan_to_scan(msg)
    # REP-117: NaN, below range_min, beyond range_max and -inf are no measurement; +inf is nothing within range.
    assert np.isnan(back.ranges[ahead:ahead + 4]).all() and np.isposinf(back.ranges[(ahead + 18) % 36])
    spec_back = convert.laser_spec(msg, 0.02)
    assert (spec_back.range, spec_back.beams, spec_back.noise) == (8.0, 36, 0.02)
    assert spec_back.fov == pytest.approx(2 * math.pi) and spec_back.full_turn
    sector = LaserSpec(range=5.0, fov=math.pi, beams=19, noise=0.0)   # both edges are beams: 18 increments
    msg = convert.scan_to_laser_scan(scan(sector, (0.0, 0.0, 0.0)))
    assert convert.laser_spec(msg, 0.0).fov == pytest.approx(math.pi)


def test_a_wall_on_a_border_between_cells_is_on_the_map() -> None:
    """office (the robot harness): the corridor wall at y = 9.0 lies on the border between two rows of 0.05 m
    cells, half a cell from both rows' centres give or take a rounding; it was on neither, missing from /map, and
    the planner drove through it."""
    world = World.from_obstacles([0, 0, 24, 16], [Segment((18.1, 9.0), (20.6, 9.0)), Segment((3.0, 7.0), (3.0, 9.0))])
    grid = convert.world_to_occupancy_grid(world, 0.05)
    mapped = World.from_obstacles([0, 0, 24, 16], convert.occupancy_grid_obstacles(grid))
    along = np.column_stack([np.linspace(18.2, 20.5, 24), np.full(24, 9.0)])
    assert (mapped.obstacles.clearance(along) <= 0.05).all()
    up = np.column_stack([np.full(20, 3.0), np.linspace(7.1, 8.9, 20)])
    assert (mapped.obstacles.clearance(up) <= 0.05).all()


def test_a_scan_of_more_beams_than_any_lidar_is_refused_before_it_is_read() -> None:
    from sensor_msgs.msg import LaserScan

    from fastep_core.sensing.laser import MAX_BEAMS
    msg = LaserScan(angle_min=-math.pi, angle_max=math.pi, angle_increment=2 * math.pi / (MAX_BEAMS + 1),
                    range_min=0.1, range_max=10.0, ranges=[1.0] * (MAX_BEAMS + 1))
    with pytest.raises(ValueError, match=f'laser scan has {MAX_BEAMS + 1} ranges, more than {MAX_BEAMS}'):
        convert.laser_scan_to_scan(msg)
    msg.ranges = [1.0] * MAX_BEAMS
    assert len(convert.laser_scan_to_scan(msg).ranges) == MAX_BEAMS
