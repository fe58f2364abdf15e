"""Pure conversions between fastep_core types and ROS 2 messages (no node, no DDS needed).

Conventions (msg_tools/interface.py, REP-103/105; the frames in docs/frames.md):
- goals, waypoints, plans and obstacles are in the `map` frame; odometry and trailer poses in the robot's odom
  frame; the functions take the frame names they are given;
- a point mass has yaw 0; its command and odometry twist are (vx, vy) in linear.x, linear.y;
- a tractor-trailer's yaw is the tractor heading theta0; its command is (v, omega) = (linear.x, angular.z); its
  odometry twist is the reference point's velocity in the tractor frame, linear.y = L * omega / 2 (eq. 13);
  the trailer heading theta1 travels on `trailer_pose`;
- a diff_drive's command and odometry twist are (v, omega) = (linear.x, angular.z) in the body frame.

The map (OccupancyGrid) conversions are msg_tools/occupancy_grid.py's, named here too. Functions that read
messages raise ValueError (with a one-line reason) for values that are not finite or malformed; the nodes turn
that into a status message instead of crashing.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Iterable, Mapping, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, PoseStamped, Quaternion, Twist, TwistStamped
from nav_msgs.msg import Odometry, Path
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from visualization_msgs.msg import Marker, MarkerArray

from fastep_core.geometry import Circle, Obstacle, Segment
from fastep_core.planning.others import OtherRobot
from fastep_core.sensing.laser import FULL_TURN_TOLERANCE, MAX_BEAMS, LaserSpec, Scan
from msg_tools.occupancy_grid import (
    DEFAULT_RESOLUTION,
    MAX_GRID_CELLS,
    OCCUPIED_THRESHOLD,
    GridCopy,
    GridWalls,
    grid_copy,
    grid_resolution,
    grid_shape,
    grid_walls,
    occupancy_grid_lookup,
    occupancy_grid_obstacles,
    occupancy_grid_workspace,
    world_to_occupancy_grid,
)

if TYPE_CHECKING:   # perception (scipy) is imported only by nodes that perceive
    from fastep_core.perception.belief import Belief

__all__ = [
    'DEFAULT_RESOLUTION', 'LEVELS', 'MAX_GRID_CELLS', 'MOVERS_NS', 'MOVER_VELOCITIES_NS', 'OCCUPIED_THRESHOLD',
    'TRACKS_NS', 'TRACK_VELOCITIES_NS', 'GridCopy', 'GridWalls', 'belief_to_marker_array', 'command_to_twist',
    'command_twist_values', 'diagnostic_to_dict',
    'grid_copy', 'grid_resolution', 'grid_shape', 'grid_walls', 'laser_scan_to_scan', 'laser_spec', 'make_status',
    'marker_array_to_movers',
    'marker_array_to_obstacles', 'movers_to_marker_array', 'obstacles_to_marker_array', 'occupancy_grid_lookup',
    'occupancy_grid_obstacles', 'occupancy_grid_workspace', 'odometry_position', 'odometry_to_state',
    'odometry_velocity', 'path_to_waypoints', 'point_to_pose_stamped', 'pose_stamped_to_point', 'pose_to_state',
    'quaternion_to_yaw', 'scan_to_laser_scan', 'seconds_to_clock', 'seconds_to_stamp', 'stamp_to_seconds',
    'state_to_odometry', 'status_values', 'trailer_pose', 'trailer_yaw', 'twist_in_map', 'twist_to_command',
    'twist_values_to_command', 'waypoints_to_path', 'world_to_occupancy_grid', 'yaw_of', 'yaw_quaternion',
    'yaw_to_quaternion',
]

CIRCLES_NS = 'circles'
TRACKS_NS = 'tracks'                    # tracked_obstacles: a planner's tracked movers
TRACK_VELOCITIES_NS = 'track_velocities'   # ... and their velocities
MOVERS_NS = 'movers'                    # /movers: the known movers as the map knows them
MOVER_VELOCITIES_NS = 'mover_velocities'   # ... and their velocities
SEGMENTS_NS = 'segments'
LEVELS = {'ok': DiagnosticStatus.OK, 'warn': DiagnosticStatus.WARN, 'error': DiagnosticStatus.ERROR,
          'stale': DiagnosticStatus.STALE}
Vector = Sequence[float] | np.ndarray   # a state or command: a list, tuple or numpy array of numbers


def _finite(values: Iterable[float], what: str) -> None:
    for v in values:
        if not math.isfinite(v):
            raise ValueError(f'{what} is not finite')


# ------------------------------------------------------------------------------------------------- time

def seconds_to_stamp(t: float) -> Time:
    """Seconds (>= 0, finite) to builtin_interfaces/Time, nanoseconds rounded."""
    if not math.isfinite(t) or t < 0.0:
        raise ValueError(f'time {t!r} must be finite and >= 0')
    total = int(round(t * 1e9))
    return Time(sec=total // 1_000_000_000, nanosec=total % 1_000_000_000)


def stamp_to_seconds(stamp: Time) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def seconds_to_clock(t: float) -> Clock:
    return Clock(clock=seconds_to_stamp(t))


# ------------------------------------------------------------------------------------------------- angles

def yaw_to_quaternion(yaw: float) -> Quaternion:
    """Rotation about z by yaw (radians, counter-clockwise)."""
    x, y, z, w = yaw_quaternion(yaw)
    return Quaternion(x=x, y=y, z=z, w=w)


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of yaw_to_quaternion's message; ValueError if not finite."""
    if not math.isfinite(yaw):
        raise ValueError(f'yaw {yaw!r} is not finite')
    return 0.0, 0.0, math.sin(0.5 * yaw), math.cos(0.5 * yaw)


