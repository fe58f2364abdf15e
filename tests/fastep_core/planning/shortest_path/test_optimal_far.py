"""The exact shortest path with walls that are points and coordinates far beyond the map: what a scan taken from
an absurd pose leaves in a belief (at 1e300 a wall's ends round to one point). Such walls are point obstacles,
obstacles that cannot reach the workspace change nothing, and a world too vast for the arithmetic is refused in one
line, never a ZeroDivisionError or a path through an obstacle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from fastep_core.errors import ParameterError
from fastep_core.geometry import Circle, Segment
from fastep_core.planning.shortest_path.optimal import shortest_path
from fastep_core.world import World

WORKSPACE = (0.0, 0.0, 20.0, 20.0)


def test_a_wall_whose_ends_are_one_point_is_gone_round_as_a_point() -> None:
    """From (2, 10) to (18, 10) past a point at (10, 10), keeping 1 m: two tangents of sqrt(63) and the arc between."""
    world = World.from_obstacles(WORKSPACE, [Segment((10.0, 10.0), (10.0, 10.0))])
    path = shortest_path(world, (2.0, 10.0), (18.0, 10.0), 1.0)
    assert path is not None
    assert path.length == pytest.approx(2.0 * math.sqrt(63.0) + math.pi - 2.0 * math.acos(1.0 / 8.0), rel=1e-9)
    assert world.obstacles.clearance(path.sample(0.01)).min() >= 1.0 - 1e-6


@pytest.mark.parametrize('wall', [Segment((1e300, 1e300), (1e300 + 0.1, 1e300)),   # rounds to one point
                                  Segment((1e17, 5.0), (1e17 + 1.0, 5.0)),         # too: 16 m between floats
                                  Segment((3e200, -1e200), (4e200, 2e200))])       # squares overflow
def test_a_wall_far_off_the_map_changes_nothing(wall: Segment) -> None:
    world = World.from_obstacles(WORKSPACE, [Circle((10.0, 10.0), 1.0), wall])
    near = World.from_obstacles(WORKSPACE, [Circle((10.0, 10.0), 1.0)])
    path, expected = shortest_path(world, (2.0, 10.0), (18.0, 10.0), 0.5), \
        shortest_path(near, (2.0, 10.0), (18.0, 10.0), 0.5)
    assert path is not None and expected is not None
    assert path.length == expected.length and np.array_equal(path.points, expected.points)


def test_an_obstacle_too_vast_for_the_arithmetic_is_refused_in_one_line() -> None:
    """A disc of radius 1e200 over the goal: its distances overflowed to inf, so the straight line through it
    counted as free."""
    world = World.from_obstacles(WORKSPACE, [Circle((1e200 + 15.0, 10.0), 1e200)])
    with pytest.raises(ParameterError, match=r'^the exact path needs obstacles within 1e\+150 m of the origin; one '
                                             r'near the workspace reaches 1e\+200 m$'):
        shortest_path(world, (2.0, 10.0), (18.0, 10.0), 0.5)


HUGE = st.floats(min_value=-1e300, max_value=1e300, allow_nan=False, allow_infinity=False)
SMALL = st.floats(min_value=-5.0, max_value=5.0, allow_nan=False, allow_infinity=False)


@st.composite
def far_walls(draw: st.DrawFn) -> list[Segment | Circle]:
    """Walls and discs anywhere beyond the workspace: a start that may be vast, a length that may round away."""
    out: list[Segment | Circle] = []
    for _ in range(draw(st.integers(1, 4))):
        x, y = draw(HUGE), draw(HUGE)
        if max(abs(x), abs(y)) < 100.0:
            x += 1000.0   # beyond the workspace and its border
        if draw(st.booleans()):
            out.append(Segment((x, y), (x + draw(SMALL), y + draw(SMALL))))
        else:
            out.append(Circle((x, y), draw(st.floats(min_value=0.01, max_value=10.0))))
    return out


@settings(max_examples=60, deadline=None)
@given(far_walls(), st.floats(min_value=0.1, max_value=2.0))
@example([Segment((1e300, 1e300), (1e300, 1e300))], 0.5)
@example([Segment((1e300, 1e300), (1e300 + 0.2, 1e300 - 0.2))], 0.5)
def test_obstacles_that_cannot_reach_the_workspace_never_change_the_path(far: list[Segment | Circle],
                                                                         clearance: float) -> None:
    near = [Circle((10.0, 10.0), 1.5), Segment((6.0, 4.0), (6.0, 16.0))]
    path = shortest_path(World.from_obstacles(WORKSPACE, [*near, *far]), (2.0, 10.0), (18.0, 12.0), clearance)
    expected = shortest_path(World.from_obstacles(WORKSPACE, near), (2.0, 10.0), (18.0, 12.0), clearance)
    assert expected is not None and path is not None
    assert path.length == expected.length and np.array_equal(path.points, expected.points)
