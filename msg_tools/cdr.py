"""Fast reads of the high-rate message types from their CDR bytes, without building rclpy messages.

rclpy's deserialize_message builds a full Python message (an Odometry is ~15 objects, each importing its field
types in __init__, and two covariance arrays: ~50 us here), which made reading a 10-minute recording take half a
minute, and a planner following 15 other robots spend most of a lock-step tick building their odometry. These
read only the needed float64 fields of little-endian CDR (encapsulation 00 01) with struct. Alignment is relative
to the payload after the 4-byte encapsulation header. Tests compare them with rclpy (tests/msg_tools/test_cdr.py).
A message shorter than the whole type (cut off) raises CdrError, as rclpy's decoder refuses it; bytes that are
not little-endian CDR give None (left to rclpy).
"""

from __future__ import annotations

import struct

__all__ = ['CdrError', 'float64_field', 'header_stamp', 'odometry_fields', 'twist_fields']

_CDR_LE = b'\x00\x01'
_U32 = struct.Struct('<I')
_ODOM = struct.Struct('<3d4d288x3d3d')  # position, orientation, (pose covariance), twist linear, angular
_ODOM_TAIL = 85 * 8                     # pose (7), its covariance (36), twist (6), its covariance (36)
_TWIST = struct.Struct('<3d3d')
_F64 = struct.Struct('<d')
_STAMP = struct.Struct('<iI')   # a header's stamp: sec, nanosec (right after the 4-byte CDR header)


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
