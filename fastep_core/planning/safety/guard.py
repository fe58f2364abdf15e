"""The guard: the last check between a planned command and the robot.

Whatever chose the command (the kinematic controller, a manoeuvre, a recovery), the guard predicts where one
control tick of it takes the robot and stops the robot instead when that point is
- within the robot's radius (plus `obstacle_margin`: a robot planning in what its scans show keeps a little more)
  of an obstacle surface and nearer than where the robot is now (a robot already that near may still move
  away), or
- within the robot's radius of a return of the latest laser scan (`scan_points`, when the robot has a laser) and
  nearer than now: whatever perception made of the scan (a circle fitted a little small, a wall a little off), the
  beams' own ends are where something is;
- within the sum of both radii of another robot, plus the other robot's travel in one tick (at max_speed, or
  at its own speed when it reports more: a mover) and a quarter of the clearance margin (odometry a tick old,
  a command a tick late on a real graph), and nearer than now.
The prediction integrates the command exactly as the plant does (RK4 for a tractor-trailer): a straight Euler
guess cuts the corner of a tight turn and once let a robot end a tick 2.3 mm inside its radius.

A robot with a footprint (planning/outline.py) is checked by its polygon instead of its circle against obstacles
and scan returns: placed at every pose of the command's motion over the check horizon (`predicted_poses`, a
turn in place too, where the corners sweep the circumscribed circle), its least clearance must keep
`obstacle_margin` from obstacle surfaces and stay off the returns, or be no nearer than the polygon is now: the
circle's rules, with the outline. Other robots stay circles, kept from the circumscribed one.
"""

from __future__ import annotations

import math
from enum import Enum
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.footprint import Footprint
from fastep_core.kinematics.model import RobotModel
from fastep_core.planning.limits import Limits
from fastep_core.planning.others import OtherRobot, other_arrays
from fastep_core.planning.outline import outline_clearance, predicted_poses
from fastep_core.planning.params import PlannerParams
from fastep_core.world import World

__all__ = ['NEAR_ROOM', 'Guard', 'ScanReturns', 'Stop']

FloatArray = NDArray[np.float64]
NEAR_ROOM = 0.5
"""m: while the robot is within this of where it took a scan, the guard reads only that scan's returns near there."""


class ScanReturns:
    """A scan's returns (map frame) as the guard reads them: all of them, and those within the robot's radius and
    NEAR_ROOM of where the robot was when it took the scan (made once per scan, on the planning pass). While the
    robot is within NEAR_ROOM of there, no other return comes within its radius, and the nearest one to it is
    either among those or farther than anything that would stop it: the same decisions from a few dozen points.

    Why: the control tick checks the returns two or three times. On a whole scan (720 points) each numpy call lets
    the GIL go (numpy does above 500 elements), and the control thread then waits up to a switch interval for the
    planning thread to give it back: most of the control tick's wall time in the robot harness (py-spy)."""

    def __init__(self, points: FloatArray, position: FloatArray, radius: float) -> None:
        self.points = np.asarray(points, dtype=float).reshape(-1, 2)
        self.centre = (float(position[0]), float(position[1]))
        self.radius = radius
        reach = np.hypot(self.points[:, 0] - self.centre[0], self.points[:, 1] - self.centre[1])
        self._reach = reach
        self.near: FloatArray = self.points[reach <= radius + NEAR_ROOM + 1e-6]   # 1e-6: rounding, in its favour
        self._near_outline: tuple[float, FloatArray] | None = None   # (circumscribed radius, its near returns)

    def around(self, a: FloatArray, b: FloatArray, radius: float) -> FloatArray:
        """The returns to measure positions a and b against, for a robot of this radius."""
        cx, cy = self.centre
        if radius == self.radius and math.hypot(float(a[0]) - cx, float(a[1]) - cy) <= NEAR_ROOM and \
                math.hypot(float(b[0]) - cx, float(b[1]) - cy) <= NEAR_ROOM:
            return self.near
        return self.points

    def around_outline(self, positions: FloatArray, reach: float) -> FloatArray:
        """The returns to measure an outline of circumscribed radius `reach` against at positions (n, 2): while all
        are within NEAR_ROOM of where the scan was taken, those within reach + NEAR_ROOM of there (a return
        farther off is outside the outline at every pose, so it decides nothing: see the class docstring)."""
        cx, cy = self.centre
        if float(np.max(np.hypot(positions[:, 0] - cx, positions[:, 1] - cy))) > NEAR_ROOM:
            return self.points
        if self._near_outline is None or self._near_outline[0] != reach:
            self._near_outline = (reach, self.points[self._reach <= reach + NEAR_ROOM + 1e-6])
        return self._near_outline[1]


class Stop(str, Enum):
    """Why the guard stopped the robot."""

    OBSTACLE = 'obstacle'
    ROBOT = 'robot'