def quaternion_to_yaw(q: Quaternion) -> float:
    """Yaw in (-pi, pi] of a quaternion (normalised first); ValueError if not finite or of zero length."""
    return yaw_of(q.x, q.y, q.z, q.w)


def yaw_of(qx: float, qy: float, qz: float, qw: float) -> float:
    """quaternion_to_yaw of the quaternion (qx, qy, qz, qw)."""
    _finite((qx, qy, qz, qw), 'orientation')
    norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    if norm < 1e-9:
        raise ValueError('orientation quaternion has zero length')
    x, y, z, w = qx / norm, qy / norm, qz / norm, qw / norm
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


# ------------------------------------------------------------------------------------------------- poses

def point_to_pose_stamped(point: Sequence[float], stamp: Time | None = None, frame_id: str = 'map',
                          yaw: float = 0.0) -> PoseStamped:
    """A PoseStamped at (x, y) with the given yaw. Values are copied as they are (NaN stays NaN)."""
    msg = PoseStamped()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.pose.position = Point(x=float(point[0]), y=float(point[1]), z=0.0)
    msg.pose.orientation = yaw_to_quaternion(yaw)
    return msg


def pose_stamped_to_point(msg: PoseStamped) -> tuple[float, float]:
    """(x, y) of a pose, as it is: the caller decides what a NaN means (a goal check refuses it)."""
    return float(msg.pose.position.x), float(msg.pose.position.y)


def waypoints_to_path(points: Iterable[Sequence[float]], stamp: Time | None = None,
                      frame_id: str = 'map') -> Path:
    msg = Path()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.poses = [point_to_pose_stamped(p, stamp, frame_id) for p in points]
    return msg


def path_to_waypoints(msg: Path) -> list[tuple[float, float]]:
    return [pose_stamped_to_point(p) for p in msg.poses]


# ------------------------------------------------------------------------------------------------- odometry

