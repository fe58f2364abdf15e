"""Fast reads and writes of the high-rate message types as CDR bytes, without building rclpy messages.

Why: rclpy's deserialize_message builds a full Python message (an Odometry is ~15 objects), which made reading
long recordings slow and a planner following many robots spend most of a lock-step tick building their
odometry. These read only the needed float64 fields of little-endian CDR with struct (alignment relative to the
payload after the 4-byte encapsulation header). A cut-off message raises CdrError, as rclpy's decoder refuses
it; bytes that are not little-endian CDR give None (left to rclpy).

The writers make the message's bytes (zero padding), which a publisher sends as they are: odometry, cmd_vel,
waypoint, plan and status cost a few microseconds each instead of building a message. Tests compare both
directions with rclpy (tests/msg_tools/test_cdr.py).
"""

from __future__ import annotations

import functools
import struct
from typing import Sequence

__all__ = ['CdrError', 'clock_cdr', 'diagnostic_status_cdr', 'float64_cdr', 'float64_field', 'header_frame_id',
           'header_stamp', 'odometry_cdr', 'odometry_fields', 'odometry_transform', 'path_cdr', 'pose_stamped_cdr',
           'stamp_parts', 'tf_message_cdr', 'twist_cdr', 'twist_fields', 'twist_stamped_cdr', 'twist_stamped_fields']

_CDR_LE = b'\x00\x01'
_ENCAPSULATION = b'\x00\x01\x00\x00'    # little-endian CDR, no options
_U32 = struct.Struct('<I')
_ODOM = struct.Struct('<3d4d288x3d3d')  # position, orientation, (pose covariance), twist linear, angular
_ODOM_WRITE = struct.Struct('<3d4d288x3d3d288x')   # ... and the twist covariance (zeros)
_ODOM_TAIL = 85 * 8                     # pose (7), its covariance (36), twist (6), its covariance (36)
_TWIST = struct.Struct('<3d3d')
_POSE = struct.Struct('<3d4d')
_F64 = struct.Struct('<d')
_STAMP = struct.Struct('<iI')   # a header's stamp: sec, nanosec (right after the 4-byte CDR header)
_BYTE = struct.Struct('<B')
_IDENTITY = (0.0, 0.0, 0.0, 1.0)   # orientation (x, y, z, w) of yaw 0: convert.yaw_quaternion(0.0)


class CdrError(ValueError):
    """CDR bytes that do not hold a whole message of the type (cut off, or a string running past the end)."""


def _string_end(data: bytes, offset: int) -> int:
    """Offset after a CDR string starting at `offset` (payload offsets; data includes the 4-byte header);
    struct.error if its length field lies past the end (a string running past the end is caught by the
    caller's length check)."""
    offset = (offset + 3) & ~3
    return offset + 4 + _U32.unpack_from(data, 4 + offset)[0]


def header_stamp(data: bytes) -> tuple[int, int]:
    """(sec, nanosec) of the header of a CDR message that starts with one (struct.error if cut off)."""
    sec, nanosec = _STAMP.unpack_from(data, 4)
    return int(sec), int(nanosec)


def header_frame_id(data: bytes) -> str:
    """header.frame_id of a little-endian CDR message that starts with a std_msgs/Header (CdrError if cut off)."""
    try:
        (length,) = _U32.unpack_from(data, 12)   # payload offset 8, after the stamp
    except struct.error:
        raise CdrError(f'cut off: {len(data)} bytes end inside a header') from None
    if length == 0 or 16 + length > len(data):
        raise CdrError(f'cut off: {len(data)} bytes end inside a frame name')
    try:
        return data[16:15 + length].decode()
    except UnicodeDecodeError as exc:
        raise CdrError(f'frame name is not UTF-8: {exc}') from None


def odometry_fields(data: bytes) -> tuple[float, ...] | None:
    """(x, y, qx, qy, qz, qw, linear.x, linear.y, angular.z) of a CDR Odometry, None if not little-endian CDR;
    CdrError if the bytes are not a whole Odometry."""
    if data[:2] != _CDR_LE:
        return None
    try:
        offset = _string_end(data, 8)           # header.stamp (8 bytes), header.frame_id
        offset = _string_end(data, offset)      # child_frame_id
    except struct.error:
        raise CdrError(f'cut off: {len(data)} bytes end inside a frame name') from None
    offset = (offset + 7) & ~7
    if 4 + offset + _ODOM_TAIL > len(data):
        raise CdrError(f'cut off: {len(data)} bytes, an Odometry with these frame names needs '
                       f'{4 + offset + _ODOM_TAIL}')
    v = _ODOM.unpack_from(data, 4 + offset)
    return v[0], v[1], v[3], v[4], v[5], v[6], v[7], v[8], v[12]


