"""What a navigator does when the guard keeps its robot stopped: the hold breaker, and backing up.

- The hold breaker: two robots the guard holds for each other wait forever if each sees its own way as clear.
  After HOLD_BEFORE_STEP seconds held for another robot, the held robot plans a step round it.
- A robot counts as stopped until it is HOLD_RELEASE metres from where the guard first stopped it: a turn in
  place or a step of a few centimetres is not a way out, and counting it as one kept two face-to-face
  differential-drive robots twitching instead of backing up.
- Stuck: stopped HOLD_BEFORE_STEP seconds at a wall, or three times that at a robot. A robot that cannot turn in
  place first tries a manoeuvre (planning/recovery/manoeuvre_driver.py); otherwise it backs up for BACKUP_TIME seconds
  at `backup_speed` (Nav2's backup recovery), the move that gains the most room, checked by the guard every tick.
- Evidence: a robot never reverses into space it has no evidence is free. `reverse_free` sweeps the robot's disc
  along a command's path against the map and, with a laser, against the space recent scans saw (`SeenFree`: a
  270-degree laser is blind behind); BackUp given such a check (`free`) moves only while the next
  REVERSE_HORIZON seconds of its move pass it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from fastep_core.footprint import Footprint
from fastep_core.geometry import point_segment_distance
from fastep_core.kinematics.model import RobotModel
from fastep_core.kinematics.tractor_trailer import hitch_angle
from fastep_core.planning.limits import Limits
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.outline import outline_clearance, predicted_poses
from fastep_core.planning.params import PlannerParams
from fastep_core.planning.safety.guard import Stop
from fastep_core.sensing.laser import FULL_TURN_TOLERANCE, Scan
from fastep_core.world import World

__all__ = ['BACKUP_SPEED', 'BACKUP_TIME', 'HOLD_BEFORE_STEP', 'HOLD_RELEASE', 'MAX_RECOVERY_HITCH',
           'REVERSE_HORIZON', 'BackUp', 'RecentScans', 'SeenFree', 'StopTimer', 'backup_speed', 'free_room',
           'reverse_free', 'swept_centres']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]
HOLD_BEFORE_STEP = 1.0    # seconds a robot waits for another before stepping around it
HOLD_RELEASE = 0.25       # metres from where the guard first stopped it: until then the robot is still stopped
BACKUP_SPEED = 0.25       # m/s of the backing-up recovery ...
BACKUP_TIME = 4.0         # ... for this many seconds (1 m)
MAX_RECOVERY_HITCH = 1.0  # rad: a recovery move may not fold the trailer beyond this (or beyond where it is)
REVERSE_HORIZON = 0.2     # s: backing up with evidence goes on while this much of its move ahead is seen free
LOOK_TURN = 1.0            # rad/s: the turn in place of a robot that has no evidence to back up into
MOVED_AT_LEAST = 0.2       # m: RecentScans keeps a scan from where the robot has moved this far, or ...
TURNED_AT_LEAST = 0.3      # rad: ... turned this far, since the last scan it kept, ...
KEPT_SCANS = 50            # ... and this many at most (the free space of 10 m of way, whatever its age)

# reverse_free checks the swept disc at its centre and on rings of half and all its radius (8 and 16 points).
_RING_ANGLES = [np.linspace(0.0, 2.0 * math.pi, n, endpoint=False) for n in (8, 16)]
FOOTPRINT: FloatArray = np.concatenate([np.zeros((1, 2)),
                                        0.5 * np.column_stack([np.cos(_RING_ANGLES[0]), np.sin(_RING_ANGLES[0])]),
                                        np.column_stack([np.cos(_RING_ANGLES[1]), np.sin(_RING_ANGLES[1])])])
"""Points of the unit disc at which reverse_free checks the robot's disc (times its radius) about each centre."""