class Guard:
    """Stops any motion into an obstacle or within reach of another robot (see the module docstring)."""

    def __init__(self, model: RobotModel, radius: float, params: PlannerParams,
                 footprint: Footprint | None = None, limits: Limits | None = None) -> None:
        # The model predicts each command's motion; the limits (params.limits unless given: Navigator.retune hands
        # model, parameters and limits over together) bound the other robots' speed.
        self.model, self.radius, self.params = model, radius, params
        self.limits = params.limits if limits is None else limits
        # None: the robot is its circle. With one, other robots come to the guard grown by the circumscribed
        # radius less `radius` (outline.inflated, the navigator's view of them), so they are kept from that circle.
        self.footprint = footprint
        # Kept beyond the radius from obstacle surfaces: 0 on a map that is the truth; a robot that plans in what
        # its scans show (fastep_core/perception) keeps PERCEPTION_MARGIN, as its surfaces are known only that well.
        self.obstacle_margin = 0.0
        self.scan_points: ScanReturns | None = None   # the latest scan's returns (None: no laser)
        self.stop: Stop | None = None   # why the last refused command was refused ...
        self.reason = ''                # ... in words, for the status
        # A disc of the world known to be obstacle-free: any point within (clearance - radius) of a point whose
        # clearance is known is safe (triangle inequality), so distances are recomputed only outside it. It
        # belongs to one world: a new map (a new World object) starts afresh.
        self._free: tuple[World, FloatArray, float] | None = None

    def check(self, world: World, state: FloatArray, command: FloatArray, dt: float,
              others: Sequence[OtherRobot]) -> FloatArray:
        """`command` itself (the same object: callers test identity) when it is safe, else zeros."""
        position = state[:2]
        after = self.model.integrate(state, command, dt)[:2]
        if self.footprint is not None:
            refused = self._outline_refusal(world, state, command, dt)
            if refused is not None:
                return self._refuse(command, Stop.OBSTACLE, refused)
            return self._robots(position, after, command, dt, others)
        obstacles = world.obstacles
        free = self._free
        if len(obstacles) and (free is None or free[0] is not world or
                               math.hypot(after[0] - free[1][0], after[1] - free[1][1]) >= free[2]):
            then = float(obstacles.clearance(after))
            keep = self.radius + self.obstacle_margin
            if then < keep and then < float(obstacles.clearance(position)):
                return self._refuse(command, Stop.OBSTACLE, 'stopped: an obstacle is within the robot radius ahead')
            self._free = (world, after, then - keep)
        returns = self.scan_points
        points = None if returns is None else returns.around(position, after, self.radius)
        if points is not None and len(points):
            then_points = float(np.min(np.hypot(points[:, 0] - after[0], points[:, 1] - after[1])))
            if then_points < self.radius and \
                    then_points < float(np.min(np.hypot(points[:, 0] - position[0], points[:, 1] - position[1]))):
                return self._refuse(command, Stop.OBSTACLE, 'stopped: the laser shows an obstacle within the robot '
                                                            'radius ahead')
        return self._robots(position, after, command, dt, others)

    def _outline_refusal(self, world: World, state: FloatArray, command: FloatArray, dt: float) -> str | None:
        """Why the footprint, placed along the command's motion over dt, may not go (None: it may)."""
        footprint = self.footprint
        assert footprint is not None
        reach = footprint.radius
        poses = predicted_poses(self.model, state, command, dt, reach)
        positions = poses[:, :2]
        obstacles = world.obstacles
        keep = self.obstacle_margin
        free = self._free
        # The free disc about a point of known clearance c: an outline within reach of its base_link stays
        # c - |offset| - reach from every surface, so poses within c - reach - keep of the point need no check.
        if len(obstacles) and (free is None or free[0] is not world or
                               float(np.max(np.hypot(positions[:, 0] - free[1][0],
                                                     positions[:, 1] - free[1][1]))) >= free[2]):
            clearances = outline_clearance(footprint, poses, obstacles, keep)
            then = float(clearances[1:].min())
            if then < keep and then < float(clearances[0]):
                return 'stopped: an obstacle is within the robot outline ahead'
            self._free = (world, np.array(state[:2], dtype=float),
                          float(obstacles.clearance(state[:2])) - reach - keep)
        returns = self.scan_points
        points = None if returns is None else returns.around_outline(positions, reach)
        if points is not None and len(points):
            gaps = footprint.circle_distances(poses, points, np.zeros(len(points))).min(axis=-1)
            then = float(gaps[1:].min())
            if then < 0.0 and then < float(gaps[0]):
                return 'stopped: the laser shows an obstacle within the robot outline ahead'
        return None

    def _robots(self, position: FloatArray, after: FloatArray, command: FloatArray, dt: float,
                others: Sequence[OtherRobot]) -> FloatArray:
        """`command`, or a stop giving way to another robot (module docstring)."""
        if len(others):
            # All the others at once (one by one, this loop was a tenth of a 40-robot run); the same numbers.
            centres, velocities, radii = other_arrays(others)
            # Another robot moves at most max_speed; a mover (a v2 world) may be faster: its own speed counts then.
            speed = np.hypot(*velocities.T)
            top = self.limits.max_speed
            if top > 0:
                speed = np.where(speed > top, speed, top)
            reach = speed * dt + 0.25 * self.params.clearance_margin
            gap_now = np.hypot(*(position - centres).T)
            gap_then = np.hypot(*(after - centres).T)
            giving_way = (gap_then < self.radius + radii + reach) & (gap_then < gap_now)
            if giving_way.any():
                other = others[int(np.argmax(giving_way))]
                return self._refuse(command, Stop.ROBOT, f'stopped: giving way to {other.name}')
        return command

    def _refuse(self, command: FloatArray, stop: Stop, reason: str) -> FloatArray:
        self.stop, self.reason = stop, reason
        return np.zeros_like(command)
