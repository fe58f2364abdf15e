"""The planner's scan perception told how far its pose may be off (fastep_ros/perception.py, ScanPerception): a
tolerance, the localization's covariance and the odometry's drift since it; the doorway of
tests/fastep_core/perception/test_localization_error.py seen from a pose off the truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.geometry import Segment
from fastep_core.perception.uncertainty import OdometryDrift, PoseUncertainty
from fastep_core.sensing.laser import LaserSpec, scan
from fastep_core.world import World
from fastep_ros.perception import ScanPerception
from msg_tools import convert

SPEC = LaserSpec(range=10.0, fov=1.5 * math.pi, beams=720, noise=0.01)
WALLS = [Segment((0.0, 5.0), (9.7, 5.0)), Segment((10.3, 5.0), (20.0, 5.0)),
         Segment((9.7, 5.0), (9.7, 5.3)), Segment((10.3, 5.0), (10.3, 5.3))]
MAP = World((0.0, 0.0, 20.0, 10.0), tuple(WALLS))


def approach(perception: ScanPerception) -> ScanPerception:
    starts, ends = np.array([w.start for w in WALLS]), np.array([w.end for w in WALLS])
    rng = np.random.default_rng(0)
    for k in range(60):
        truth = (10.0, 1.0 + 0.05 * k, math.pi / 2)
        placed = (truth[0] + 0.03, truth[1] - 0.02, truth[2] + math.radians(1.0))
        msg = convert.scan_to_laser_scan(scan(SPEC, truth, rng, 0.05 * k, starts=starts, ends=ends))
        perception.update(msg, 0.05 * k, placed, MAP, [])
    return perception


def test_told_the_uncertainty_the_planner_believes_its_map() -> None:
    blind = approach(ScanPerception(0.01))
    assert blind.belief is not None and blind.belief.seen_obstacles
    told = approach(ScanPerception(0.01, PoseUncertainty(0.04, math.radians(1.2))))
    assert told.belief is not None and not told.belief.seen_obstacles and not told.belief.dropped


def test_the_bound_from_the_covariance_and_the_drift_since_the_localization_pose() -> None:
    perception = approach(ScanPerception(0.01, PoseUncertainty(0.01, 0.0), OdometryDrift(0.01, 0.001)))
    assert perception.driven == pytest.approx(2.95)
    assert perception.pose_uncertainty().translation == pytest.approx(0.01 + 0.0295 + 0.5 * 0.001 * 2.95 ** 2)
    covariance = np.zeros(36)
    covariance[0] = covariance[7] = 1e-4
    covariance[35] = 1e-4
    perception.localized(covariance.tolist())
    assert perception.driven == 0.0
    bound = perception.pose_uncertainty()
    assert bound.translation == pytest.approx(0.01 + 0.03) and bound.yaw == pytest.approx(0.03)
    perception.localized([math.nan] * 36)    # a localizer that does not know: the tolerance and the drift only
    assert perception.pose_uncertainty() == PoseUncertainty(0.01, 0.0)
