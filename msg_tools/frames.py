"""REP-105 frames: planar pose algebra, the map -> odom transform, and TF messages (tf2_msgs/msg/TFMessage).

Per robot namespace `<ns>` (no leading slash; plain `odom`, `base_link` in the root namespace):

    map  ->  <ns>/odom  ->  <ns>/base_link          (and <ns>/odom -> <ns>/trailer_link for tractor-trailers)

The plant's odometry is base_link in odom; the planner works in `map`, composing the odometry with map -> odom
(the identity in simulation; on a robot the transform that makes a localization pose agree with the odometry
at its stamp, kept by MapFromOdom). Map-frame commands are rotated into the body frame before they are sent.
Recordings serialise TFMessage with rosbags' typestore, so they do not depend on tf2_msgs (not among the
registry's ROS wheels); nodes publish TF live where tf2_msgs is importable (fastep_ros.live_tf).
Details: docs/frames.md. Poses are (x, y, yaw) tuples; angles in radians, wrapped to (-pi, pi].
"""

from __future__ import annotations

import bisect
import functools
import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import TransformStamped

from msg_tools import cdr, convert
from msg_tools.ros2_profile import qos_dict

__all__ = [
    'IDENTITY', 'TF', 'TF_QOS', 'TF_STATIC', 'TF_STATIC_QOS', 'TF_TYPE', 'MapFromOdom', 'OdometryHistory', 'Pose2D',
    'StampedPose',
    'TfTree',
    'base_frame',
    'body_velocity', 'compose', 'frame_name', 'inverse', 'odom_frame', 'odometry_pose', 'odometry_transforms',
    'planar_transform',
    'stamped_pose', 'state_in_frame', 'static_map_to_odom', 'tf_message_cdr', 'tf_message_class', 'trailer_frame',
    'transform_stamped',
]

Pose2D = tuple[float, float, float]   # x, y, yaw
IDENTITY: Pose2D = (0.0, 0.0, 0.0)

TF = '/tf'
TF_STATIC = '/tf_static'
TF_TYPE = 'tf2_msgs/msg/TFMessage'
# What tf2_ros's broadcasters offer: /tf reliable, volatile, 100 deep; /tf_static reliable, transient-local, 1 deep.
TF_QOS = [qos_dict(depth=100)]
TF_STATIC_QOS = [qos_dict(depth=1, transient_local=True)]


# ----------------------------------------------------------------------------------------------- names

def frame_name(namespace: str, frame: str) -> str:
    """`r1/odom` for namespace `/r1`, `odom` for the root namespace: a frame id never starts with a slash."""
    ns = namespace.strip('/')
    return f'{ns}/{frame}' if ns else frame


def odom_frame(namespace: str) -> str:
    return frame_name(namespace, 'odom')


def base_frame(namespace: str) -> str:
    return frame_name(namespace, 'base_link')


def trailer_frame(namespace: str) -> str:
    return frame_name(namespace, 'trailer_link')


# ----------------------------------------------------------------------------------------------- pose algebra

