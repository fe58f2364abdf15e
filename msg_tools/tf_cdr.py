"""tf2_msgs/msg/TFMessage read from its CDR bytes, without building a message: every transform of it, or only the
transforms of some child frames, found by searching the bytes.

A neighbour's TFMessage of 20,000 transforms took rclpy ~0.4 s to turn into messages, on the executor, ten times
a second. transform_count reads how many a message holds (O(1)); read_all reads them all with struct (for a
message of a bounded size); read_children finds a child frame's transform by searching the bytes for its
child_frame_id as CDR writes it (C speed, whatever the message's size) and reading the fields around it, so a
node that needs two edges of a huge message reads two transforms of it. Little-endian CDR (what every ROS 2
middleware here writes); None for anything else (the caller deserialises with rclpy instead).
"""

from __future__ import annotations

import functools
import re
import struct
from typing import Iterable

__all__ = ['MATCHES_MAX', 'NAME_MAX', 'TRIES', 'Edge', 'read_all', 'read_children', 'transform_count']

Edge = tuple[str, str, float, tuple[float, float, float, float, float, float, float]]
"""(parent, child, stamp in s, (tx, ty, tz, qx, qy, qz, qw)): one TransformStamped's fields; frames without a
leading '/' are the caller's business (as they came)."""

NAME_MAX = 1024
"""Bytes of a frame name read_children reads back to (REP-105 names are a few dozen): longer parents are not
found."""

TRIES = 8
"""Matches of any shape read_children checks last, from the end, when none shaped as a child is a transform."""

MATCHES_MAX = 64
"""Matches shaped as a child read_children checks per frame, from the end (one that is not a transform is a match
inside other bytes: a crafted message)."""

_CDR_LE = b'\x00\x01'
_U32 = struct.Struct('<I')
_HEAD = struct.Struct('<iII')    # stamp sec, nanosec, the frame_id's length
_STAMP = struct.Struct('<iI')
_POSE = struct.Struct('<7d')     # translation x y z, rotation x y z w
_START = 8                        # the first transform: after the 4-byte encapsulation and the sequence's length


def _pad(offset: int, to: int) -> int:
    """offset moved up to a multiple of `to` from the CDR payload (which starts after the 4-byte encapsulation)."""
    return offset + (-(offset - 4) % to)


def transform_count(data: bytes) -> int | None:
    """How many transforms the message says it holds (None: not little-endian CDR, or shorter than its header)."""
    if data[:2] != _CDR_LE or len(data) < _START:
        return None
    return int(_U32.unpack_from(data, 4)[0])


def _name(raw: bytes) -> str:
    return raw.decode('utf-8', 'replace')


def read_all(data: bytes) -> list[Edge] | None:
    """Every transform of the message, in order; None when it is not little-endian CDR. ValueError (one line) when
    the bytes end before the transforms it says it holds (a string's length past its end, or of zero)."""
    count = transform_count(data)
    if count is None:
        return None
    out: list[Edge] = []
    offset = _START
    try:
        for _ in range(count):
            offset = _pad(offset, 4)
            sec, nanosec, length = _HEAD.unpack_from(data, offset)
            offset += 12
            if length < 1 or offset + length > len(data):
                raise struct.error(f'a frame_id of {length} bytes at byte {offset}')
            parent = data[offset:offset + length - 1]
            offset = _pad(offset + length, 4)
            (length,) = _U32.unpack_from(data, offset)
            offset += 4
            if length < 1 or offset + length > len(data):
                raise struct.error(f'a child_frame_id of {length} bytes at byte {offset}')
            child = data[offset:offset + length - 1]
            offset = _pad(offset + length, 8)
            pose = _POSE.unpack_from(data, offset)
            offset += _POSE.size
            out.append((_name(parent), _name(child), sec + nanosec * 1e-9, pose))
    except struct.error as exc:
        raise ValueError(f'TFMessage cut off after {len(out)} of {count} transforms ({exc})') from exc
    return out