class StopTimer:
    """How long the guard has kept the robot stopped: for another robot (the hold breaker) and at all."""

    def __init__(self) -> None:
        self.held_since: float | None = None    # since when the guard holds the robot for another robot
        self.stuck_since: float | None = None   # since when the guard stops the robot without a break
        self.where: tuple[float, float] | None = None   # where the guard first stopped it

    def moved(self, position: FloatArray) -> None:
        """A command got through: the stop is over once the robot is HOLD_RELEASE from where it began."""
        if self.where is None or math.hypot(position[0] - self.where[0],
                                            position[1] - self.where[1]) >= HOLD_RELEASE:
            self.held_since = self.stuck_since = self.where = None

    def hold_breaker_due(self, t: float) -> bool:
        """Held for another robot HOLD_BEFORE_STEP seconds: time to step round it (the clock restarts)."""
        if self.held_since is not None and t - self.held_since >= HOLD_BEFORE_STEP:
            self.held_since = None
            return True
        return False

    def stopped(self, t: float, stop: Stop | None, position: FloatArray) -> bool:
        """Note a tick the guard stopped; True when the robot is stuck and a recovery is due."""
        if self.where is None:
            self.where = (float(position[0]), float(position[1]))
        if self.held_since is None and stop is Stop.ROBOT:
            self.held_since = t
        if self.stuck_since is None:
            self.stuck_since = t
        patience = HOLD_BEFORE_STEP * (1.0 if stop is Stop.OBSTACLE else 3.0)
        if t - self.stuck_since >= patience:
            self.stuck_since = self.where = None
            return True
        return False


def free_room(world: World, points: FloatArray, others: Sequence[OtherRobot]) -> FloatArray:
    """Free room at points (n, 2): distance to the nearest obstacle surface or other robot's body."""
    room = world.obstacles.clearance(points) if len(world.obstacles) else np.full(len(points), 1e9)
    for other in others:
        room = np.minimum(room, np.hypot(*(points - np.asarray(other.position)).T) - other.radius)
    return room


def backup_speed(limits: Limits | PlannerParams) -> float:
    """The backing-up recovery's speed: BACKUP_SPEED, or max_reverse_speed when that is lower (0: unlimited)."""
    cap = limits.max_reverse_speed
    return min(BACKUP_SPEED, cap) if cap > 0.0 else BACKUP_SPEED


MARGIN_DIRECTIONS = 8   # points round a point SeenFree.covers checks with a margin


def free_reach(scan: Scan) -> FloatArray:
    """How far each beam of the scan saw free space (m): to its return, range_max for +inf, none for no reading."""
    ranges = scan.ranges
    reach: FloatArray = np.where(np.isposinf(ranges), scan.range_max,
                                 np.where(np.isnan(ranges) | (ranges < scan.range_min), 0.0,
                                          np.minimum(ranges, scan.range_max))).astype(float)
    return reach


