"""A ROS user's robot, as processes: a wall-time diff-drive base (fastep_testing.robot_base) scanning in frame
`base_laser`, base_link -> base_laser on /tf_static as robot_state_publisher sends it, and fastep-planner with
obstacle_source map and no laser_mount, in a corridor with a 0.6 m box its map lacks (the robot harness's
`unmapped_box`). With the transform the planner places its scans by TF and goes round the box; without it, it
says why and does not drive. Each run is on a DDS domain of its own; every process is stopped (robot_harness)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fastep_ros.sensors import CREEP
from fastep_testing.robot_harness import run_world


@pytest.mark.parametrize('mount', [(0.0, 0.0, 0.0), (0.2, 0.0, 0.0)])
def test_the_planner_places_its_scans_by_tf_static_and_goes_round_the_box(mount: tuple[float, float, float]) -> None:
    result = run_world('unmapped_box', laser_mount=mount, laser_frame='base_laser', timeout=120.0,
                       start_timeout=90.0)
    assert result.arrived, result
    assert not result.collided and result.min_clearance > 0.0, result
    assert result.scans > 0, result


def test_without_the_transform_the_planner_says_why_and_does_not_drive(tmp_path: Path) -> None:
    result = run_world('unmapped_box', laser_mount=(0.2, 0.0, 0.0), laser_frame='base_laser', laser_tf=False,
                       timeout=15.0, start_timeout=90.0, log_dir=tmp_path)
    assert not result.arrived and result.status == 'blind', result
    assert "scan frame 'base_laser'" in result.reason and 'no transform' in result.reason, result
    with np.load(tmp_path / 'base.npz') as data:
        track = data['track']
    speeds = np.abs(track[:, 4])
    assert speeds.max() <= CREEP + 1e-9, speeds.max()   # not one command to move
    assert np.hypot(track[-1, 1] - track[0, 1], track[-1, 2] - track[0, 2]) < 0.01
