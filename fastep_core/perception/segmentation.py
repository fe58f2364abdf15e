"""Scan points and their breakpoint segmentation into clusters, along the beam order.

A scan's finite readings become points in the map frame. Two neighbouring beams (consecutive indices; the
last and the first too for a full-turn scanner) belong to one cluster when their points are closer than the
breakpoint distance, the adaptive breakpoint detector of Borges and Aldon (2004, "Line extraction in 2D range
images for mobile robotics", J. Intell. Robot. Syst. 40): d_max = r sin(dphi) / sin(lambda - dphi) + 3 sigma,
with r the nearer reading, dphi the angle between the beams and lambda the shallowest incidence angle at which
a surface still counts as one (here 10 degrees), plus a floor. A beam that reads +inf breaks the cluster.
Vectorised: the breaks are one comparison over all beams and the labels their cumulative sum.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from fastep_core.sensing.laser import Scan

__all__ = ['BREAK_FLOOR', 'INCIDENCE', 'scan_points', 'segment']

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

INCIDENCE = math.radians(10.0)
"""lambda of the adaptive breakpoint detector: surfaces seen at shallower angles break into pieces."""
BREAK_FLOOR = 0.15
"""Metres: neighbouring points closer than this are always one cluster (close beams, tiny gaps)."""


def scan_points(scan: Scan, pose: FloatArray) -> tuple[FloatArray, IntArray]:
    """The map-frame points (n, 2) of the scan's finite readings from pose (x, y, heading), and their beams."""
    beams = np.flatnonzero(np.isfinite(scan.ranges))
    r = scan.ranges[beams]
    angles = pose[2] + scan.angle_min + scan.angle_increment * beams
    points = np.column_stack([pose[0] + r * np.cos(angles), pose[1] + r * np.sin(angles)])
    return points, beams


def segment(scan: Scan, points: FloatArray, beams: IntArray, noise: float = 0.0,
            full_turn: bool = True) -> IntArray:
    """A cluster label (0, 1, ...) for each point (points and beams from scan_points, possibly a subset kept in
    beam order): consecutive beams whose points lie within the breakpoint distance share a label."""
    n = len(points)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    ranges = scan.ranges[beams]
    gaps = np.diff(beams)                                              # beams apart (1: neighbours)
    dphi = np.abs(scan.angle_increment) * gaps
    near = np.minimum(ranges[:-1], ranges[1:])
    limit = near * np.sin(dphi) / np.sin(np.maximum(INCIDENCE - dphi, 1e-3)) + 3.0 * noise
    jump = np.hypot(*np.diff(points, axis=0).T)
    together = (gaps == 1) & (jump <= np.maximum(limit, BREAK_FLOOR))
    labels = np.concatenate([[0], np.cumsum(~together)]).astype(np.int64)
    # A full turn closes on itself: the last beam's cluster continues into the first one's.
    beam_count = len(scan.ranges)
    if full_turn and labels[-1] > 0 and beams[0] == 0 and beams[-1] == beam_count - 1:
        r = min(ranges[0], ranges[-1])
        d = abs(scan.angle_increment)
        wrap = r * math.sin(d) / math.sin(max(INCIDENCE - d, 1e-3)) + 3.0 * noise
        if float(np.hypot(*(points[0] - points[-1]))) <= max(wrap, BREAK_FLOOR):
            labels[labels == labels[-1]] = 0
            labels = np.unique(labels, return_inverse=True)[1].astype(np.int64)
    return labels