Transform = tuple[tuple[int, int], str, str, tuple[float, float, float], tuple[float, float, float, float]]
"""A TF transform: (stamp (sec, nanosec), parent frame, child frame, translation, rotation (x, y, z, w))."""


def odometry_transform(data: bytes) -> Transform | None:
    """The TF a CDR Odometry stands for (header.frame_id -> child_frame_id, its pose's numbers), None if not
    little-endian CDR; CdrError if cut off."""
    if data[:2] != _CDR_LE:
        return None
    try:
        frame_end = _string_end(data, 8)
        child_end = _string_end(data, frame_end)
        offset = (child_end + 7) & ~7
        v = _POSE.unpack_from(data, 4 + offset)
        frame = data[16:4 + frame_end - 1].decode()
        child_start = (frame_end + 3) & ~3
        child = data[4 + child_start + 4:4 + child_end - 1].decode()
    except (struct.error, UnicodeDecodeError):
        raise CdrError(f'cut off: {len(data)} bytes end inside an Odometry') from None
    return header_stamp(data), frame, child, (v[0], v[1], v[2]), (v[3], v[4], v[5], v[6])


def twist_fields(data: bytes) -> tuple[float, float, float] | None:
    """(linear.x, linear.y, angular.z) of a CDR Twist (CdrError if cut off)."""
    if data[:2] != _CDR_LE:
        return None
    try:
        v = _TWIST.unpack_from(data, 4)
    except struct.error:
        raise CdrError(f'cut off: {len(data)} bytes, a Twist needs {4 + _TWIST.size}') from None
    return v[0], v[1], v[5]


def float64_field(data: bytes) -> float | None:
    """The value of a CDR Float64 (CdrError if cut off)."""
    if data[:2] != _CDR_LE:
        return None
    try:
        return _F64.unpack_from(data, 4)[0]
    except struct.error:
        raise CdrError(f'cut off: {len(data)} bytes, a Float64 needs {4 + _F64.size}') from None


def twist_stamped_fields(data: bytes) -> tuple[float, float, float] | None:
    """(linear.x, linear.y, angular.z) of a CDR TwistStamped (CdrError if cut off)."""
    if data[:2] != _CDR_LE:
        return None
    try:
        offset = (_string_end(data, 8) + 7) & ~7     # header.stamp, header.frame_id, then 8-byte aligned
        v = _TWIST.unpack_from(data, 4 + offset)
    except struct.error:
        raise CdrError(f'cut off: {len(data)} bytes end inside a TwistStamped') from None
    return v[0], v[1], v[5]


# ------------------------------------------------------------------------------------------------- writers

def stamp_parts(t: float) -> tuple[int, int]:
    """(sec, nanosec) of seconds t >= 0, nanoseconds rounded (msg_tools.convert.seconds_to_stamp's)."""
    total = int(round(t * 1e9))
    return total // 1_000_000_000, total % 1_000_000_000


_PADDING_TO_4 = (b'', b'\x00\x00\x00', b'\x00\x00', b'\x00')   # by offset % 4: looked up, a status writes 43 strings


def _string(text: str, offset: int) -> bytes:
    """A CDR string written at payload offset `offset`: padding to 4, length (with the NUL), text, NUL."""
    raw = text.encode() + b'\x00'
    return _PADDING_TO_4[offset & 3] + _U32.pack(len(raw)) + raw


@functools.lru_cache(maxsize=64)
def _header_tail(*frames: str) -> bytes:
    """The frame names after a header's stamp (payload offset 8), padded to the 8-byte alignment of the doubles
    after them. A robot's frames are few and fixed: made once."""
    out = b''
    for frame in frames:
        out += _string(frame, 8 + len(out))
    return out + bytes(-(8 + len(out)) % 8)


