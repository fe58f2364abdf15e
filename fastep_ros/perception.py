"""A planner's laser perception: any sensor_msgs/LaserScan on `scan`, folded into what the robot believes.

The same perception as fastep-sim's robots with a `sensor` (fastep_core/perception): the map the planner was
given (its /obstacles or /map), less what a scan sees through, plus the still obstacles the scans show, and the
movers it tracks (a Kalman filter per track). The scanner is taken to sit at base_link, looking along the
robot's heading (a point mass: along +x of the map, its odometry's yaw being 0), which is how fastep's plants
publish it; its range, field of view and beams come from each message, its noise (which a LaserScan does not
carry) from the planner's `scan_noise`. A scan is placed at the robot's map pose at its stamp as the odometry
last gave it (the control loop predicts no further for it: a scan is a tick's worth of travel at most).

The planner then plans in the belief (a new World only when the still obstacles believed change) and avoids
the tracked movers beside the other robots, yielding to them as to any mover (fastep_core/planning/yielding.py);
`tracked_obstacles` (MarkerArray) shows the belief. Tracks older than TRACK_TIMEOUT (no scan) are forgotten.
"""

from __future__ import annotations

import importlib
from typing import Sequence

import numpy as np
from numpy.typing import NDArray
from sensor_msgs.msg import LaserScan

from fastep_core.perception.belief import RECENT_SCANS, Belief, Perception, perception_margin
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.recovery import RecentScans
from fastep_core.world import World
from msg_tools import convert

__all__ = ['PASS_IMPORTS', 'TRACK_TIMEOUT', 'ScanPerception']

FloatArray = NDArray[np.float64]
TRACK_TIMEOUT = 1.0   # seconds (node clock) after the last scan the tracked movers are still avoided
# What planning passes import on first use (the tracker of the first scan: scipy.optimize, ~0.3 s; a
# tractor-trailer's manoeuvre: scipy.sparse.csgraph), imported when the node makes its perception, before its
# control timer runs: on the planning thread, loading them held the GIL and the control tick waited for it
# (up to 0.3 s on a loaded machine, docs/real_time.md).
PASS_IMPORTS = ('scipy.optimize', 'scipy.sparse.csgraph')


class ScanPerception:
    """One planner's perception over its scans (module docstring)."""

    def __init__(self, noise: float) -> None:
        for name in PASS_IMPORTS:
            importlib.import_module(name)
        self.noise = noise
        self.perception: Perception | None = None
        self.spec_key: tuple[float, float, int] | None = None   # the scanner the perception was made for
        self.map_world: World | None = None
        self.last_scan = -np.inf
        self.scans = 0
        self.margin = 0.0   # the guard's margin beyond the radius once the robot plans in its scans

    def reset(self) -> None:
        """A new map: start believing it afresh at the next scan."""
        self.perception, self.map_world = None, None

    @property
    def returns(self) -> NDArray[np.float64]:
        """The latest scan's returns (map frame)."""
        return self.perception.returns if self.perception is not None else np.zeros((0, 2))

    @property
    def recent(self) -> RecentScans:
        """The free space the recent scans saw (where the robot may back up)."""
        return self.perception.recent if self.perception is not None else RecentScans(RECENT_SCANS)

    @property
    def belief(self) -> Belief | None:
        return None if self.perception is None else self.perception.belief

    def update(self, msg: LaserScan, t: float, pose: Sequence[float], map_world: World,
               others: Sequence[OtherRobot]) -> Belief:
        """Fold one scan taken at t from pose (x, y, heading) into the belief; ValueError (one line) for a scan
        that is not one. `map_world`: the planner's map; `others`: the other robots and movers it is told of
        (their points are not obstacles)."""
        scan = convert.laser_scan_to_scan(msg, t)
        spec = convert.laser_spec(msg, self.noise)
        key = (spec.range, spec.fov, spec.beams)
        self.margin = perception_margin(spec)
        if self.perception is None or self.map_world is not map_world or key != self.spec_key:
            self.perception, self.map_world, self.spec_key = Perception(spec, map_world), map_world, key
        belief = self.perception.update(t, pose, scan, others)
        self.last_scan, self.scans = t, self.scans + 1
        return belief

    def movers(self, t: float) -> list[OtherRobot]:
        """The movers tracked, while scans keep coming (TRACK_TIMEOUT)."""
        belief = self.belief
        if belief is None or not 0.0 <= t - self.last_scan <= TRACK_TIMEOUT:
            return []
        return list(belief.movers)
