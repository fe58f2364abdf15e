"""The robot harness's phantom count (fastep_testing.robot_harness.count_phantoms) on beliefs drawn as the
planner publishes them."""

from __future__ import annotations

import numpy as np

from fastep_core.geometry import Circle, Segment
from fastep_core.perception.belief import Belief
from fastep_core.planning.others import OtherRobot
from fastep_testing.robot_harness import HarnessResult, count_phantoms
from fastep_testing.robot_worlds import world
from msg_tools.convert import belief_to_marker_array


def drawn(seen: tuple, movers: tuple) -> object:
    scenario = world('open_room')
    return belief_to_marker_array(Belief(0.0, scenario.world, (), seen, (), movers, np.zeros((0, 2))))


def test_movers_in_a_still_world_and_surfaces_where_the_truth_has_none_are_counted() -> None:
    on_wall = Segment((2.0, 0.1), (4.0, 0.1))             # the room's bottom wall: no phantom
    nowhere = Circle((5.0, 3.0), 0.2)                       # the middle of the empty room
    beside = Circle((5.0, 0.35), 0.2)                       # touching the wall: no phantom
    mover = OtherRobot('track 3', (5.0, 3.0), (0.5, 0.0), 0.3, mover=True)
    beliefs = [drawn((on_wall, beside), ()), drawn((on_wall, nowhere, Segment((3.0, 2.0), (3.0, 4.0))), (mover,)),
               drawn((), (mover, OtherRobot('track 4', (1.0, 1.0), (0.0, 0.5), 0.3, mover=True)))]
    result = count_phantoms(HarnessResult('open_room', True), world('open_room'), beliefs)
    assert (result.phantom_movers, result.most_movers, result.phantom_obstacles) == (2, 2, 2)
    clean = count_phantoms(HarnessResult('open_room', True), world('open_room'), beliefs[:1])
    assert (clean.phantom_movers, clean.most_movers, clean.phantom_obstacles) == (0, 0, 0)