@dataclass(frozen=True)
class SeenFree:
    """The free space laser scans saw: each beam from its scan's origin out to what it hit, or to range_max where
    it hit nothing. All scans in stacked arrays (k scans, n beams in all), so a query is one numpy computation."""

    origins: FloatArray      # (k, 2) where each scan was taken (map frame)
    first: FloatArray        # (k,) the map-frame angle of each scan's first beam
    increment: FloatArray    # (k,) the angle between its beams (> 0)
    beams: IntArray          # (k,) how many beams it has
    full_turn: BoolArray     # (k,) whether they go all the way round
    offset: IntArray         # (k,) where its beams start in `reach`
    reach: FloatArray        # (n,) how far each beam saw free space (m)

    @classmethod
    def of_scans(cls, scans: Sequence[tuple[Scan, ArrayLike]],
                 reaches: Sequence[FloatArray] | None = None) -> SeenFree:
        """From (scan, pose of the scanner (x, y, heading) when it was taken) pairs (and each one's free_reach,
        when known). A reading of +inf (no return) saw free space to range_max; NaN, -inf and readings below
        range_min saw none. Scans with no beams or no positive increment are left out."""
        pairs = list(scans)
        known = list(reaches) if reaches is not None else [free_reach(scan) for scan, _ in pairs]
        kept = [(scan, np.asarray(pose, dtype=float), r) for (scan, pose), r in zip(pairs, known)
                if len(scan.ranges) and scan.angle_increment > 0.0 and math.isfinite(scan.angle_increment)]
        beams = np.array([len(scan.ranges) for scan, _, _ in kept], dtype=np.int64)
        increment = np.array([scan.angle_increment for scan, _, _ in kept], dtype=float)
        reach = [r for _, _, r in kept]
        return cls(origins=np.array([pose[:2] for _, pose, _ in kept], dtype=float).reshape(-1, 2),
                   first=np.array([pose[2] + scan.angle_min for scan, pose, _ in kept], dtype=float),
                   increment=increment, beams=beams,
                   full_turn=increment * beams >= 2.0 * math.pi - FULL_TURN_TOLERANCE,
                   offset=(np.cumsum(beams) - beams).astype(np.int64),
                   reach=np.concatenate(reach).astype(float) if reach else np.zeros(0))

    def covers(self, points: ArrayLike, margin: float = 0.0) -> BoolArray:
        """Which points (m, 2) some scan saw free: within its angle, and nearer its origin than both beams on either
        side of the point's bearing reach (the fan between two beams counts as seen, as a costmap clears it).
        margin > 0: the free space eroded by it, the points MARGIN_DIRECTIONS around each at that distance seen
        free too (a beam grazing a surface passes within the noise of it: what lies there was not seen free)."""
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        if margin > 0.0 and len(p):
            angles = np.linspace(0.0, 2.0 * math.pi, MARGIN_DIRECTIONS, endpoint=False)
            ring = margin * np.column_stack([np.cos(angles), np.sin(angles)])
            around = np.concatenate([p[:, None, :], p[:, None, :] + ring[None]], axis=1)     # (m, 1 + d, 2)
            covered: BoolArray = np.asarray(self.covers(around.reshape(-1, 2)).reshape(len(p), -1).all(axis=1))
            return covered
        if not len(self.reach) or not len(p):
            return np.zeros(len(p), dtype=bool)
        dx = p[:, None, 0] - self.origins[:, 0]                      # (m, k)
        dy = p[:, None, 1] - self.origins[:, 1]
        along = np.mod(np.arctan2(dy, dx) - self.first, 2.0 * math.pi) / self.increment   # in beams from the first
        last = self.beams - 1
        inside = self.full_turn | (along <= last + 1e-9)
        below = np.minimum(np.floor(along), last).astype(np.int64)
        above = np.where(self.full_turn, (below + 1) % self.beams, np.minimum(below + 1, last))
        below = np.where(self.full_turn, below % self.beams, below)
        reach = np.minimum(self.reach[self.offset + below], self.reach[self.offset + above])
        seen: BoolArray = (inside & (np.hypot(dx, dy) <= reach)).any(axis=1)
        return seen


class RecentScans:
    """The scans of the last `keep` seconds (by their time stamps) and the free space they saw.

    A scan from near where the last one kept was taken (within MOVED_AT_LEAST metres and TURNED_AT_LEAST
    radians) is not kept beside it: it shows little new, and a robot that stands or shuffles would otherwise soon
    keep only (KEPT_SCANS) scans from where it stands, none of the way it came (a 270-degree laser's blind
    quarter behind it: no evidence to back up into, and a robot held in dense clutter stood there for good).
    """

    def __init__(self, keep: float = 5.0) -> None:
        self.keep = keep
        self.scans: deque[tuple[Scan, FloatArray]] = deque(maxlen=KEPT_SCANS)
        self._reaches: deque[FloatArray] = deque(maxlen=KEPT_SCANS)   # each kept scan's free_reach
        self._seen: SeenFree | None = None

    def add(self, scan: Scan, pose: ArrayLike) -> None:
        """A scan taken from pose (x, y, heading); scans older than `keep` before it are forgotten."""
        where = np.array(pose, dtype=float)
        while self.scans and self.scans[0][0].time < scan.time - self.keep:
            self.scans.popleft()
            self._reaches.popleft()
            self._seen = None
        last = self.scans[-1][1] if self.scans else None
        if last is None or math.hypot(where[0] - last[0], where[1] - last[1]) >= MOVED_AT_LEAST or \
                abs(math.atan2(math.sin(where[2] - last[2]), math.cos(where[2] - last[2]))) >= TURNED_AT_LEAST:
            self.scans.append((scan, where))
            self._reaches.append(free_reach(scan))
            self._seen = None

    def seen(self) -> SeenFree:
        if self._seen is None:
            self._seen = SeenFree.of_scans(self.scans, self._reaches)
        return self._seen