def state_to_odometry(state: Vector, stamp: Time | None = None, *, child_frame_id: str = 'base_link',
                      frame_id: str = 'map', linear: Sequence[float] = (0.0, 0.0),
                      angular: float = 0.0) -> Odometry:
    """Odometry of a model state: (x, y) (point mass, yaw 0), (x, y, theta) (diff_drive, yaw theta) or
    (x, y, theta0, theta1) (tractor-trailer, yaw theta0).

    `linear` (x, y) and `angular` (z) are the twist in the child frame (see the module docstring).
    """
    s = [float(v) for v in state]
    if len(s) not in (2, 3, 4):
        raise ValueError(f'state must have 2, 3 or 4 values, got {len(s)}')
    _finite(s, 'state')
    _finite((*linear, angular), 'velocity')
    msg = Odometry()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.child_frame_id = child_frame_id
    msg.pose.pose.position = Point(x=s[0], y=s[1], z=0.0)
    msg.pose.pose.orientation = yaw_to_quaternion(s[2] if len(s) > 2 else 0.0)
    msg.twist.twist.linear.x = float(linear[0])
    msg.twist.twist.linear.y = float(linear[1])
    msg.twist.twist.angular.z = float(angular)
    return msg


def odometry_position(msg: Odometry) -> tuple[float, float]:
    """(x, y) of an odometry message; ValueError if not finite."""
    x, y = float(msg.pose.pose.position.x), float(msg.pose.pose.position.y)
    _finite((x, y), 'odometry position')
    return x, y


def odometry_to_state(msg: Odometry, model: str = 'point_mass', trailer: float | None = None) -> np.ndarray:
    """Model state from odometry: (x, y) for a point mass; (x, y, yaw) for a diff_drive; (x, y, yaw, trailer)
    for a tractor-trailer.

    `trailer` is theta1 (from `trailer_pose`), required for tractor-trailers. ValueError if not finite.
    """
    x, y = odometry_position(msg)
    if model == 'point_mass':
        return np.array([x, y])
    return pose_to_state((x, y, quaternion_to_yaw(msg.pose.pose.orientation)), model, trailer)


def pose_to_state(pose: tuple[float, float, float], model: str = 'point_mass',
                  trailer: float | None = None) -> np.ndarray:
    """odometry_to_state of a planar pose (x, y, yaw) read from odometry."""
    x, y, yaw = pose
    if model == 'point_mass':
        return np.array([x, y])
    if model == 'diff_drive':
        return np.array([x, y, yaw])
    if model == 'tractor_trailer':
        if trailer is None:
            raise ValueError('tractor-trailer state needs the trailer heading (trailer_pose)')
        _finite((trailer,), 'trailer heading')
        return np.array([x, y, yaw, float(trailer)])
    raise ValueError(f'unknown robot model {model!r}')


def odometry_velocity(msg: Odometry) -> tuple[float, float]:
    """Map-frame velocity (vx, vy) of the reference point: the child-frame twist rotated by the yaw."""
    q = msg.pose.pose.orientation
    return twist_in_map(float(msg.twist.twist.linear.x), float(msg.twist.twist.linear.y), (q.x, q.y, q.z, q.w))


def twist_in_map(vx: float, vy: float, orientation: tuple[float, float, float, float]) -> tuple[float, float]:
    """A child-frame velocity (vx, vy) rotated by the yaw of the orientation quaternion (x, y, z, w)."""
    _finite((vx, vy), 'odometry twist')
    yaw = yaw_of(*orientation)
    c, s = math.cos(yaw), math.sin(yaw)
    return c * vx - s * vy, s * vx + c * vy


def trailer_pose(state: Vector, trailer_length: float, hitch_offset: float = 0.0,
                 stamp: Time | None = None, frame_id: str = 'map') -> PoseStamped:
    """Pose of the trailer axle point of a tractor-trailer state (x, y, theta0, theta1), yaw theta1.

    The hitch is `hitch_offset` behind the tractor's mid-axle point, the trailer axle `trailer_length`
    behind the hitch (eq. 13).
    """
    x, y, th0, th1 = (float(v) for v in state)
    hx, hy = x - hitch_offset * math.cos(th0), y - hitch_offset * math.sin(th0)
    point = (hx - trailer_length * math.cos(th1), hy - trailer_length * math.sin(th1))
    return point_to_pose_stamped(point, stamp, frame_id, yaw=th1)