def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def compose(a: Pose2D, b: Pose2D) -> Pose2D:
    """a o b: the pose b (given in frame A, whose pose in the parent is a) expressed in the parent."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (a[0] + c * b[0] - s * b[1], a[1] + s * b[0] + c * b[1], _wrap(a[2] + b[2]))


def inverse(a: Pose2D) -> Pose2D:
    """The pose whose composition with a is the identity."""
    c, s = math.cos(a[2]), math.sin(a[2])
    return (-c * a[0] - s * a[1], s * a[0] - c * a[1], _wrap(-a[2]))


def planar_transform(t: Any) -> tuple[str, str, Pose2D] | None:
    """(parent, child, the child's planar pose in the parent) of a geometry_msgs/TransformStamped; None when a
    frame is missing, the frames are one, or it is not finite."""
    parent, child = t.header.frame_id.lstrip('/'), t.child_frame_id.lstrip('/')
    q, v = t.transform.rotation, t.transform.translation
    norm = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w
    if not parent or not child or parent == child or not (math.isfinite(norm) and norm > 0.0):
        return None
    yaw = math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))
    pose = (float(v.x), float(v.y), yaw)
    return (parent, child, pose) if all(math.isfinite(c) for c in pose) else None


class TfTree:
    """The newest transform of every edge of a TF tree, in the plane (x, y, yaw of each child frame in its parent),
    from /tf and /tf_static messages; lookup composes along the tree, as tf2's lookups at the latest time do.
    Frame names without a leading '/'; a transform that is not finite, or would make a frame its own ancestor,
    is left out."""

    MAX_DEPTH = 64   # frames between a frame and its root: a deeper chain is taken for a broken tree

    def __init__(self) -> None:
        self.parents: dict[str, tuple[str, Pose2D]] = {}

    def add(self, transforms: Sequence[Any]) -> None:
        """geometry_msgs/TransformStamped messages (a TFMessage's transforms)."""
        for t in transforms:
            edge = planar_transform(t)
            if edge is None or edge[1] in self._ancestors(edge[0]):
                continue
            self.parents[edge[1]] = (edge[0], edge[2])

    def _ancestors(self, frame: str) -> list[str]:
        chain = [frame]
        while frame in self.parents and len(chain) <= self.MAX_DEPTH:
            frame = self.parents[frame][0]
            chain.append(frame)
        return chain

    def _in_root(self, frame: str) -> tuple[str, Pose2D]:
        """(the root of frame's tree, frame's pose in it)."""
        pose = IDENTITY
        for _ in range(self.MAX_DEPTH):
            if frame not in self.parents:
                break
            parent, edge = self.parents[frame]
            pose, frame = compose(edge, pose), parent
        return frame, pose

    def lookup(self, target: str, source: str) -> Pose2D | None:
        """The pose of frame `source` in frame `target`, or None when they are not in one tree."""
        target, source = target.lstrip('/'), source.lstrip('/')
        if target == source:
            return IDENTITY
        root_s, in_root_s = self._in_root(source)
        root_t, in_root_t = self._in_root(target)
        if root_s != root_t:
            return None
        return compose(inverse(in_root_t), in_root_s)

    def frames(self) -> list[str]:
        return sorted({*self.parents, *(parent for parent, _ in self.parents.values())})


def state_in_frame(transform: Pose2D, state: np.ndarray) -> np.ndarray:
    """A model state [x, y, angles...] (every model's state is a point and headings) moved by `transform`: the
    point transformed, every heading turned by its yaw. The identity returns the state unchanged (no rounding)."""
    if transform == IDENTITY:
        return state
    out = np.array(state, dtype=float)
    out[0], out[1], _ = compose(transform, (float(state[0]), float(state[1]), 0.0))
    out[2:] = [_wrap(float(v) + transform[2]) for v in state[2:]]
    return out


def body_velocity(velocity: Sequence[float] | np.ndarray, heading: float) -> tuple[float, float]:
    """A velocity given in a frame, rotated into a body frame whose heading in that frame is `heading`."""
    if heading == 0.0:
        return float(velocity[0]), float(velocity[1])
    c, s = math.cos(heading), math.sin(heading)
    return c * velocity[0] + s * velocity[1], -s * velocity[0] + c * velocity[1]


# ----------------------------------------------------------------------------------------------- map -> odom

@dataclass(frozen=True)
class OdometryHistory:
    """The recent odometry poses of one robot, by stamp: one immutable value, replaced whole when a pose is added,
    so a reader on another thread always sees stamps and poses of one moment paired."""

    stamps: tuple[float, ...] = ()
    poses: tuple[Pose2D, ...] = ()

    def added(self, stamp: float, pose: Pose2D, keep: int) -> OdometryHistory:
        """This history with (stamp, pose) appended, at most `keep` poses; a stamp before the newest (a restarted
        clock) starts it afresh: what was kept belongs to another run."""
        if self.stamps and stamp < self.stamps[-1]:
            return OdometryHistory((stamp,), (pose,))
        drop = max(0, len(self.stamps) + 1 - keep)
        return OdometryHistory((*self.stamps[drop:], stamp), (*self.poses[drop:], pose))

    def nearest(self, stamp: float) -> Pose2D | None:
        """The kept pose whose stamp is nearest to `stamp` (None before any)."""
        stamps = self.stamps
        if not stamps:
            return None
        i = bisect.bisect_left(stamps, stamp)
        if i == len(stamps) or (i > 0 and stamp - stamps[i - 1] <= stamps[i] - stamp):
            i -= 1
        return self.poses[i]

    def interpolated(self, stamp: float) -> Pose2D | None:
        """The pose at `stamp`, interpolated between the kept poses around it (linearly, the yaw along the shorter
        turn); None outside the kept stamps (a scan stamped after the newest odometry, or long ago)."""
        stamps = self.stamps
        if not stamps or not stamps[0] <= stamp <= stamps[-1]:
            return None
        i = bisect.bisect_left(stamps, stamp)
        if stamps[i] == stamp or i == 0:
            return self.poses[i]
        (t0, a), (t1, b) = (stamps[i - 1], self.poses[i - 1]), (stamps[i], self.poses[i])
        share = (stamp - t0) / (t1 - t0) if t1 > t0 else 1.0
        return (a[0] + share * (b[0] - a[0]), a[1] + share * (b[1] - a[1]), _wrap(a[2] + share * _wrap(b[2] - a[2])))


class MapFromOdom:
    """map -> odom of one robot: from localization poses (map pose of base_link, stamped) and the odometry.

    add_odometry keeps the recent odometry poses (by stamp, an OdometryHistory); add_localization sets map->odom =
    localization o inverse(the odometry pose nearest to the localization's stamp). A localization pose that comes
    before any odometry waits for the first odometry. transform is None until one was computed: the robot's map
    pose is not known then.
    """

    def __init__(self, keep: int = 400) -> None:
        self.keep = keep                    # odometry poses kept (20 s at the plant's 20 Hz odometry)
        self.history = OdometryHistory()
        self.pending: tuple[float, Pose2D] | None = None
        self.transform: Pose2D | None = None
        self.localizations = 0              # localization poses turned into a transform

    def add_odometry(self, stamp: float, pose: Pose2D) -> None:
        self.history = self.history.added(stamp, pose, self.keep)
        if self.pending is not None:
            pending, self.pending = self.pending, None
            self.add_localization(*pending)

    def odometry_at(self, stamp: float) -> Pose2D | None:
        """The kept odometry pose whose stamp is nearest to `stamp` (None before any)."""
        return self.history.nearest(stamp)

    def interpolated(self, stamp: float) -> Pose2D | None:
        """OdometryHistory.interpolated of the history as it is now."""
        return self.history.interpolated(stamp)

    def add_localization(self, stamp: float, pose: Pose2D) -> None:
        odometry = self.odometry_at(stamp)
        if odometry is None:
            self.pending = (stamp, pose)
            return
        self.transform = compose(pose, inverse(odometry))
        self.localizations += 1


# ----------------------------------------------------------------------------------------------- messages

def odometry_pose(msg: Any) -> Pose2D:
    """(x, y, yaw) of a nav_msgs/Odometry or geometry_msgs PoseStamped / PoseWithCovarianceStamped (ValueError
    when not finite)."""
    pose = msg.pose.pose if hasattr(msg.pose, 'pose') else msg.pose
    x, y = float(pose.position.x), float(pose.position.y)
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError('position is not finite')
    return x, y, convert.quaternion_to_yaw(pose.orientation)


@dataclass(frozen=True)
class StampedPose:
    """A planar pose with its frame and stamp (s): what a planner takes of its own odometry."""

    frame_id: str
    stamp: float
    pose: Pose2D   # x, y, yaw
    twist: tuple[float, float, float] = (0.0, 0.0, 0.0)   # linear.x, linear.y, angular.z in the child frame


def stamped_pose(msg: Any) -> StampedPose:
    """StampedPose of a nav_msgs/Odometry, or of its CDR bytes (read with struct where they are little-endian, to
    the message's floats); ValueError if not finite or cut off."""
    if isinstance(msg, bytes):
        fields = cdr.odometry_fields(msg)
        if fields is None:   # not little-endian CDR: rclpy reads it
            from nav_msgs.msg import Odometry
            from rclpy.serialization import deserialize_message
            msg = deserialize_message(msg, Odometry)
        else:
            x, y, qx, qy, qz, qw = fields[:6]
            if not (math.isfinite(x) and math.isfinite(y)):
                raise ValueError('position is not finite')   # odometry_pose's checks and words
            sec, nanosec = cdr.header_stamp(msg)
            return StampedPose(cdr.header_frame_id(msg), sec + nanosec * 1e-9, (x, y, convert.yaw_of(qx, qy, qz, qw)),
                               (fields[6], fields[7], fields[8]))
    twist = msg.twist.twist
    return StampedPose(msg.header.frame_id, convert.stamp_to_seconds(msg.header.stamp), odometry_pose(msg),
                       (float(twist.linear.x), float(twist.linear.y), float(twist.angular.z)))


def transform_stamped(parent: str, child: str, pose: Pose2D, stamp: Time) -> TransformStamped:
    """The TF of `child` in `parent` (a planar pose)."""
    msg = TransformStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = parent
    msg.child_frame_id = child
    msg.transform.translation.x, msg.transform.translation.y = float(pose[0]), float(pose[1])
    msg.transform.rotation = convert.yaw_to_quaternion(pose[2])
    return msg


def odometry_transforms(odom: Any, trailer: Any = None, trailer_child: str = '') -> list[TransformStamped]:
    """The TF an odometry message stands for (header.frame_id -> child_frame_id, as tf2's odometry broadcasters
    send), and a trailer pose's (its frame -> trailer_child) when given."""
    out = [_exact(transform_stamped(odom.header.frame_id, odom.child_frame_id, odometry_pose(odom),
                                    odom.header.stamp), odom.pose.pose)]
    if trailer is not None:
        out.append(_exact(transform_stamped(trailer.header.frame_id, trailer_child, odometry_pose(trailer),
                                            trailer.header.stamp), trailer.pose))
    return out


def _exact(transform: TransformStamped, pose: Any) -> TransformStamped:
    """The transform with the pose's own numbers (no round trip through the yaw)."""
    t, q = transform.transform, pose.orientation
    t.translation.x, t.translation.y, t.translation.z = pose.position.x, pose.position.y, pose.position.z
    t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w = q.x, q.y, q.z, q.w
    return transform


def static_map_to_odom(map_frame: str, odom: str, stamp: Time | None = None) -> TransformStamped:
    """map -> odom as the identity: a simulated robot's odometry does not drift."""
    return transform_stamped(map_frame, odom, IDENTITY, stamp if stamp is not None else Time())


@functools.cache
def _typestore() -> Any:
    from rosbags.typesys import Stores, get_typestore
    return get_typestore(Stores.ROS2_JAZZY)


def tf_message_cdr(transforms: Sequence[TransformStamped]) -> bytes:
    """The CDR bytes of a tf2_msgs/msg/TFMessage holding these transforms (rosbags' serialiser: no rclpy class)."""
    store = _typestore()
    types = store.types
    tf_type, stamped, header, time, transform, vector, quaternion = (
        types[n] for n in (TF_TYPE, 'geometry_msgs/msg/TransformStamped', 'std_msgs/msg/Header',
                           'builtin_interfaces/msg/Time', 'geometry_msgs/msg/Transform', 'geometry_msgs/msg/Vector3',
                           'geometry_msgs/msg/Quaternion'))
    items = []
    for t in transforms:
        tr, q = t.transform.translation, t.transform.rotation
        items.append(stamped(header=header(stamp=time(sec=t.header.stamp.sec, nanosec=t.header.stamp.nanosec),
                                           frame_id=t.header.frame_id),
                             child_frame_id=t.child_frame_id,
                             transform=transform(translation=vector(x=tr.x, y=tr.y, z=tr.z),
                                                 rotation=quaternion(x=q.x, y=q.y, z=q.z, w=q.w))))
    return bytes(store.serialize_cdr(tf_type(transforms=items), TF_TYPE))


def tf_message_class() -> type | None:
    """rclpy's tf2_msgs/msg/TFMessage where tf2_msgs is installed (built by interfaces/build.sh, or a ROS install), else
    None."""
    try:
        from tf2_msgs.msg import TFMessage
    except ImportError:
        return None
    cls: type = TFMessage
    return cls


class TfFromOdometry:
    """What a recorder derives from the odometry it records, when the graph has no TF of its own (no tf2_msgs):
    take(topic, cdr) returns the (TF topic, TFMessage CDR) pairs to write beside a recorded message.

    Per robot: the first odometry in a frame other than the map frame brings /tf_static map -> that frame (the
    identity: simulated odometry does not drift); every odometry /tf header.frame_id -> child_frame_id; every
    trailer pose /tf its frame -> `<robot>/trailer_link`. Messages that do not decode or are not finite give
    nothing (the recording keeps them as they are)."""

    def __init__(self, map_frame: str = 'map') -> None:
        self.map_frame = map_frame
        self.static: list[TransformStamped] = []
        self.static_frames: set[str] = set()

    def take(self, topic: str, data: bytes) -> list[tuple[str, bytes]]:
        from nav_msgs.msg import Odometry
        from rclpy.serialization import deserialize_message

        from msg_tools.interface import ODOM, TRAILER_POSE, split_robot_topic

        parts = split_robot_topic(topic)
        if parts is None or parts[1] not in (ODOM, TRAILER_POSE):
            return []
        out = []
        try:
            if parts[1] == ODOM:
                # From the bytes (msg_tools.cdr): one message a robot and tick, and an Odometry took ~150 us to
                # decode and turn into TF here, a third of a recorder's CPU.
                fast = cdr.odometry_transform(data)
                if fast is not None:
                    return self._odometry_tf(*fast)
                msg = deserialize_message(data, Odometry)
                transforms = odometry_transforms(msg)
                frame = msg.header.frame_id
                if frame and frame != self.map_frame and frame not in self.static_frames:
                    self.static_frames.add(frame)
                    # One latched message holds every static transform, as tf2_ros's static broadcaster sends.
                    self.static.append(static_map_to_odom(self.map_frame, frame, msg.header.stamp))
                    out.append((TF_STATIC, tf_message_cdr(self.static)))
            else:
                from geometry_msgs.msg import PoseStamped
                pose = deserialize_message(data, PoseStamped)
                transforms = [transform_stamped(pose.header.frame_id, trailer_frame(parts[0]), odometry_pose(pose),
                                                pose.header.stamp)]
        except Exception:  # noqa: BLE001  (a message that does not decode or is not finite: no TF from it)
            return []
        out.append((TF, tf_message_cdr(transforms)))
        return out

    def _odometry_tf(self, stamp: tuple[int, int], frame: str, child: str, translation: tuple[float, float, float],
                     rotation: tuple[float, float, float, float]) -> list[tuple[str, bytes]]:
        """take() of an odometry message read from its bytes: what odometry_transforms gives of the message."""
        if not (math.isfinite(translation[0]) and math.isfinite(translation[1])):
            return []
        try:
            convert.yaw_of(*rotation)   # odometry_pose's checks: finite, not of zero length
        except ValueError:
            return []
        out = []
        if frame and frame != self.map_frame and frame not in self.static_frames:
            self.static_frames.add(frame)
            self.static.append(static_map_to_odom(self.map_frame, frame, Time(sec=stamp[0], nanosec=stamp[1])))
            out.append((TF_STATIC, tf_message_cdr(self.static)))
        out.append((TF, cdr.tf_message_cdr([(stamp, frame, child, translation, rotation)])))
        return out
