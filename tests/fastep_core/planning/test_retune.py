"""Planner parameters set while a diff_drive base drives, as the ROS planner node sets them (issue 30 item 4).

The node's apply_parameters calls `Navigator.retune(params, make_robot(body, params)[1])`. The report: "setting
max_speed at runtime, even to its current value, left the robot at 0.13 m/s for the rest of the goal": the
navigator kept telling the old controller what the base got, so the new one ramped from rest every tick and
never passed max_acceleration x dt = 0.125 m/s. No ROS here: the core loop, tick by tick.
"""

from __future__ import annotations

import numpy as np
import pytest

from fastep_core.planning import PlannerParams
from fastep_core.planning.algorithms import make_navigator, make_robot
from fastep_core.planning.navigator import Navigator
from fastep_core.scenario import RobotSpec
from fastep_core.world import World

SPEC = RobotSpec('d1', 'diff_drive', (2.0, 10.0, 0.0), (58.0, 10.0), 0.35)
WORLD = World.from_obstacles([0, 0, 60, 20], [])
P = PlannerParams()


class Run:
    """A diff_drive base driving east across an empty world, one control tick at a time."""

    def __init__(self, algorithm: str) -> None:
        self.nav: Navigator = make_navigator(algorithm, SPEC, SPEC.radius, WORLD, P, 0)
        self.nav.set_goal(SPEC.goal)
        self.state, self.t = np.array(SPEC.start), 0.0

    def ticks(self, n: int) -> np.ndarray:
        speeds = []
        for _ in range(n):
            command = self.nav.update(self.t, self.state)
            self.state = self.nav.model.integrate(self.state, command, P.dt)
            self.t += P.dt
            speeds.append(float(command[0]))
        return np.array(speeds)

    def set(self, **changes: float) -> None:
        """What the planner node's apply_parameters does."""
        params = self.nav.params.with_overrides(changes)
        self.nav.retune(params, make_robot(SPEC, params)[1])


@pytest.mark.parametrize('algorithm', ['fastep', 'fastep_route'])
def test_max_speed_set_to_its_own_value_leaves_the_speed_as_it_was(algorithm):
    run = Run(algorithm)
    assert run.ticks(40)[-1] == pytest.approx(P.max_speed)
    run.set(max_speed=P.max_speed)
    after = run.ticks(40)
    assert after[-20:] == pytest.approx(P.max_speed)   # at 0.125 m/s for the rest of the goal before the fix


def test_max_speed_set_at_runtime_takes_effect_as_set():
    run = Run('fastep')
    run.ticks(40)
    for value in (0.5, 0.8, P.max_speed):
        run.set(max_speed=value)
        assert run.ticks(40)[-10:] == pytest.approx(value)


def test_a_new_controller_ramps_from_the_velocity_the_base_has():
    run = Run('fastep')
    before = run.ticks(40)
    run.set(max_speed=P.max_speed)
    after = run.ticks(10)
    change = np.abs(np.diff(np.concatenate([before[-1:], after])))
    assert change.max() <= P.max_acceleration * P.dt * (1 + 1e-9)