def trailer_yaw(msg: PoseStamped) -> float:
    """theta1 from a `trailer_pose` message (ValueError if not finite)."""
    return quaternion_to_yaw(msg.pose.orientation)


# ------------------------------------------------------------------------------------------------- commands

STEERED_MODELS = ('tractor_trailer', 'diff_drive')
"""Models commanded by (v, omega) in the body frame: Twist linear.x and angular.z."""


def command_to_twist(command: Vector, model: str = 'point_mass') -> Twist:
    """Model command to Twist: point mass (vx, vy) -> linear.x/y; tractor-trailer and diff_drive (v, omega) ->
    linear.x, angular.z."""
    (x, y), z = command_twist_values(command, model)
    msg = Twist()
    msg.linear.x, msg.linear.y, msg.angular.z = x, y, z
    return msg


def command_twist_values(command: Vector, model: str = 'point_mass') -> tuple[tuple[float, float], float]:
    """((linear.x, linear.y), angular.z) of command_to_twist's message (msg_tools.cdr writes them as bytes)."""
    a, b = float(command[0]), float(command[1])
    return ((a, 0.0), b) if model in STEERED_MODELS else ((a, b), 0.0)


def twist_to_command(msg: Twist | TwistStamped, model: str = 'point_mass') -> np.ndarray:
    """Inverse of command_to_twist (TwistStamped accepted); ValueError if the used fields are not finite."""
    twist = msg.twist if isinstance(msg, TwistStamped) else msg
    return twist_values_to_command(float(twist.linear.x), float(twist.linear.y), float(twist.angular.z), model)


def twist_values_to_command(linear_x: float, linear_y: float, angular_z: float,
                            model: str = 'point_mass') -> np.ndarray:
    """twist_to_command of a twist's (linear.x, linear.y, angular.z), as msg_tools.cdr reads them."""
    cmd = (linear_x, angular_z) if model in STEERED_MODELS else (linear_x, linear_y)
    _finite(cmd, 'velocity command')
    return np.array(cmd)


# ------------------------------------------------------------------------------------------------- obstacles

def obstacles_to_marker_array(obstacles: Iterable[Obstacle], stamp: Time | None = None, frame_id: str = 'map',
                              height: float = 1.0, line_width: float = 0.1) -> MarkerArray:
    """One CYLINDER marker per circle (scale x = y = diameter) and one LINE_LIST for all segments.

    A DELETEALL marker comes first, so a re-published array replaces an old one in RViz/Foxglove.
    """
    out = MarkerArray()
    clear = Marker()
    clear.header.frame_id = frame_id
    clear.action = Marker.DELETEALL
    out.markers.append(clear)
    items = list(obstacles)
    circles = [o for o in items if isinstance(o, Circle)]
    segments = [o for o in items if isinstance(o, Segment)]
    for i, c in enumerate(circles):
        m = Marker()
        m.header.frame_id = frame_id
        if stamp is not None:
            m.header.stamp = stamp
        m.ns, m.id, m.type, m.action = CIRCLES_NS, i, Marker.CYLINDER, Marker.ADD
        m.pose.position = Point(x=float(c.center[0]), y=float(c.center[1]), z=0.5 * height)
        m.pose.orientation.w = 1.0
        m.scale.x = m.scale.y = 2.0 * float(c.radius)
        m.scale.z = height
        m.color.r = m.color.g = m.color.b = 0.55
        m.color.a = 0.9
        out.markers.append(m)
    if segments:
        m = Marker()
        m.header.frame_id = frame_id
        if stamp is not None:
            m.header.stamp = stamp
        m.ns, m.id, m.type, m.action = SEGMENTS_NS, 0, Marker.LINE_LIST, Marker.ADD
        m.pose.orientation.w = 1.0
        m.scale.x = line_width
        m.color.r = m.color.g = m.color.b = 0.25
        m.color.a = 1.0
        for s in segments:
            m.points.append(Point(x=float(s.start[0]), y=float(s.start[1]), z=0.0))
            m.points.append(Point(x=float(s.end[0]), y=float(s.end[1]), z=0.0))
        out.markers.append(m)
    return out