def swept_centres(model: RobotModel, state: FloatArray, command: FloatArray, horizon: float,
                  spacing: float) -> FloatArray:
    """The reference point's path (n, 2) under `command` held for `horizon` seconds, at most `spacing` apart.

    In closed form: a holonomic model's straight run; for a steered one the unicycle's arc (diff_drive exactly)
    plus a tractor-trailer's lateral term (L omega / 2 across its heading: (L / 2) (cos, sin) of the heading's
    change), the exact solution of what its integrate steps with RK4.
    """
    c = np.asarray(command, dtype=float)
    if model.holonomic:
        length = math.hypot(c[0], c[1]) * horizon
    else:
        lever = 0.5 * float(getattr(model, 'length', 0.0)) if model.trailer else 0.0
        length = (abs(c[0]) + lever * abs(c[1])) * horizon
    t = np.linspace(0.0, horizon, int(min(max(math.ceil(length / spacing), 1), 10_000)) + 1)
    x0, y0 = float(state[0]), float(state[1])
    if model.holonomic:
        return np.column_stack([x0 + c[0] * t, y0 + c[1] * t])
    theta, turn = float(state[2]), c[1] * t
    chord = c[0] * t * np.sinc(turn / (2.0 * math.pi))   # np.sinc(x) = sin(pi x) / (pi x): sinc of turn / 2
    middle = theta + 0.5 * turn
    x = x0 + chord * np.cos(middle) + lever * (np.cos(theta + turn) - math.cos(theta))
    y = y0 + chord * np.sin(middle) + lever * (np.sin(theta + turn) - math.sin(theta))
    return np.column_stack([x, y])


def reverse_free(model: RobotModel, state: FloatArray, radius: float, command: FloatArray, horizon: float,
                 world: World, seen: SeenFree | None = None, others: Sequence[OtherRobot] = (),
                 margin: float = 0.0, footprint: Footprint | None = None) -> bool:
    """May the robot drive `command` (a reverse move, or any) for `horizon` seconds? Its disc of `radius` swept
    along the path must keep radius + margin from every obstacle surface, other robot and the workspace border
    (or, where it is nearer already, come no nearer), and, given `seen`, lie in the free space recent scans saw
    (the robot's own disc where it stands counts as free). Without `seen` (no laser) the map alone decides.
    A robot with a `footprint` (a diff_drive; `radius` its planning circle, planning/outline.py): the polygon
    placed along the motion must also keep `margin` from every obstacle surface (or come no nearer), and its
    vertices lie in the free space seen, so backing up or turning does not swing the box's rear into a post."""
    state = np.asarray(state, dtype=float)
    c = np.asarray(command, dtype=float)
    if not (np.isfinite(state).all() and np.isfinite(c).all() and horizon >= 0.0):
        return False
    keep = radius + margin
    here = state[:2]
    centres = swept_centres(model, state, c, horizon, max(radius, 0.01) / 4.0)
    a, b = centres[:-1], centres[1:]
    # The map: each stretch between two centres is a capsule of the disc; near already, no nearer than now.
    if len(world.obstacles):
        now = float(world.obstacles.clearance(here))
        if float(world.obstacles.path_clearance(a, b).min()) < min(keep, now) - 1e-9:
            return False
    if float(world.wall_distance(centres).min()) < min(keep, float(world.wall_distance(here))) - 1e-9:
        return False
    if len(others):
        where = np.array([o.position for o in others], dtype=float)
        radii = np.array([o.radius for o in others], dtype=float)
        gap = point_segment_distance(where[:, None, :], a, b).min(axis=1) - radii
        now_gap = np.hypot(*(where - here).T) - radii
        if (gap < np.minimum(keep, now_gap) - 1e-9).any():
            return False
    poses = None
    if footprint is not None:
        poses = predicted_poses(model, state, c, horizon, footprint.radius)
        if len(world.obstacles):
            outline = outline_clearance(footprint, poses, world.obstacles, margin)
            if float(outline[1:].min()) < min(margin, float(outline[0])) - 1e-9:
                return False
    if seen is None:
        return True
    # The evidence: the disc's centre and rings about every centre of the path, in space the beams passed.
    points = (centres[:, None, :] + keep * FOOTPRINT[None]).reshape(-1, 2)
    standing = np.hypot(*(points - here).T) <= radius + 1e-9
    if poses is not None and footprint is not None:
        # ... and the outline's vertices at every pose; those of the box where it stands count as free.
        corners = footprint.placed(poses[:, 0], poses[:, 1], poses[:, 2])
        standing = np.concatenate([standing, np.ones(corners.shape[1], dtype=bool),
                                   np.zeros((len(poses) - 1) * corners.shape[1], dtype=bool)])
        points = np.concatenate([points, corners.reshape(-1, 2)])
    return bool((standing | seen.covers(points)).all())