def _string_before(data: bytes, end: int) -> tuple[int, bytes] | None:
    """(where its length field starts, the name) of the CDR string whose padding ends at `end` (a 4-aligned
    offset), or None. Its NUL is the first zero of the (at most 4) bytes before `end`; its length field's high
    bytes are zero and its characters are not, so the last zero before the characters is the field's top byte."""
    for pad in range(4):
        stop = end - pad   # just after the NUL
        if stop - 2 < _START or data[stop - 1] != 0 or data[stop - 2] == 0:
            continue
        top = data.rfind(b'\x00', max(_START, stop - 2 - NAME_MAX - 4), stop - 1)
        start = top - 3
        if top < 0 or start < _START or (start - 4) % 4 or _U32.unpack_from(data, start)[0] != stop - start - 4:
            continue
        return start, data[start + 4:stop - 1]
    return None


def _is_string(data: bytes, offset: int) -> bool:
    """Whether a CDR string of a plausible length (a name) starts at `offset`."""
    if offset + 5 > len(data):
        return False
    (length,) = _U32.unpack_from(data, offset)
    stop = offset + 4 + length
    return 2 <= length <= NAME_MAX and stop <= len(data) and data[stop - 1] == 0 and \
        data.find(b'\x00', offset + 4, stop - 1) < 0


def _edge_at(data: bytes, at: int, child: str, length: int) -> Edge | None:
    """The transform whose child_frame_id's length field is at `at`, or None when the bytes around it are not one
    (a header's frame_id of that name is followed by another string; a child's by the doubles)."""
    after = at + 4 + length
    if _is_string(data, _pad(after, 4)):
        return None   # the name as another transform's parent
    pose_at = _pad(after, 8)
    if pose_at + _POSE.size > len(data):
        return None
    parent = _string_before(data, at)
    if parent is None or parent[0] - _STAMP.size < _START:
        return None
    sec, nanosec = _STAMP.unpack_from(data, parent[0] - _STAMP.size)
    return _name(parent[1]), child, sec + nanosec * 1e-9, _POSE.unpack_from(data, pose_at)


@functools.lru_cache(maxsize=64)
def _child_shaped(pattern: bytes) -> re.Pattern[bytes]:
    """Where `pattern` (a name as CDR writes it) starts a match NOT followed, after its padding (any bytes: CDR
    writers leave them as they were), by what follows a header's frame_id: a string's length of 2 to NAME_MAX and
    its first character (the child_frame_id after a parent). The regex engine skips the parent matches: a message
    of 20,000 transforms whose parent is the frame searched for costs one scan of its bytes (3 ms)."""
    pad = -len(pattern) % 4   # from a 4-aligned start: where the next field starts
    small = b'(?:[\x02-\xff][\x00-\x03]|[\x00-\x01][\x01-\x03]|[\x00][\x04])\x00\x00'   # 2 <= L <= 1024
    return re.compile(re.escape(pattern) + b'(?!' + b'.' * pad + small + b'[^\x00])', re.DOTALL)


def read_children(data: bytes, children: Iterable[str]) -> dict[str, Edge] | None:
    """The last transform of each child frame named that the message holds (a frame it does not hold is left
    out); None when it is not little-endian CDR. Per name: one regex scan of the bytes that passes over the name's
    matches as a parent, then the last MATCHES_MAX matches left checked from the end; if none is a transform,
    the last TRIES matches of any shape. A transform is missed only when it is followed by more than TRIES of its
    child's matches as a parent AND the 4 bytes after its name's padding read as a string's length with a character
    after them (none in 3000 random transforms of rclpy's serializer behind 200 such parents)."""
    if transform_count(data) is None:
        return None
    out: dict[str, Edge] = {}
    for child in children:
        raw = child.encode()
        if not raw or b'\x00' in raw:
            continue
        length = len(raw) + 1
        pattern = _U32.pack(length) + raw + b'\x00'
        found = None
        starts = [m.start() for m in _child_shaped(pattern).finditer(data, _START) if (m.start() - 4) % 4 == 0]
        for at in reversed(starts[-MATCHES_MAX:]):
            found = _edge_at(data, at, child, length)
            if found is not None:
                break
        end = len(data)
        for _ in range(TRIES if found is None else 0):
            at = data.rfind(pattern, _START, end)
            if at < 0:
                break
            end = at + len(pattern) - 1
            if (at - 4) % 4:
                continue
            found = _edge_at(data, at, child, length)
            if found is not None:
                break
        if found is not None:
            out[child] = found
    return out