def marker_array_to_obstacles(msg: MarkerArray) -> list[Obstacle]:
    """Circles (CYLINDER: centre = pose position, radius = scale.x / 2) and segments (LINE_LIST point pairs).

    Markers are applied in order: DELETEALL clears what came before, DELETE removes one (ns, id), ADD or
    MODIFY replaces one. Other marker types are ignored. Poses are taken as given in the map frame (the
    marker pose of a LINE_LIST must be the identity). ValueError for non-finite values, a radius <= 0, an odd
    number of LINE_LIST points or a zero-length segment.
    """
    found: dict[tuple[str, int], list[Obstacle]] = {}
    for m in msg.markers:
        key = (m.ns, m.id)
        if m.action == Marker.DELETEALL:
            found.clear()
            continue
        if m.action == Marker.DELETE:
            found.pop(key, None)
            continue
        if m.type == Marker.CYLINDER:
            cx, cy, r = float(m.pose.position.x), float(m.pose.position.y), 0.5 * float(m.scale.x)
            _finite((cx, cy, r), f'obstacle marker {m.ns}/{m.id}')
            if r <= 0.0:
                raise ValueError(f'obstacle marker {m.ns}/{m.id} has radius {r:g} <= 0')
            found[key] = [Circle((cx, cy), r)]
        elif m.type == Marker.LINE_LIST:
            if len(m.points) % 2:
                raise ValueError(f'obstacle marker {m.ns}/{m.id}: LINE_LIST has an odd number of points')
            ox, oy = float(m.pose.position.x), float(m.pose.position.y)
            segs: list[Obstacle] = []
            for a, b in zip(m.points[0::2], m.points[1::2]):
                coords = (a.x + ox, a.y + oy, b.x + ox, b.y + oy)
                _finite(coords, f'obstacle marker {m.ns}/{m.id}')
                if coords[:2] == coords[2:]:
                    raise ValueError(f'obstacle marker {m.ns}/{m.id}: zero-length segment')
                segs.append(Segment((coords[0], coords[1]), (coords[2], coords[3])))
            found[key] = segs
    return [o for group in found.values() for o in group]


# ------------------------------------------------------------------------------------------------- scans

def scan_to_laser_scan(scan: Scan, stamp: Time | None = None, frame_id: str = 'base_link') -> LaserScan:
    """sensor_msgs/LaserScan of a scan (fastep_core.sensing.laser.Scan carries its fields; +inf beyond range)."""
    msg = LaserScan()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.angle_min, msg.angle_max = float(scan.angle_min), float(scan.angle_max)
    msg.angle_increment = float(scan.angle_increment)
    msg.range_min, msg.range_max = float(scan.range_min), float(scan.range_max)
    msg.ranges = np.asarray(scan.ranges, dtype=np.float32).tolist()
    return msg


def laser_scan_to_scan(msg: LaserScan, time: float = 0.0) -> Scan:
    """The Scan of any sensor_msgs/LaserScan, readings as REP-117 means them: +inf (nothing within range: the
    beam's whole length is free) stays +inf; NaN, -inf and readings below range_min or beyond range_max are no
    measurement and become NaN (they neither mark nor clear anything: a beam that missed a dark or glass surface
    does not make the map's obstacle there go away). ValueError (one line) for no ranges or more than MAX_BEAMS,
    non-finite angles or range limits, a zero increment, or range_max <= range_min."""
    fields = (msg.angle_min, msg.angle_max, msg.angle_increment, msg.range_min, msg.range_max)
    _finite(fields, 'laser scan')
    if not len(msg.ranges):
        raise ValueError('laser scan has no ranges')
    if len(msg.ranges) > MAX_BEAMS:   # what perception could not take, refused before the copy
        raise ValueError(f'laser scan has {len(msg.ranges)} ranges, more than {MAX_BEAMS} (a planar lidar\'s most)')
    if msg.angle_increment == 0.0:
        raise ValueError('laser scan angle_increment is 0')
    if not 0.0 <= msg.range_min < msg.range_max:
        raise ValueError(f'laser scan range limits [{msg.range_min:g}, {msg.range_max:g}] are not 0 <= min < max')
    ranges = np.asarray(msg.ranges, dtype=float)
    valid = np.isfinite(ranges) & (ranges >= msg.range_min) & (ranges <= msg.range_max)
    readings = np.where(valid, ranges, np.where(np.isposinf(ranges), np.inf, np.nan))
    return Scan(float(msg.angle_min), float(msg.angle_max), float(msg.angle_increment), float(msg.range_min),
                float(msg.range_max), readings, time)


