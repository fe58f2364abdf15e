"""Where the planner's scans were taken, and whether it may drive on them: the executor's side of perception.

Every LaserScan on `scan` is placed on the robot here, on the executor's thread, before perception (on a
planning pass) sees it: a scan in base_link (or no frame) sits at base_link; in a frame of its own, at that
frame's pose in base_link at the scan's stamp, from `laser_mount` when that parameter is set (robots without
TF), else from /tf_static and /tf (msg_tools.tf_buffer: any chain of frames, moving mounts interpolated). A
scan whose transform has not come waits for it up to `transform_tolerance` (tf2's message filter, Nav2's
transform_tolerance), retried at each control tick; a scan that cannot be placed, whose spec is not a scanner's,
stamped too far from the node's clock, or from a mount outside the robot (farther from base_link than the robot
reaches plus MOUNT_MARGIN) is not used. What a planning pass gets is a PlacedScan, made once and not changed:
the pass shares nothing else with this side.

Whether the robot may drive (`hold`): with `scan_mode` auto (the default) scans are required once any scan
has been heard, required from the start with `required`, and never with `ignored` (the topic is not followed:
a robot on its map alone). Required, the robot is held still (creep speed 0) while no scan was usable for
`scan_timeout`: status `blind`, ERROR naming the cause (WARN while the first scans wait for their transform,
for scan_timeout after the first was heard), until a usable scan comes; then it drives on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable

from diagnostic_msgs.msg import DiagnosticStatus
from sensor_msgs.msg import LaserScan

from fastep_core.footprint import Footprint
from fastep_ros.common import StartupError
from msg_tools import convert, frames
from msg_tools.tf_buffer import TfUnavailable

__all__ = ['MOUNT_MARGIN', 'PENDING', 'SCAN_MODES', 'PlacedScan', 'ScanSource', 'check_laser_mount',
           'declared_footprint', 'mount_problem', 'robot_reach']

SCAN_MODES = ('auto', 'required', 'ignored')
MOUNT_MARGIN = 0.1   # m: a laser may sit this far beyond the robot's extent (a bumper, a mast), no farther
PENDING = 5          # scans waiting for their transform at once, at most (the oldest is dropped first)
CREEP = 0.0          # m/s: how fast a robot held for its scans moves (it does not)


@dataclass(frozen=True)
class PlacedScan:
    """A scan and where it was taken: the scanner's pose in base_link at its stamp, and the robot's map pose
    then (None: not known, the state's is taken), both worked out on the executor's thread."""

    msg: LaserScan
    mount: frames.Pose2D
    robot_pose: tuple[float, float, float] | None = None

    @property
    def stamp(self) -> float:
        return convert.stamp_to_seconds(self.msg.header.stamp)

    def at(self, robot_pose: tuple[float, float, float] | None) -> PlacedScan:
        return replace(self, robot_pose=robot_pose)


def robot_reach(values: dict[str, Any]) -> tuple[float, str]:
    """How far the robot reaches from base_link (m), and what says so: the circumscribed radius of a `footprint`
    parameter where there is one, else robot_radius."""
    outline = declared_footprint(values)
    if outline is not None:
        return outline.radius, 'the footprint\'s circumscribed radius'
    return float(values['robot_radius']), 'robot_radius'


def declared_footprint(values: dict[str, Any]) -> Footprint | None:
    """The `footprint` parameter's outline, None where it is empty (Nav2's "[]" too): the circle of robot_radius;
    StartupError in one line for one that is not an outline or is on a model without a heading."""
    text = str(values.get('footprint') or '').strip()
    if text in ('', '[]'):
        return None
    try:
        outline = Footprint.parse(text, what='parameter footprint')
    except ValueError as exc:
        raise StartupError(str(exc)) from None
    if values.get('model', 'diff_drive') != 'diff_drive':
        raise StartupError(f'parameter footprint is for a diff_drive (it turns with the robot\'s heading); a '
                           f'{values.get("model")} is a circle of robot_radius')
    return outline


def mount_problem(mount: frames.Pose2D, reach: float, what: str) -> str:
    """Why a scanner at `mount` (in base_link) cannot be on the robot ('' when it can)."""
    distance = math.hypot(mount[0], mount[1])
    if distance <= reach + MOUNT_MARGIN:
        return ''
    return f'{distance:g} m from base_link, outside the robot ({what} {reach:g} m + {MOUNT_MARGIN:g} m)'


def check_laser_mount(value: Any, values: dict[str, Any]) -> frames.Pose2D | None:
    """The laser_mount parameter (None when empty); StartupError (one line) when it is not [x, y, yaw] or puts the
    laser outside the robot."""
    if not value:
        return None
    if len(value) != 3 or not all(math.isfinite(v) for v in value):
        raise StartupError(f'parameter laser_mount must be [x, y, yaw], three finite numbers, got {value}')
    mount = (float(value[0]), float(value[1]), float(value[2]))
    problem = mount_problem(mount, *robot_reach(values))
    if problem:
        raise StartupError(f'parameter laser_mount {list(mount)} puts the laser {problem}')
    return mount


class ScanSource:
    """The planner's scans, placed on the robot and watched (module docstring). Executor thread only."""

    def __init__(self, values: dict[str, Any], base_frame: str, topic: str, now: float,
                 lookup: Callable[[str, str, float | None], frames.Pose2D]) -> None:
        """`values`: the planner's parameters; `lookup(target, source, stamp)`: TF (TfListener.lookup_at)."""
        mode = values['scan_mode']
        if mode not in SCAN_MODES:
            raise StartupError(f'parameter scan_mode must be one of {", ".join(SCAN_MODES)}, got {mode!r}')
        self.mode: str = mode
        self.laser_mount = check_laser_mount(values['laser_mount'], values)
        self.reach = robot_reach(values)
        self.tolerance: float = values['transform_tolerance']
        self.timeout: float = values['scan_timeout']
        self.base_frame, self.topic, self.lookup = base_frame, topic, lookup
        self.started = now             # node time the wait for a required scan counts from
        self.heard = 0                 # scans that came
        self.first_heard = -math.inf   # node times: the first scan heard, the last one placed
        self.last_usable = -math.inf
        self.problem = ''              # why the newest scan was not used ('' when it was)
        self.waiting = ''              # what the scans waiting for their transform wait for ('' when none waits)
        self.pending: list[tuple[LaserScan, float]] = []   # (scan, when it came): waiting for their transform
        self.unplaced_since = math.inf   # when the first scan came of those not placed since the last one was

    @property
    def followed(self) -> bool:
        """Is the scan topic subscribed to?"""
        return self.mode != 'ignored'

    def restart(self, now: float) -> None:
        """The node's clock switched: times kept on the other clock count from now."""
        self.started = now
        self.first_heard = now if self.heard else -math.inf
        self.last_usable = -math.inf
        self.pending, self.waiting, self.unplaced_since = [], '', math.inf

    def take(self, msg: LaserScan, now: float) -> PlacedScan | None:
        """A scan that came: placed, or None (waiting for its transform, or not usable: `problem` says why)."""
        self.heard += 1
        if self.first_heard == -math.inf:
            self.first_heard = now
        try:
            convert.laser_scan_to_scan(msg)   # its spec: what perception would refuse
        except ValueError as exc:
            self.problem = f'scan ignored: {exc}'
            return None
        stamp = convert.stamp_to_seconds(msg.header.stamp)
        if stamp > 0.0 and abs(now - stamp) > self.timeout:
            when = f'{now - stamp:.2f} s ago' if now > stamp else f'{stamp - now:.2f} s ahead of this node\'s clock'
            self.problem = f'scan ignored: stamped {when} (scan_timeout {self.timeout:g} s)'
            return None
        self.pending.append((msg, now))
        del self.pending[:-PENDING]   # at 20 Hz, 0.25 s of scans: a transform that late is given up by time
        self.unplaced_since = min(self.unplaced_since, now)
        return self.retry(now)

    def retry(self, now: float) -> PlacedScan | None:
        """The newest waiting scan whose transform has come (the older ones are dropped), or None; scans that
        waited longer than transform_tolerance are given up, `problem` saying why."""
        newer = ''   # what the newer scans, still waiting, wait for
        for i in range(len(self.pending) - 1, -1, -1):
            msg, came = self.pending[i]
            mount, why = self.mount(msg)
            if mount is not None:
                del self.pending[:i + 1]
                self.problem, self.waiting, self.last_usable = '', newer, now
                self.unplaced_since = self.pending[0][1] if self.pending else math.inf
                return PlacedScan(msg, mount)
            if now - came > self.tolerance:
                del self.pending[:i + 1]   # given up, and every older one
                self.problem, self.waiting = why, newer
                return None
            newer = newer or why
        if newer and now - self.unplaced_since > self.tolerance:
            # No scan placed for longer than a transform may lag (the oldest waiting were dropped, PENDING).
            self.problem, self.waiting = newer, ''
            return None
        self.waiting = newer
        return None

    def mount(self, msg: LaserScan) -> tuple[frames.Pose2D | None, str]:
        """Where the scanner of `msg` sat in base_link at its stamp, or None and why not."""
        frame = msg.header.frame_id.lstrip('/')
        if frame in ('', self.base_frame, 'base_link'):
            return frames.IDENTITY, ''
        if self.laser_mount is not None:
            return self.laser_mount, ''
        stamp = convert.stamp_to_seconds(msg.header.stamp)
        try:
            mount = self.lookup(self.base_frame, frame, stamp if stamp > 0.0 else None)
        except TfUnavailable as exc:
            return None, f'scan frame {frame!r}: {exc} (laser_mount not set)'
        problem = mount_problem(mount, *self.reach)
        if problem:
            return None, f'scan frame {frame!r}: TF puts the laser {problem}: not used'
        return mount, ''

    def required(self) -> bool:
        return self.mode == 'required' or (self.mode == 'auto' and self.heard > 0)

    def hold(self, now: float) -> tuple[bytes, str]:
        """(level, why) the robot must not drive on what it sees: (OK, '') when it may (scans not required, or
        one usable within scan_timeout); WARN while the first scans wait (scan_timeout from the first heard, or
        from the start for a scan that is required and has not come), ERROR after."""
        if not self.required() or now - self.last_usable <= self.timeout:
            return DiagnosticStatus.OK, ''
        if not self.heard:
            level = DiagnosticStatus.WARN if now - self.started <= self.timeout else DiagnosticStatus.ERROR
            return level, f'no scan on {self.topic} (scan_mode required): held still'
        waiting = self.last_usable == -math.inf and now - self.first_heard <= self.timeout
        if waiting:
            return DiagnosticStatus.WARN, f'waiting for a usable scan: {self.problem or self.waiting or "none yet"}'
        if self.problem or self.waiting:
            return DiagnosticStatus.ERROR, f'{self.problem or self.waiting}; held still'
        since = 'ever' if self.last_usable == -math.inf else f'for {now - self.last_usable:.2f} s'
        return DiagnosticStatus.ERROR, f'scans stale: none usable {since} (scan_timeout {self.timeout:g} s); ' \
                                       f'held still'
