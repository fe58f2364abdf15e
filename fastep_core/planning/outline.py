"""A robot's outline in planning (Nav2's way): plan with the circle the box fits while it heads along its way,
check the placed polygon along every motion the robot is about to make.

A robot with a footprint (fastep_core/footprint.py) is planned with `planning_radius`: the inscribed radius (half
the width of a centred box) plus FOOTPRINT_MARGIN, not the circumscribed one, which no gap a Jackal drives through
in dense clutter leaves room for. The route, the swarm's constraints, detection, escapes and backing up keep that
circle; what only the outline can tell (a corner swung into a wall by a turn, the rear of the box backed into a
post) is the guard's and the recovery's check of the polygon along the predicted poses (`predicted_poses`).

What stays on the circumscribed circle (`body_radius`): other robots and movers. They are circles that move, and
the swarm, yielding and the guard separate circles by the sum of both radii; the robot's heading relative to
another robot is nobody's plan, so only the circle that covers every heading is safe there (and other robots
see this robot as that circle: what the simulator and the footprint topic announce).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.footprint import Footprint
from fastep_core.geometry import Obstacles
from fastep_core.kinematics.model import RobotModel
from fastep_core.planning.others import OtherRobot

__all__ = ['CORNER_SPACING', 'FOOTPRINT_MARGIN', 'MAX_POSES', 'body_radius', 'inflated', 'outline_clearance',
           'planning_radius', 'predicted_poses']

FloatArray = NDArray[np.float64]
FOOTPRINT_MARGIN = 0.02
"""m beyond the inscribed radius: the planning circle's slack for a box that does not head exactly along its way
(the controller's heading error on a curve); the guard's polygon check keeps the rest."""
CORNER_SPACING = 0.02
"""m: predicted poses lie at most this far apart at the outline's farthest vertex (a turn in place included)."""
MAX_POSES = 64
"""Predicted poses at most per check (a long braking horizon at full turn rate)."""


def planning_radius(footprint: Footprint, radius: float) -> float:
    """The circle the planners keep for a robot with `footprint` declared with `radius` (at least the circumscribed
    radius): the inscribed radius plus FOOTPRINT_MARGIN, plus whatever `radius` adds beyond the outline (a radius
    declared larger than the box is a margin kept all round)."""
    return footprint.inscribed + FOOTPRINT_MARGIN + max(0.0, radius - footprint.radius)


def body_radius(footprint: Footprint | None, radius: float) -> float:
    """The circle that covers the robot at every heading: what other robots are kept from."""
    return radius if footprint is None else max(radius, footprint.radius)


def inflated(others: Sequence[OtherRobot], extra: float) -> Sequence[OtherRobot]:
    """The other robots grown by `extra` (the circumscribed radius less the planning radius): every separation the
    planners compute as the sum of radii is then the circumscribed one. `others` itself when extra is 0."""
    if extra <= 0.0 or not len(others):
        return others
    return [replace(o, radius=o.radius + extra) for o in others]


def predicted_poses(model: RobotModel, state: FloatArray, command: FloatArray, horizon: float,
                    reach: float, spacing: float = CORNER_SPACING) -> FloatArray:
    """The poses (n, 3) of a unicycle (diff_drive) holding `command` for `horizon` s from `state`, the first being
    `state`: exact arcs (as DiffDrive.integrate), close enough that no point within `reach` of base_link moves more
    than `spacing` between two (at most MAX_POSES + 1)."""
    saturate = getattr(model, 'saturate', None)
    v, omega = saturate(command) if saturate is not None else (float(command[0]), float(command[1]))
    length = (abs(v) + reach * abs(omega)) * max(horizon, 0.0)
    n = int(min(max(math.ceil(length / spacing), 1), MAX_POSES))
    t = np.linspace(0.0, max(horizon, 0.0), n + 1)
    x0, y0, theta = float(state[0]), float(state[1]), float(state[2])
    turn = omega * t
    chord = v * t * np.sinc(turn / (2.0 * math.pi))   # np.sinc(x) = sin(pi x) / (pi x): sinc of turn / 2
    middle = theta + 0.5 * turn
    return np.column_stack([x0 + chord * np.cos(middle), y0 + chord * np.sin(middle), theta + turn])


def outline_clearance(footprint: Footprint, poses: FloatArray, obstacles: Obstacles, keep: float) -> FloatArray:
    """The footprint's signed clearance at each of `poses` (n, 3) (the first where the robot is) to the obstacles
    that can come within `keep` of it along them: shape (n,), inf where none can. An obstacle whose surface lies
    beyond the circumscribed radius + keep + the poses' farthest reach from the first is kept from at every pose
    (the outline lies within the radius of base_link), so it changes no decision made by comparing these with
    `keep` and with each other below keep; the rest, a handful in clutter, are measured exactly."""
    here = poses[0, :2]
    travel = float(np.max(np.hypot(poses[:, 0] - here[0], poses[:, 1] - here[1])))
    near = obstacles.distances(here) <= footprint.radius + travel + max(keep, 0.0) + 1e-6
    circles, walls = near[:obstacles.n_circles], near[obstacles.n_circles:]
    out = np.full(len(poses), np.inf)
    if circles.any():
        out = np.minimum(out, footprint.circle_distances(poses, obstacles.centers[circles],
                                                         obstacles.radii[circles]).min(axis=-1))
    if walls.any():
        out = np.minimum(out, footprint.segment_distances(poses, obstacles.starts[walls],
                                                          obstacles.ends[walls]).min(axis=-1))
    return out
