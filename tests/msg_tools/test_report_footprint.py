"""fastep-report judges a robot with a footprint by its outline, as fastep-sim does (the metadata carries it)."""

from __future__ import annotations

from pathlib import Path

import pytest

from fastep_core.scenario import parse_scenario
from msg_tools.recorded_run import load_run
from msg_tools.report import metrics, open_recording
from msg_tools.sim_mcap import record_run

BOX = [[0.35, 0.25], [-0.35, 0.25], [-0.35, -0.25], [0.35, -0.25]]


def test_a_recorded_box_robot_is_judged_by_its_outline_not_its_circumscribed_circle(tmp_path: Path) -> None:
    # A wall 0.32 m beside the way: the 0.25 m half-width box passes it; its circumscribed circle (0.43 m) cannot.
    scenario = parse_scenario({
        'workspace': [0, 0, 10, 4], 'obstacles': [{'segment': {'start': [0.0, 2.32], 'end': [10.0, 2.32]}}],
        'robots': [{'name': 'r1', 'model': 'diff_drive', 'start': [1, 2, 0.0], 'goal': [9, 2, 0.0],
                    'footprint': BOX}]})
    run, _ = record_run(scenario, 'fastep_route', 0, tmp_path / 'box.mcap')
    [robot] = metrics(load_run(open_recording(tmp_path / 'box.mcap')))['robots']
    assert run.robots[0].reached and not run.robots[0].collided
    assert not robot['collided'] and robot['min_clearance'] == pytest.approx(run.robots[0].min_clearance, abs=0.01)
    assert robot['min_clearance'] < 0.1   # the outline's clearance, not the circle's (which would be < 0)
