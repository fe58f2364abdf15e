"""A differential-drive run through fastep-sim --mcap, fastep-report and the figures (issue 14 item 1)."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pytest

from msg_tools import convert, plots, report, sim_cli
from msg_tools.mcap_io import read_messages

SCENARIO = """\
name: diff_pair
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [10, 10], radius: 1.5}
robots:
  - name: d1
    model: diff_drive
    start: [2, 10, 3.14159]
    goal: [18, 10.5]
    radius: 0.35
  - name: d2
    model: diff_drive
    start: [10, 2, 0.0]
    goal: [10.5, 18]
    radius: 0.35
"""


@pytest.fixture(scope='module')
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp('diff')
    (folder / 'scenario.yaml').write_text(SCENARIO)
    mcap = folder / 'run.mcap'
    assert sim_cli.main([str(folder / 'scenario.yaml'), '--algorithm', 'fastep_route', '--mcap', str(mcap),
                         '--json', str(folder / 'run.json'), '--plot', str(folder / 'paths.png')]) == 0
    return {'folder': folder, 'mcap': mcap, 'sim': json.loads((folder / 'run.json').read_text())['runs'][0]}


def test_the_run_arrives_with_heading_rows(run: dict[str, Any]) -> None:
    for robot in run['sim']['robots']:
        assert robot['reached'] and not robot['collided'], robot['status']
        assert {len(row) for row in robot['trajectory']} == {4}


def test_odometry_carries_the_heading_and_a_body_frame_twist(run: dict[str, Any]) -> None:
    """Odometry yaw = theta, twist linear.x = v, linear.y = 0, angular.z = omega; cmd_vel is (v, omega)."""
    sim = {r['name']: np.array(r['trajectory']) for r in run['sim']['robots']}
    odom = [m for m in read_messages(run['mcap'], ['/d1/odom'])]
    cmd = [m for m in read_messages(run['mcap'], ['/d1/cmd_vel'])]
    assert len(odom) > 100 and len(cmd) >= len(odom) - 1
    first = odom[0].message
    assert convert.quaternion_to_yaw(first.pose.pose.orientation) == pytest.approx(3.14159)
    rows = {round(row[0], 6): row for row in sim['d1']}
    matched = 0
    for m in odom[1:]:
        t = round(m.log_time * 1e-9, 6)
        if t in rows:
            state = convert.odometry_to_state(m.message, 'diff_drive')
            np.testing.assert_allclose(state, rows[t][1:], atol=1e-6)   # the JSON rounds to 6 decimals
            matched += 1
    assert matched > 50
    turning = [m.message for m in odom[1:] if abs(m.message.twist.twist.angular.z) > 0.5]
    assert turning and all(msg.twist.twist.linear.y == 0.0 for msg in turning)
    # The command that moved the robot is its odometry twist: (v, omega) on cmd_vel = (linear.x, angular.z).
    for c, o in zip(cmd[:50], odom[1:51]):
        assert (c.message.linear.x, c.message.angular.z) == (o.message.twist.twist.linear.x,
                                                             o.message.twist.twist.angular.z)


def test_report_and_figures_draw_v_omega_and_headings(run: dict[str, Any]) -> None:
    recorded = report.load_run(report.open_recording(run['mcap']))
    assert {r.model for r in recorded.robots.values()} == {'diff_drive'}
    figures = report.figures(recorded)
    velocity = figures['velocity.png']
    assert [line.get_label() for line in velocity.axes[0].get_lines()] == ['v (m/s)', 'omega (rad/s)']
    arrows = [c for c in figures['paths.png'].axes[0].collections if type(c).__name__ == 'Quiver']
    assert len(arrows) == 2
    first = arrows[0]
    assert first.N == plots.HEADING_ARROWS
    assert math.atan2(first.V[0], first.U[0]) == pytest.approx(3.14159, abs=1e-6)   # d1 starts facing -x
    assert (run['folder'] / 'paths.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
