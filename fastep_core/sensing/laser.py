"""A planar laser scanner: ray casting against circles and segments, with sensor_msgs/LaserScan semantics.

A scan is a fan of `beams` rays from the scanner's position, centred on its heading; each ray's range is the distance
to the nearest circle (obstacle, mover where it is at the scan's time, robot) or segment (a wall of zero thickness).
All beams against all obstacles are one numpy computation; each obstacle is cast only on the beams within its angle
(fan_hits), with the same ranges, bit for bit, as all beams x all obstacles (cast, hit_distances). Beams: for
fov < 2 pi both edges included, angle_min = -fov / 2, angle_increment = fov / (beams - 1); for a full turn (within
FULL_TURN_TOLERANCE of 2 pi) no beam twice, angle_min = -pi, angle_increment = 2 pi / beams, angle_max = pi -
angle_increment; one beam: straight ahead, increment = fov. range_min is 0; a beam with no surface within range_max
reads +inf; a scanner inside a circle reads 0; grazing a circle or ending on a segment's end counts as a hit. Noise:
Gaussian `noise` from the caller's Generator, one draw per beam hit or not (so the stream does not depend on the
world), clipped into [range_min, range_max]: never negative, never turning a hit into a miss, and a miss stays one.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ['DEFAULT_BEAMS', 'DEFAULT_FOV', 'DEFAULT_NOISE', 'DEFAULT_RANGE', 'FULL_TURN_TOLERANCE', 'MAX_BEAMS',
           'NEAR', 'WAY_BEAMS', 'WAY_DISTANCE', 'FanDirections', 'LaserSpec', 'Scan', 'beam_angles', 'cast',
           'fan_directions', 'fan_hits', 'hit_distances', 'main', 'way_problem']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

DEFAULT_RANGE = 10.0
"""Metres: a typical indoor 2D lidar (e.g. a TurtleBot 4's RPLIDAR A1 reaches 12 m)."""
DEFAULT_FOV = 2.0 * math.pi
"""A full turn, as most 2D lidars on small robots."""
DEFAULT_BEAMS = 360
"""One beam per degree over the default fov."""
DEFAULT_NOISE = 0.01
"""Metres, the standard deviation of each reading (about what low-cost lidars specify at a few metres)."""
MAX_BEAMS = 10_000
"""The most beams a sensor may have: more than any planar lidar gives per scan (4 x a 0.1-degree scanner)."""
FULL_TURN_TOLERANCE = 1e-3
"""Radians: a fov within this of 2 pi is a full turn (files write 6.2832 or 6.283 for 2 pi)."""
NEAR = 0.01
"""Metres: an obstacle whose surface (a segment: whose line) comes this close to the scanner is cast on every
beam (fan_hits): seen from so near, its angle is too wide or too ill-conditioned to window."""


@dataclass(frozen=True)
class LaserSpec:
    """A scanner's parameters (a scenario robot's `sensor`): range_max (m), fov (rad), beams, noise (m), and where
    it sits on the robot: mount (x, y, yaw) in the robot's frame (m, rad; the reference point facing ahead)."""

    range: float = DEFAULT_RANGE
    fov: float = DEFAULT_FOV
    beams: int = DEFAULT_BEAMS
    noise: float = DEFAULT_NOISE
    mount: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.range) and self.range > 0.0):
            raise ValueError(f'range must be > 0, got {self.range}')
        if not (math.isfinite(self.fov) and 0.0 < self.fov <= 2.0 * math.pi + FULL_TURN_TOLERANCE):
            raise ValueError(f'fov must be in (0, 2 pi], got {self.fov}')
        if isinstance(self.beams, bool) or not isinstance(self.beams, int) or not 1 <= self.beams <= MAX_BEAMS:
            raise ValueError(f'beams must be an integer in [1, {MAX_BEAMS}], got {self.beams}')
        if not (math.isfinite(self.noise) and self.noise >= 0.0):
            raise ValueError(f'noise must be >= 0, got {self.noise}')
        if len(self.mount) != 3 or not all(math.isfinite(v) for v in self.mount):
            raise ValueError(f'mount must be three finite numbers [x, y, yaw], got {self.mount}')

    def pose_on(self, robot: Sequence[float]) -> tuple[float, float, float]:
        """The scanner's pose (x, y, heading) on a robot at `robot` (x, y, heading of the robot's frame)."""
        x, y, heading = float(robot[0]), float(robot[1]), float(robot[2])
        mx, my, myaw = self.mount
        if mx == 0.0 and my == 0.0 and myaw == 0.0:
            return x, y, heading   # at the reference point: the pose itself, to the bit
        c, s = math.cos(heading), math.sin(heading)
        turned = heading + myaw
        return x + c * mx - s * my, y + s * mx + c * my, math.atan2(math.sin(turned), math.cos(turned))

    @property
    def full_turn(self) -> bool:
        return self.fov >= 2.0 * math.pi - FULL_TURN_TOLERANCE


