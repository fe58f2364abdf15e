"""A robot's footprint as geometry_msgs/PolygonStamped: how a fastep planner announces its robot to the others.

Nav2 names a robot's outline its footprint and draws a circular one as a polygon of 16 points about the
robot's base frame (nav2_costmap_2d makeFootprintFromRadius); fastep does the same with the safety circle, so
RViz and Foxglove draw it and any robot of the graph reads the radius back (footprint_radius: the largest
distance of a vertex from the frame's origin, which for a circle's polygon is the radius itself). A robot with a
polygon footprint (fastep_core.footprint.Footprint) announces the polygon itself (polygon_footprint), as Nav2's
costmap publishes its `footprint` parameter; footprint_radius then reads its circumscribed radius.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np
from geometry_msgs.msg import Point32, PolygonStamped
from numpy.typing import ArrayLike

__all__ = ['FOOTPRINT_POINTS', 'MAX_FOOTPRINT_RADIUS', 'base_frame', 'circle_footprint', 'footprint_radius',
           'polygon_footprint']

FOOTPRINT_POINTS = 16
MAX_FOOTPRINT_RADIUS = 1000.0   # m: a larger outline is a bad message, not a robot


def base_frame(namespace: str) -> str:
    """The robot's body frame in a namespace: '/r1' -> 'r1/base_link', '/' -> 'base_link' (REP-105 names)."""
    name = namespace.strip('/')
    return f'{name}/base_link' if name else 'base_link'


def circle_footprint(radius: float, frame_id: str, stamp: Any = None) -> PolygonStamped:
    """A circle of `radius` about the origin of `frame_id` as a polygon of FOOTPRINT_POINTS vertices on it."""
    msg = PolygonStamped()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.polygon.points = [Point32(x=radius * math.cos(a), y=radius * math.sin(a), z=0.0)
                          for a in (2.0 * math.pi * k / FOOTPRINT_POINTS for k in range(FOOTPRINT_POINTS))]
    return msg


def polygon_footprint(vertices: ArrayLike | Sequence[Sequence[float]], frame_id: str,
                      stamp: Any = None) -> PolygonStamped:
    """A polygon footprint (vertices (N, 2) in `frame_id`, e.g. Footprint.vertices) as a PolygonStamped, vertex
    for vertex in the order given (z = 0). ValueError for fewer than 3 vertices or a coordinate that is not finite
    (check the outline itself with fastep_core.footprint.Footprint.parse)."""
    points = np.asarray(vertices, dtype=float)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 3:
        raise ValueError(f'a polygon footprint needs 3 or more [x, y] vertices, got shape {points.shape}')
    if not np.isfinite(points).all():
        raise ValueError('a polygon footprint\'s vertices must be finite')
    msg = PolygonStamped()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.polygon.points = [Point32(x=float(x), y=float(y), z=0.0) for x, y in points]
    return msg


def footprint_radius(msg: PolygonStamped) -> float:
    """The radius of the smallest circle about the frame's origin that holds the footprint (m).

    ValueError for a footprint with no points, all at the origin, with coordinates that are not finite, or
    beyond MAX_FOOTPRINT_RADIUS."""
    points = msg.polygon.points
    if not points:
        raise ValueError('footprint has no points')
    radius = max(math.hypot(float(p.x), float(p.y)) for p in points)
    if not 0.0 < radius <= MAX_FOOTPRINT_RADIUS:   # also false for NaN
        raise ValueError(f'footprint radius {radius:g} m is not in (0, {MAX_FOOTPRINT_RADIUS:g}] m')
    return radius
