"""Bases that do not do what they are told, by goals (fastep_testing/base_matrix.py), with the planner's defaults:
every goal reached stopped, no contact, overshoot at most 0.1 m, no loop, every heading goal at its heading."""

from __future__ import annotations

import pytest

from fastep_testing.base_matrix import BASES, GOALS, run_base


@pytest.mark.parametrize('goal', GOALS)
@pytest.mark.parametrize('base', BASES)
def test_every_base_reaches_every_goal_stopped_without_contact_or_loop(base: str, goal: str) -> None:
    run = run_base(base, goal)
    assert run.arrived, run.status
    assert run.min_clearance > 0.0
    assert run.final_distance <= 0.1 and run.overshoot <= 0.1 and run.after_reaching <= 1.0
    assert run.heading_error != run.heading_error or abs(run.heading_error) <= 0.25   # NaN: no heading
    assert run.ok


def test_the_kinematic_plant_arrives_as_before_a_tick_after_entering_the_goal() -> None:
    """What the closed loop changes for a base that does what it is told: the tick it takes to stop at the goal."""
    run = run_base('kinematic', 'open_floor')
    assert run.overshoot == 0.0 and run.after_reaching == 0.0 and run.arrival_speed == 0.0