def odometry_cdr(stamp: tuple[int, int], frame_id: str, child_frame_id: str, position: tuple[float, float],
                 orientation: tuple[float, float, float, float], linear: tuple[float, float],
                 angular: float) -> bytes:
    """nav_msgs/Odometry: a planar pose (z 0), the twist (linear x, y; angular z) in the child frame, zero
    covariances."""
    qx, qy, qz, qw = orientation
    return _ENCAPSULATION + _STAMP.pack(*stamp) + _header_tail(frame_id, child_frame_id) + _ODOM_WRITE.pack(
        position[0], position[1], 0.0, qx, qy, qz, qw, linear[0], linear[1], 0.0, 0.0, 0.0, angular)


def twist_cdr(linear: tuple[float, float], angular: float) -> bytes:
    """geometry_msgs/Twist with linear x, y and angular z."""
    return _ENCAPSULATION + _TWIST.pack(linear[0], linear[1], 0.0, 0.0, 0.0, angular)


def twist_stamped_cdr(stamp: tuple[int, int], frame_id: str, linear: tuple[float, float], angular: float) -> bytes:
    """geometry_msgs/TwistStamped."""
    return _ENCAPSULATION + _STAMP.pack(*stamp) + _header_tail(frame_id) + \
        _TWIST.pack(linear[0], linear[1], 0.0, 0.0, 0.0, angular)


def float64_cdr(value: float) -> bytes:
    """std_msgs/Float64."""
    return _ENCAPSULATION + _F64.pack(value)


def clock_cdr(stamp: tuple[int, int]) -> bytes:
    """rosgraph_msgs/Clock."""
    return _ENCAPSULATION + _STAMP.pack(*stamp)


def tf_message_cdr(transforms: list[Transform]) -> bytes:
    """tf2_msgs/TFMessage: a sequence of geometry_msgs/TransformStamped (msg_tools.frames writes it from messages
    with rosbags; a recorder writes one per odometry message, from the odometry's bytes)."""
    out = bytearray(_U32.pack(len(transforms)))
    for stamp, frame, child, translation, rotation in transforms:
        out += bytes(-len(out) % 4) + _STAMP.pack(*stamp)
        out += _string(frame, len(out))
        out += _string(child, len(out))
        out += bytes(-len(out) % 8) + _POSE.pack(*translation, *rotation)
    return _ENCAPSULATION + bytes(out)


def pose_stamped_cdr(stamp: tuple[int, int], frame_id: str, position: tuple[float, float]) -> bytes:
    """geometry_msgs/PoseStamped at (x, y), z 0, yaw 0 (convert.point_to_pose_stamped's message)."""
    return _ENCAPSULATION + _STAMP.pack(*stamp) + _header_tail(frame_id) + \
        _POSE.pack(position[0], position[1], 0.0, *_IDENTITY)


def path_cdr(stamp: tuple[int, int], frame_id: str, points: Sequence[Sequence[float]]) -> bytes:
    """nav_msgs/Path through the points (x, y), each pose stamped and framed as the path, z 0, yaw 0
    (convert.waypoints_to_path's message)."""
    # A header: the frame name right after the stamp needs no padding, and the same bytes head every pose (a
    # pose starts 4-aligned: after the sequence's length, or 8-aligned after the doubles of the pose before).
    header = _STAMP.pack(*stamp) + _string(frame_id, 8)
    out = bytearray(header)
    out += bytes(-len(out) % 4) + _U32.pack(len(points))
    for point in points:
        out += header
        out += bytes(-len(out) % 8) + _POSE.pack(point[0], point[1], 0.0, *_IDENTITY)
    return _ENCAPSULATION + bytes(out)


def diagnostic_status_cdr(level: int, name: str, message: str, hardware_id: str,
                          values: Sequence[tuple[str, str]]) -> bytes:
    """diagnostic_msgs/DiagnosticStatus: level (a byte: 0 OK, 1 WARN, 2 ERROR, 3 STALE), name, message, hardware_id
    and the (key, value) pairs (convert.status_values gives them as convert.make_status writes them)."""
    out = bytearray(_BYTE.pack(level))
    for text in (name, message, hardware_id):
        out += _string(text, len(out))
    out += bytes(-len(out) % 4) + _U32.pack(len(values))
    for key, value in values:
        out += _string(key, len(out))
        out += _string(value, len(out))
    return _ENCAPSULATION + bytes(out)