@dataclass(frozen=True)
class Scan:
    """One scan, field for field what a sensor_msgs/LaserScan carries (angles relative to the heading)."""

    angle_min: float
    angle_max: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: FloatArray           # (beams,), +inf where no return within range_max, nan where the reading is not one
    time: float = 0.0            # simulated seconds at which it was taken

    def angles(self) -> FloatArray:
        """Each beam's angle relative to the heading."""
        angles: FloatArray = self.angle_min + self.angle_increment * np.arange(len(self.ranges), dtype=float)
        return angles


def beam_angles(spec: LaserSpec) -> tuple[float, float, FloatArray]:
    """(angle_min, angle_increment, angles) of the spec's beams, relative to the heading (module docstring)."""
    n = spec.beams
    if n == 1:
        return 0.0, float(min(spec.fov, 2.0 * math.pi)), np.zeros(1)
    if spec.full_turn:
        increment = 2.0 * math.pi / n
        return -math.pi, increment, -math.pi + increment * np.arange(n, dtype=float)
    increment = spec.fov / (n - 1)
    return -spec.fov / 2.0, increment, -spec.fov / 2.0 + increment * np.arange(n, dtype=float)


WAY_AHEAD = 2.0 * math.atan(0.5)
"""Radians centred straight ahead a scanner must see: the robot's way from one robot diameter ahead on (its
half-width r at 2 r). A narrower scanner saw an obstacle dead ahead as a few points, and the robot drove in."""
WAY_BEAMS = 3
"""Beams that must fall across the robot's width at WAY_DISTANCE (or the range, if shorter)."""
WAY_DISTANCE = 3.0
"""Metres ahead where the beams are counted: nearer obstacles are denser in beams still."""


def way_problem(angle_min: float, angle_max: float, increment: float, beams: int, range_max: float,
                mount_yaw: float, radius: float) -> str:
    """Why a scanner cannot see a robot's way ('' when it can): WAY_AHEAD in view (from a scanner mounted at
    mount_yaw), and beams no further apart than WAY_BEAMS across the robot's width (2 radius) at WAY_DISTANCE.
    Angles as in a LaserScan (beam_angles for a LaserSpec)."""
    half = 0.5 * WAY_AHEAD
    centre, span = wrap(mount_yaw + 0.5 * (angle_min + angle_max)), angle_max - angle_min
    full = beams * increment >= 2.0 * math.pi - FULL_TURN_TOLERANCE
    if not full and abs(centre) + half > 0.5 * span:
        return (f'its beams span {span:.3g} rad around {centre:.3g} rad; the way ahead needs at least '
                f'{-half:.3f} to {half:.3f} rad in view')
    distance = min(range_max, WAY_DISTANCE) if range_max > 0.0 else WAY_DISTANCE   # a message's 0 or NaN
    width = 2.0 * math.atan(radius / distance)
    if beams < WAY_BEAMS or increment > width / WAY_BEAMS:
        return (f'{beams} beam{"s" if beams > 1 else ""} {increment:.3g} rad apart: a robot of radius {radius:g} '
                f'm needs {WAY_BEAMS} across its width at {distance:g} m, {width / WAY_BEAMS:.3g} rad apart at most')
    return ''


def wrap(angle: float) -> float:
    """An angle in [-pi, pi)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def _points(value: ArrayLike | None) -> FloatArray:
    return np.zeros((0, 2)) if value is None else np.asarray(value, dtype=float).reshape(-1, 2)


def _circle_terms(origin: FloatArray, centres: FloatArray,
                  radii: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Each circle's terms of the beam-circle equation: o - c (x and y) and |o - c|^2 - r^2."""
    fx, fy = origin[0] - centres[:, 0], origin[1] - centres[:, 1]
    c = fx * fx + fy * fy - radii * radii
    return fx, fy, c