def laser_spec(msg: LaserScan, noise: float) -> LaserSpec:
    """The scanner a LaserScan comes from, for perception: its range, field of view, beams, and `noise` (the
    range noise's standard deviation, which the message does not carry)."""
    beams = len(msg.ranges)
    step = abs(float(msg.angle_increment))
    # A full turn has `beams` increments (the last beam next to the first); a sector one fewer (both edges).
    full = step * beams >= 2.0 * math.pi - FULL_TURN_TOLERANCE
    fov = 2.0 * math.pi if full else min(step * max(beams - 1, 1), 2.0 * math.pi)
    return LaserSpec(float(msg.range_max), fov, beams, noise)


def belief_to_marker_array(belief: Belief, stamp: Time | None = None, frame_id: str = 'map') -> MarkerArray:
    """What a planner believes (fastep_core.perception.Belief), for a viewer: the still obstacles it saw (circles
    and walls, as obstacles_to_marker_array draws them, in orange), and each tracked mover (namespace
    TRACKS_NS) as a cylinder of its radius with an arrow of its velocity over one second (TRACK_VELOCITIES_NS)."""
    out = obstacles_to_marker_array(belief.seen_obstacles, stamp, frame_id)
    for m in out.markers[1:]:
        m.ns = f'seen_{m.ns}'
        m.color.r, m.color.g, m.color.b = 1.0, 0.55, 0.0
    out.markers.extend(_mover_markers(belief.movers, TRACKS_NS, TRACK_VELOCITIES_NS, stamp, frame_id))
    return out


def _mover_markers(movers: Sequence[OtherRobot], body_ns: str, arrow_ns: str, stamp: Time | None,
                   frame_id: str) -> list[Marker]:
    """Per mover a CYLINDER of its radius (its name as the marker's text) and an ARROW of its velocity over one
    second, both with id = its index."""
    out: list[Marker] = []
    for i, mover in enumerate(movers):
        x, y = float(mover.position[0]), float(mover.position[1])
        vx, vy = float(mover.velocity[0]), float(mover.velocity[1])
        body, arrow = Marker(), Marker()
        for m in (body, arrow):
            m.header.frame_id = frame_id
            if stamp is not None:
                m.header.stamp = stamp
            m.id, m.action = i, Marker.ADD
            m.pose.orientation.w = 1.0
            m.color.r, m.color.g, m.color.b, m.color.a = 0.6, 0.2, 0.8, 0.8
        body.ns, body.type, body.text = body_ns, Marker.CYLINDER, mover.name
        body.pose.position = Point(x=x, y=y, z=0.5)
        body.scale.x = body.scale.y = 2.0 * float(mover.radius)
        body.scale.z = 1.0
        arrow.ns, arrow.type = arrow_ns, Marker.ARROW
        arrow.points = [Point(x=x, y=y, z=1.0), Point(x=x + vx, y=y + vy, z=1.0)]
        arrow.scale.x, arrow.scale.y, arrow.scale.z = 0.08, 0.2, 0.2
        out.extend([body, arrow])
    return out


