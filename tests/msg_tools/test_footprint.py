"""A robot's footprint message: the safety circle as a polygon, and its radius read back."""

from __future__ import annotations

import math

import pytest
from geometry_msgs.msg import Point32

from msg_tools.footprint import FOOTPRINT_POINTS, base_frame, circle_footprint, footprint_radius


def test_a_circle_footprint_gives_its_radius_back() -> None:
    msg = circle_footprint(0.35, 'r1/base_link')
    assert msg.header.frame_id == 'r1/base_link' and len(msg.polygon.points) == FOOTPRINT_POINTS
    assert footprint_radius(msg) == pytest.approx(0.35, abs=1e-7)   # Point32 holds float32


def test_a_polygon_footprint_counts_by_its_farthest_corner() -> None:
    msg = circle_footprint(1.0, 'base_link')
    msg.polygon.points = [Point32(x=0.3, y=0.2), Point32(x=-0.3, y=0.2), Point32(x=-0.3, y=-0.2),
                          Point32(x=0.3, y=-0.2)]   # a 0.6 m x 0.4 m box
    assert footprint_radius(msg) == pytest.approx(math.hypot(0.3, 0.2), abs=1e-7)


@pytest.mark.parametrize('points, words', [
    ([], 'no points'),
    ([Point32()], 'not in (0'),
    ([Point32(x=math.nan)], 'not in (0'),
    ([Point32(x=math.inf)], 'not in (0'),
    ([Point32(x=5000.0)], 'not in (0'),
])
def test_a_bad_footprint_is_a_value_error(points: list[Point32], words: str) -> None:
    msg = circle_footprint(1.0, 'base_link')
    msg.polygon.points = points
    with pytest.raises(ValueError, match=words.replace('(', r'\(')):
        footprint_radius(msg)


def test_base_frames() -> None:
    assert base_frame('/r1') == 'r1/base_link'
    assert base_frame('/fleet/r1') == 'fleet/r1/base_link'
    assert base_frame('/') == 'base_link'


def test_a_polygon_footprint_is_its_vertices_in_order() -> None:
    from fastep_core.footprint import Footprint
    from msg_tools.footprint import polygon_footprint

    box = Footprint.parse('[[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]')
    msg = polygon_footprint(box.vertices, 'r1/base_link')
    assert msg.header.frame_id == 'r1/base_link'
    assert [c for p in msg.polygon.points for c in (p.x, p.y, p.z)] == pytest.approx(
        [0.254, 0.215, 0.0, -0.254, 0.215, 0.0, -0.254, -0.215, 0.0, 0.254, -0.215, 0.0], abs=1e-7)
    assert footprint_radius(msg) == pytest.approx(box.radius, abs=1e-7)
    assert len(polygon_footprint([[0.1, 0.0], [0.0, 0.1], [-0.1, -0.1]], 'base_link').polygon.points) == 3
    with pytest.raises(ValueError, match='3 or more'):
        polygon_footprint([[0.1, 0.0], [0.0, 0.1]], 'base_link')
    with pytest.raises(ValueError, match='finite'):
        polygon_footprint([[0.1, 0.0], [0.0, math.nan], [-0.1, -0.1]], 'base_link')


def test_a_simulated_robot_with_a_footprint_records_its_polygon(tmp_path) -> None:
    from fastep_core.scenario import parse_scenario
    from msg_tools.mcap_io import read_messages
    from msg_tools.sim_mcap import record_run

    box = [[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]
    scenario = parse_scenario({'workspace': [0, 0, 6, 4], 'robots': [
        {'name': 'r1', 'model': 'diff_drive', 'start': [1.0, 1.0, 0.0], 'goal': [2.0, 1.0], 'footprint': box},
        {'name': 'r2', 'model': 'diff_drive', 'start': [1.0, 3.0, 0.0], 'goal': [2.0, 3.0], 'radius': 0.3}]})
    out = tmp_path / 'run.mcap'
    record_run(scenario, 'fastep_route', 0, out)
    shapes = {m.topic: [c for p in m.message.polygon.points for c in (p.x, p.y)]
              for m in read_messages(out, ['/r1/footprint', '/r2/footprint'])}
    assert shapes['/r1/footprint'] == pytest.approx([c for v in box for c in v], abs=1e-7)
    assert len(shapes['/r2/footprint']) == 2 * FOOTPRINT_POINTS