class BackUp:
    """The backing-up recovery: which move, and until when."""

    def __init__(self, model: RobotModel, speed: float = BACKUP_SPEED) -> None:
        self.model = model
        self.speed = speed                       # m/s of every move (backup_speed(params))
        self.until = -math.inf                   # backing up until this time ...
        self.command: FloatArray | None = None   # ... with this command (a steered robot's choice, kept)
        self.looking = False                     # turning in place to see behind it (no evidence to back into)

    def start(self, t: float) -> None:
        self.until, self.command = t + BACKUP_TIME, None

    def stop(self) -> None:
        self.until = -math.inf

    def active(self, t: float) -> bool:
        return t < self.until

    def drive(self, state: FloatArray, dt: float, room: Callable[[FloatArray], FloatArray],
              guard: Callable[[FloatArray], FloatArray],
              free: Callable[[FloatArray], bool] | None = None) -> FloatArray:
        """This tick's command as `guard(command)` lets it through; a refused one ends the recovery. `free`, when
        given, is the evidence check (reverse_free over REVERSE_HORIZON): a move it refuses is not chosen, and
        the recovery ends, standing still, once the move it drives is refused."""
        self.looking = False
        if free is None:
            command = self.choose(state, dt, room, lambda option: guard(option) is option)
        else:
            command = self.choose(state, dt, room, lambda option: guard(option) is option and free(option))
            if not free(command):
                if self.model.holonomic or not self.model.turns_in_place:
                    self.stop()
                    return np.zeros(2)
                # No scan has seen the space behind (a laser's blind quarter): turn in place to see it, and back
                # up once a move is seen free (chosen afresh).
                self.command, self.looking = None, True
                command = np.array([0.0, LOOK_TURN])
        guarded = guard(command)
        if guarded is not command:
            self.stop()
        return guarded

    def choose(self, state: FloatArray, dt: float, room: Callable[[FloatArray], FloatArray],
               allowed: Callable[[FloatArray], bool]) -> FloatArray:
        """This tick's command: `room(points)` is the free room at points, `allowed(command)` the guard's verdict."""
        if not self.model.holonomic:
            if self.command is None:
                self.command = self._steered_move(state, dt, room, allowed)
            return self.command
        h = 1e-4
        probes = state[:2] + np.array([[h, 0.0], [-h, 0.0], [0.0, h], [0.0, -h]])
        free = room(probes)
        away = np.array([free[0] - free[1], free[2] - free[3]])
        norm = float(np.hypot(*away))
        return away * (self.speed / norm) if norm > 0 else np.zeros(2)

    def _steered_move(self, state: FloatArray, dt: float, room: Callable[[FloatArray], FloatArray],
                      allowed: Callable[[FloatArray], bool]) -> FloatArray:
        """Of straight back and forward or back at full lock either way, the move that gains the most room over
        the recovery without folding the trailer (hitch angle over MAX_RECOVERY_HITCH) and whose first step
        the guard allows: a wall alongside pins straight moves too, and reversing a trailer far folds it.
        When every move would fold it, straight back (the first option) all the same: cutting moves short
        instead kept trailers straighter but landed fewer robots (docs/robustness.md, "Tractor-trailers before
        manoeuvres")."""
        max_steer = float(getattr(self.model, 'max_steer', 0.0))
        lock = self.speed * math.tan(max_steer) / max(getattr(self.model, 'length', 1.0), 1e-6)
        options = [np.array([v, w]) for v in (-self.speed, self.speed) for w in (0.0, -lock, lock)]
        scores = []
        for option in options:
            if not allowed(option):
                scores.append(-math.inf)
                continue
            probe, folds = state, False
            for _ in range(int(round(BACKUP_TIME / dt))):
                probe = self.model.integrate(probe, option, dt)
                folds = folds or (self.model.trailer and
                                  abs(hitch_angle(probe)) > max(MAX_RECOVERY_HITCH, abs(hitch_angle(state))))
            scores.append(-math.inf if folds else float(room(probe[None, :2])[0]))
        return options[int(np.argmax(scores))]