def movers_to_marker_array(movers: Sequence[OtherRobot], stamp: Time | None = None,
                           frame_id: str = 'map') -> MarkerArray:
    """The known movers as the map node publishes them on /movers: a DELETEALL, then per mover a cylinder
    (MOVERS_NS) and an arrow of its velocity over one second (MOVER_VELOCITIES_NS), id = its index."""
    out = MarkerArray()
    clear = Marker()
    clear.header.frame_id = frame_id
    clear.action = Marker.DELETEALL
    out.markers.append(clear)
    out.markers.extend(_mover_markers(movers, MOVERS_NS, MOVER_VELOCITIES_NS, stamp, frame_id))
    return out


def marker_array_to_movers(msg: MarkerArray) -> list[OtherRobot]:
    """The movers of a /movers MarkerArray (movers_to_marker_array): position and radius from each cylinder, the
    velocity from the arrow of the same id (none: standing), the name from its text ('mover K' if empty).
    ValueError (one line) for a non-finite value or a radius <= 0."""
    bodies: dict[int, Marker] = {}
    arrows: dict[int, Marker] = {}
    for m in msg.markers:
        if m.action == Marker.DELETEALL:
            bodies.clear()
            arrows.clear()
        elif m.ns == MOVERS_NS and m.type == Marker.CYLINDER:
            bodies[m.id] = m
        elif m.ns == MOVER_VELOCITIES_NS and m.type == Marker.ARROW and len(m.points) == 2:
            arrows[m.id] = m
    out: list[OtherRobot] = []
    for key, body in bodies.items():
        x, y, r = float(body.pose.position.x), float(body.pose.position.y), 0.5 * float(body.scale.x)
        arrow = arrows.get(key)
        vx = vy = 0.0
        if arrow is not None:
            vx, vy = arrow.points[1].x - arrow.points[0].x, arrow.points[1].y - arrow.points[0].y
        _finite((x, y, r, vx, vy), f'mover marker {body.ns}/{key}')
        if r <= 0.0:
            raise ValueError(f'mover marker {body.ns}/{key} has radius {r:g} <= 0')
        out.append(OtherRobot(body.text or f'mover {key}', (x, y), (float(vx), float(vy)), r, mover=True))
    return out


# ------------------------------------------------------------------------------------------------- status

def make_status(name: str, message: str, level: str | bytes, values: Mapping[str, Any] | None = None,
                hardware_id: str = '') -> DiagnosticStatus:
    """DiagnosticStatus with level 'ok' | 'warn' | 'error' | 'stale' (or a level byte); values as strings."""
    msg = DiagnosticStatus()
    msg.level = LEVELS[level] if isinstance(level, str) else level
    msg.name, msg.message, msg.hardware_id = name, message, hardware_id
    msg.values = [KeyValue(key=key, value=text) for key, text in status_values(values)]
    return msg


def status_values(values: Mapping[str, Any] | None) -> list[tuple[str, str]]:
    """The (key, value) pairs of make_status's message, values as text (msg_tools.cdr writes them as bytes)."""
    return [(str(k), _value_text(v)) for k, v in (values or {}).items()]


def _value_text(value: Any) -> str:
    if value is None:
        return ''
    if isinstance(value, float):
        return _float_text(value)
    if isinstance(value, (list, tuple, np.ndarray)):
        return ','.join(_float_text(float(v)) for v in value)
    return str(value)


def _float_text(value: float) -> str:
    """Six significant digits, but never coarser than a millisecond below 1e12: a wall-clock time (1.8e9 s) keeps
    its milliseconds (as 1.79588e+09 a status's `t` and `since` moved in steps of 10,000 s, and fastep-launch
    --no-clock timed every run 0.0 s)."""
    return f'{value:.3f}' if 1e3 <= abs(value) < 1e12 else f'{value:.6g}'


def diagnostic_to_dict(msg: DiagnosticStatus) -> dict[str, Any]:
    """{'name', 'message', 'level' ('ok'|'warn'|'error'|'stale'), and every key/value}."""
    names = {v: k for k, v in LEVELS.items()}
    out: dict[str, Any] = {kv.key: kv.value for kv in msg.values}
    out.update(name=msg.name, message=msg.message, level=names.get(msg.level, repr(msg.level)))
    return out
