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
