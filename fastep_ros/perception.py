"""A planner's laser perception: any sensor_msgs/LaserScan on `scan`, folded into what the robot believes.

The same perception as fastep-sim's robots with a `sensor` (fastep_core/perception): the map the planner was
given (its /obstacles or /map), less what a scan sees through, plus the still obstacles the scans show, and the
movers it tracks (a Kalman filter per track). The scanner is taken to sit at base_link, looking along the
robot's heading (a point mass: along +x of the map, its odometry's yaw being 0), which is how fastep's plants
publish it; its range, field of view and beams come from each message, its noise (which a LaserScan does not
carry) from the planner's `scan_noise`. A scan is placed at the robot's map pose at its stamp as the odometry
last gave it (the control loop predicts no further for it: a scan is a tick's worth of travel at most).

A scan is placed at the robot's estimated pose, which may be off: `uncertainty` (a fixed tolerance, metres and
radians), plus the localizer's pose covariance when it gives one (`localized`, SIGMAS standard deviations), plus
`drift`'s bound for the distance driven since the last localization pose (or since the start, without a
localizer) is how far it may be off, and a return within its share of that (translation + yaw x range) of a mapped
obstacle is that obstacle, not a new one (fastep_core/perception/uncertainty.py).

The planner then plans in the belief (a new World only when the still obstacles believed change) and avoids
the tracked movers beside the other robots, yielding to them as to any mover (fastep_core/planning/safety/yielding.py);
`tracked_obstacles` (MarkerArray) shows the belief. Tracks older than TRACK_TIMEOUT (no scan) are forgotten.
"""

from __future__ import annotations

import importlib
import math
from typing import Sequence

import numpy as np
from numpy.typing import NDArray
from sensor_msgs.msg import LaserScan

from fastep_core.perception.belief import RECENT_SCANS, Belief, Perception, perception_margin
from fastep_core.perception.uncertainty import NO_DRIFT, NO_UNCERTAINTY, SIGMAS, OdometryDrift, PoseUncertainty
from fastep_core.planning.others import OtherRobot
from fastep_core.planning.recovery.back_up import RecentScans
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

    def __init__(self, noise: float, uncertainty: PoseUncertainty = NO_UNCERTAINTY,
                 drift: OdometryDrift = NO_DRIFT) -> None:
        for name in PASS_IMPORTS:
            importlib.import_module(name)
        self.noise = noise
        self.uncertainty = uncertainty     # the tolerance of every pose a scan is placed at
        self.drift = drift                 # odometry's drift per metre driven since the last localization pose
        self.covariance = NO_UNCERTAINTY   # the last localization pose's covariance, as a bound
        self.driven = 0.0                  # metres between scan poses since the last localization pose
        self._last_pose: tuple[float, float] | None = None
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

    def localized(self, covariance: Sequence[float] | None = None, sigmas: float = SIGMAS) -> None:
        """A localization pose arrived (geometry_msgs/PoseWithCovarianceStamped): its covariance (36 values,
        row-major, x y z roll pitch yaw) bounds the poses from now on (None, or one with a nan or negative
        variance: no bound of its own), and the odometry's drift starts again from it."""
        try:
            self.covariance = NO_UNCERTAINTY if covariance is None else \
                PoseUncertainty.from_covariance(covariance, sigmas)
        except ValueError:
            self.covariance = NO_UNCERTAINTY
        self.driven = 0.0

    def pose_uncertainty(self) -> PoseUncertainty:
        """How far the pose of the next scan may be off: the tolerance, the localization's covariance and the
        odometry's drift since it."""
        return self.uncertainty + self.covariance + self.drift.bound(self.driven)

    def update(self, msg: LaserScan, t: float, pose: Sequence[float], map_world: World,
               others: Sequence[OtherRobot], uncertainty: PoseUncertainty | None = None) -> Belief:
        """Fold one scan taken at t from pose (x, y, heading) into the belief; ValueError (one line) for a scan
        that is not one. `map_world`: the planner's map; `others`: the other robots and movers it is told of
        (their points are not obstacles); `uncertainty`: of this pose (None: pose_uncertainty())."""
        scan = convert.laser_scan_to_scan(msg, t)
        spec = convert.laser_spec(msg, self.noise)
        key = (spec.range, spec.fov, spec.beams)
        self.margin = perception_margin(spec)
        if self.perception is None or self.map_world is not map_world or key != self.spec_key:
            self.perception, self.map_world, self.spec_key = Perception(spec, map_world), map_world, key
        x, y = float(pose[0]), float(pose[1])
        if self._last_pose is not None:
            self.driven += math.hypot(x - self._last_pose[0], y - self._last_pose[1])
        self._last_pose = (x, y)
        told = self.pose_uncertainty() if uncertainty is None else uncertainty
        belief = self.perception.update(t, pose, scan, others, uncertainty=told)
        self.last_scan, self.scans = t, self.scans + 1
        return belief

    def movers(self, t: float) -> list[OtherRobot]:
        """The movers tracked, while scans keep coming (TRACK_TIMEOUT)."""
        belief = self.belief
        if belief is None or not 0.0 <= t - self.last_scan <= TRACK_TIMEOUT:
            return []
        return list(belief.movers)