def _circle_distances(dx: FloatArray, dy: FloatArray, fx: FloatArray, fy: FloatArray,
                      c: FloatArray) -> FloatArray:
    """Distance along beams d to circles (their _circle_terms), elementwise with broadcasting: the first crossing
    t >= 0 of |origin + t d - c| = r, 0 from inside a circle, inf when the line misses or the circle is behind."""
    b = dx * fx + dy * fy                                                   # d . (o - c)
    disc = b * b - c
    root = np.sqrt(np.maximum(disc, 0.0))
    near = -b - root
    hit = (disc >= 0.0) & (near >= 0.0)
    out = np.where(hit, near, np.inf)
    return np.where(c <= 0.0, 0.0, out)                                     # inside or on the circle


def _circle_hits(origin: FloatArray, dx: FloatArray, dy: FloatArray, centres: FloatArray,
                 radii: FloatArray) -> FloatArray:
    """Distance along each beam (rows) to each circle (columns), _circle_distances."""
    return _circle_distances(dx[:, None], dy[:, None], *_circle_terms(origin, centres, radii))


def _segment_terms(origin: FloatArray, starts: FloatArray,
                   ends: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Each segment's terms of the beam-segment equations: e = end - start, w = start - origin, w x e."""
    ex, ey = ends[:, 0] - starts[:, 0], ends[:, 1] - starts[:, 1]
    wx, wy = starts[:, 0] - origin[0], starts[:, 1] - origin[1]
    return ex, ey, wx, wy, wx * ey - wy * ex


def _segment_distances(dx: FloatArray, dy: FloatArray, ex: FloatArray, ey: FloatArray, wx: FloatArray,
                       wy: FloatArray, w_cross_e: FloatArray) -> FloatArray:
    """Distance along beams d to segments (their _segment_terms), elementwise with broadcasting, inf for a miss.

    Beam o + t d, segment p + u e: t = (w x e) / (d x e), u = (w x d) / (d x e) with w = p - o; a hit needs
    t >= 0 and 0 <= u <= 1. A beam along a segment (d x e = 0, w x d = 0) hits its nearer end ahead, or at 0
    when the scanner is on it.
    """
    denom = dx * ey - dy * ex                                               # d x e
    w_cross_d = wx * dy - wy * dx                                           # w x d
    crossing = denom != 0.0
    safe = np.where(crossing, denom, 1.0)
    t = w_cross_e / safe
    u = w_cross_d / safe
    out = np.where(crossing & (t >= 0.0) & (u >= 0.0) & (u <= 1.0), t, np.inf)
    # Collinear: the beam's line contains the segment; the distances to its ends along the beam.
    along = ~crossing & (w_cross_d == 0.0)
    if along.any():
        t0 = dx * wx + dy * wy
        t1 = t0 + dx * ex + dy * ey
        low, high = np.minimum(t0, t1), np.maximum(t0, t1)
        first = np.where(low >= 0.0, low, np.where(high >= 0.0, 0.0, np.inf))
        out = np.where(along, first, out)
    return out


def _segment_hits(origin: FloatArray, dx: FloatArray, dy: FloatArray, starts: FloatArray,
                  ends: FloatArray) -> FloatArray:
    """Distance along each beam (rows) to each segment (columns), _segment_distances."""
    return _segment_distances(dx[:, None], dy[:, None], *_segment_terms(origin, starts, ends))


def _inputs(origin: ArrayLike, angles: ArrayLike, circles: ArrayLike | None, radii: ArrayLike | None,
            starts: ArrayLike | None, ends: ArrayLike | None) -> tuple[FloatArray, ...]:
    """origin (2,), angles (B,), centres (C, 2), radii (C,), starts and ends (S, 2) as float arrays, checked."""
    o = np.asarray(origin, dtype=float).reshape(2)
    a = np.asarray(angles, dtype=float).reshape(-1)
    centres, r = _points(circles), np.asarray(radii if radii is not None else [], dtype=float).reshape(-1)
    if len(centres) != len(r):
        raise ValueError(f'{len(centres)} circle centres but {len(r)} radii')
    a_ends, b_ends = _points(starts), _points(ends)
    if len(a_ends) != len(b_ends):
        raise ValueError(f'{len(a_ends)} segment starts but {len(b_ends)} ends')
    return o, a, centres, r, a_ends, b_ends


def _beam_windows(low: FloatArray, width: FloatArray, every: NDArray[np.bool_], first: float, increment: float,
                  beams: int) -> tuple[IntArray, IntArray]:
    """The (beam, obstacle) pairs of a uniform fan (beam k at first + increment k, increment > 0) whose beam
    lies within its obstacle's angular window [low, low + width] (radians, any turn), one beam more on each
    side; every beam for the obstacles marked `every`. Each pair once, grouped by obstacle in order."""
    turn = 2.0 * math.pi
    every = every | ~(width < turn - 6.0 * increment)      # the two turns' windows below could overlap
    rel = np.mod(np.where(every, first, low) - first, turn)  # the window's start after the first beam, [0, 2 pi)
    # Each window, and the same window one turn back (a beam's angle lies in [first, first + 2 pi]): (n, 2).
    window = (rel[:, None] - _TURNS) / increment
    lows = np.maximum(np.floor(window) - 1.0, 0.0)
    highs = np.minimum(np.ceil(window + (np.where(every, 0.0, width) / increment)[:, None]) + 1.0, beams - 1.0)
    if every.any():
        lows[every] = 0.0
        highs[every] = (beams - 1.0, -1.0)
    counts = np.maximum(highs - lows + 1.0, 0.0).astype(np.int64).ravel()
    owners = np.repeat(np.arange(len(every)).repeat(2), counts)
    offsets = np.cumsum(counts) - counts
    beam_index = np.arange(len(owners), dtype=np.int64) + np.repeat(lows.astype(np.int64).ravel() - offsets, counts)
    return beam_index, owners


_TURNS = np.array([0.0, 2.0 * math.pi])


FanDirections = tuple[FloatArray, FloatArray, FloatArray]
"""A fan's beams: their angles (map frame), cosines and sines (fan_directions)."""


def fan_directions(heading: float, angle_min: float, increment: float, beams: int) -> FanDirections:
    """fan_hits' beams: their angles (map frame) and the angles' cosines and sines, for `directions`."""
    angles: FloatArray = heading + (angle_min + increment * np.arange(beams, dtype=float))
    return angles, np.cos(angles), np.sin(angles)


def fan_hits(origin: ArrayLike, heading: float, angle_min: float, increment: float, beams: int,
             circles: ArrayLike | None = None, radii: ArrayLike | None = None, starts: ArrayLike | None = None,
             ends: ArrayLike | None = None,
             directions: FanDirections | None = None) -> tuple[IntArray, IntArray, FloatArray]:
    """hit_distances of a scan's beams (at heading + angle_min + increment k, k < beams: Scan.angles() turned by
    the heading) as (beam, obstacle, distance) triples, only for the pairs where the beam can meet the obstacle:
    every pair left out is a miss (+inf in hit_distances), and every distance given is hit_distances' own for
    those angles, bit for bit (the same arithmetic on the same numbers).

    A beam can only meet an obstacle within the angle the obstacle subtends from the origin (a circle's centre
    direction +- asin(r / distance), a segment's arc between its ends), so only the beams in that window, and one
    more on each side for rounding, are cast. An obstacle within NEAR of the origin (a segment: of its line) is
    cast on every beam, so are all obstacles when increment is not > 0. Obstacles are numbered circles first.
    `directions`: fan_directions(heading, angle_min, increment, beams), made once for several calls on one scan.
    """
    angles, dx, dy = directions if directions is not None else fan_directions(heading, angle_min, increment, beams)
    o, a, centres, r, a_ends, b_ends = _inputs(origin, angles, circles, radii, starts, ends)
    return _fan_hits(o, a, dx, dy, increment, centres, r, a_ends, b_ends)


def _fan_hits(o: FloatArray, a: FloatArray, dx: FloatArray, dy: FloatArray, increment: float, centres: FloatArray,
              r: FloatArray, a_ends: FloatArray, b_ends: FloatArray) -> tuple[IntArray, IntArray, FloatArray]:
    """fan_hits of checked inputs: beams at angles a = a[0] + increment k (up to rounding), directions (dx, dy)."""
    n = len(a)
    windowed = n > 0 and math.isfinite(increment) and increment > 0.0
    turn = 2.0 * math.pi
    # Angular windows: a circle's centre direction +- its half-angle, a segment's arc from its start to its end.
    cx, cy = centres[:, 0] - o[0], centres[:, 1] - o[1]
    distance = np.hypot(cx, cy)
    size = np.abs(r)                                                      # the arithmetic sees r^2 only
    half = np.arcsin(np.minimum(size / np.maximum(distance, NEAR), 1.0))
    circle_every = ~((distance - size >= NEAR) & windowed)                # nan-safe: a nan is cast on every beam
    sx, sy, ex, ey = a_ends[:, 0] - o[0], a_ends[:, 1] - o[1], b_ends[:, 0] - o[0], b_ends[:, 1] - o[1]
    start_angle = np.arctan2(sy, sx)
    sweep = np.mod(np.arctan2(ey, ex) - start_angle + math.pi, turn) - math.pi
    line_distance = np.abs(sx * ey - sy * ex) / np.maximum(np.hypot(ex - sx, ey - sy), 1e-300)   # 0: a point
    segment_every = ~((line_distance >= NEAR) & windowed)
    beam, owner = _beam_windows(np.concatenate([np.arctan2(cy, cx) - half, start_angle + np.minimum(sweep, 0.0)]),
                                np.concatenate([2.0 * half, np.abs(sweep)]),
                                np.concatenate([circle_every, segment_every]), float(a[0]) if n else 0.0,
                                increment if windowed else 1.0, n)
    split = int(np.searchsorted(owner, len(r)))                          # circles' pairs first
    beam_c, circle, beam_s, segment = beam[:split], owner[:split], beam[split:], owner[split:] - len(r)
    fx, fy, c = _circle_terms(o, centres, r)
    to_circles = _circle_distances(dx[beam_c], dy[beam_c], fx[circle], fy[circle], c[circle])
    sex, sey, wx, wy, w_cross_e = _segment_terms(o, a_ends, b_ends)
    to_segments = _segment_distances(dx[beam_s], dy[beam_s], sex[segment], sey[segment], wx[segment],
                                     wy[segment], w_cross_e[segment])
    return beam, owner, np.concatenate([to_circles, to_segments])


def cast(origin: ArrayLike, angles: ArrayLike, range_max: float, circles: ArrayLike | None = None,
         radii: ArrayLike | None = None, starts: ArrayLike | None = None,
         ends: ArrayLike | None = None) -> FloatArray:
    """True ranges (no noise) of beams from `origin` at absolute `angles` (map frame): the nearest circle
    (centres (C, 2), radii (C,)) or segment (starts, ends (S, 2)) surface along each, +inf beyond range_max."""
    o, a, centres, r, a_ends, b_ends = _inputs(origin, angles, circles, radii, starts, ends)
    best = _nearest(o, np.cos(a), np.sin(a), centres, r, a_ends, b_ends)
    return np.where(best <= range_max, best, np.inf)


def _fan_cast(o: FloatArray, a: FloatArray, increment: float, range_max: float, centres: FloatArray,
              r: FloatArray, a_ends: FloatArray, b_ends: FloatArray) -> FloatArray:
    """cast of a scan's beams (angles a[0] + increment k): each obstacle on the beams that can meet it only
    (fan_hits), the same ranges bit for bit."""
    dx, dy = np.cos(a), np.sin(a)
    best = np.full(len(a), np.inf)
    beam, _, distance = _fan_hits(o, a, dx, dy, increment, centres, r, a_ends, b_ends)
    np.minimum.at(best, beam, distance)
    # A beam on which several obstacles read 0 (the scanner touches them) may have +0.0 and -0.0, whose minimum's
    # sign depends on the order they are met in: those beams are cast on all obstacles as cast does, so even the
    # sign of a zero reading is the same.
    zero = distance == 0.0
    if zero.any():
        touching = np.flatnonzero(np.bincount(beam[zero], minlength=len(a)) > 1)
        best[touching] = _nearest(o, dx[touching], dy[touching], centres, r, a_ends, b_ends)
    return np.where(best <= range_max, best, np.inf)


def _nearest(o: FloatArray, dx: FloatArray, dy: FloatArray, centres: FloatArray, r: FloatArray, a_ends: FloatArray,
             b_ends: FloatArray) -> FloatArray:
    """The nearest surface along each beam (direction dx, dy), every beam against every obstacle."""
    best = np.full(len(dx), np.inf)
    if len(centres):
        best = np.minimum(best, _circle_hits(o, dx, dy, centres, r).min(axis=1))
    if len(a_ends):
        best = np.minimum(best, _segment_hits(o, dx, dy, a_ends, b_ends).min(axis=1))
    return best


def hit_distances(origin: ArrayLike, angles: ArrayLike, circles: ArrayLike | None = None,
                  radii: ArrayLike | None = None, starts: ArrayLike | None = None,
                  ends: ArrayLike | None = None) -> FloatArray:
    """Distance along each beam (rows) to each obstacle (columns: the circles, then the segments) on its own,
    +inf where the beam misses it: what a scan would read if that obstacle were the only one."""
    o, a, centres, r, a_ends, b_ends = _inputs(origin, angles, circles, radii, starts, ends)
    dx, dy = np.cos(a), np.sin(a)
    return np.concatenate([_circle_hits(o, dx, dy, centres, r), _segment_hits(o, dx, dy, a_ends, b_ends)], axis=1)


def scan(spec: LaserSpec, pose: Sequence[float], rng: np.random.Generator | None = None, t: float = 0.0,
         circles: ArrayLike | None = None, radii: ArrayLike | None = None, starts: ArrayLike | None = None,
         ends: ArrayLike | None = None) -> Scan:
    """One scan from `pose` (x, y, heading) against circles and segments as they are at time t.

    Moving circles and other robots are circles at their positions at t. `rng` draws the noise (required
    when spec.noise > 0; one normal per beam).
    """
    x, y, heading = float(pose[0]), float(pose[1]), float(pose[2])
    angle_min, increment, relative = beam_angles(spec)
    o, a, centres, r, a_ends, b_ends = _inputs((x, y), heading + relative, circles, radii, starts, ends)
    ranges = _fan_cast(o, a, increment, spec.range, centres, r, a_ends, b_ends)
    if spec.noise > 0.0:
        if rng is None:
            raise ValueError('a scanner with noise needs a Generator')
        noisy = ranges + rng.normal(0.0, spec.noise, len(ranges))
        ranges = np.where(np.isfinite(ranges), np.clip(noisy, 0.0, spec.range), np.inf)
    angle_max = angle_min + increment * (spec.beams - 1)
    return Scan(angle_min, angle_max, increment, 0.0, spec.range, ranges, t)


# ----------------------------------------------------------------------------------------------- main

def main(argv: Sequence[str] | None = None) -> int:
    """Print one scan of a small world: a circle ahead, a wall to the left, a robot behind."""
    parser = argparse.ArgumentParser(description=main.__doc__)
    parser.add_argument('--beams', type=int, default=16)
    parser.add_argument('--fov', type=float, default=DEFAULT_FOV)
    parser.add_argument('--range', type=float, default=DEFAULT_RANGE)
    parser.add_argument('--noise', type=float, default=DEFAULT_NOISE)
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args(argv)
    try:
        spec = LaserSpec(args.range, args.fov, args.beams, args.noise)
    except ValueError as exc:
        parser.error(str(exc))
    start = time.perf_counter()
    result = scan(spec, (0.0, 0.0, 0.0), np.random.default_rng(args.seed),
                  circles=[(5.0, 0.0), (-3.0, 0.0)], radii=[1.0, 0.5],
                  starts=[(-4.0, 2.0)], ends=[(4.0, 2.0)])
    elapsed = time.perf_counter() - start
    print(f'angle_min {result.angle_min:.4f}  angle_max {result.angle_max:.4f}  '
          f'angle_increment {result.angle_increment:.4f}  range [{result.range_min:g}, {result.range_max:g}]  '
          f'({elapsed * 1e3:.3f} ms)')
    for angle, reading in zip(result.angles(), result.ranges):
        print(f'{math.degrees(angle):8.2f} deg  {reading:8.3f}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
