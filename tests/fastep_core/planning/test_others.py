"""Other robots as one tick's shared arrays (planning/others.py), as the simulator hands them out."""

from __future__ import annotations

import numpy as np

from fastep_core.kinematics import PointMass
from fastep_core.planning import OtherRobot, PlannerParams
from fastep_core.planning.others import OtherRobots, other_arrays, robot_arrays, robots_on_run
from fastep_core.planning.safety.guard import Guard
from fastep_core.world import World


def crowd(n: int, seed: int = 0) -> list[OtherRobot]:
    rng = np.random.default_rng(seed)
    return [OtherRobot(f'r{j}', tuple(rng.uniform(0.0, 6.0, 2)), tuple(rng.normal(0.0, 0.5, 2)),
                       float(rng.uniform(0.3, 0.7))) for j in range(n)]


def test_each_view_is_every_robot_but_one_with_the_same_arrays():
    robots = crowd(7)
    for i, view in enumerate(OtherRobots.views(robots)):
        plain = robots[:i] + robots[i + 1:]
        assert len(view) == 6 and list(view) == plain and view[0] == plain[0] and view[-1] == plain[-1]
        assert view[1:3] == plain[1:3]
        for mine, theirs in zip(other_arrays(view), other_arrays(plain)):
            assert np.array_equal(mine, theirs)
        assert all(np.array_equal(a, b) for a, b in zip(robot_arrays(view, 0.5), robot_arrays(plain, 0.5)))
        start, end = np.array([1.0, 1.0]), np.array([5.0, 4.0])
        assert robots_on_run(view, 0.5, start, end, 3.0, 0.1) == robots_on_run(plain, 0.5, start, end, 3.0, 0.1)
    assert OtherRobots.views(robots)[0].finite


def test_the_guard_gives_way_to_the_first_robot_in_reach_as_it_did_one_by_one():
    """The guard measures all the others at once now (it looped over them): the same robot, the same answer."""
    world = World.from_obstacles([0, 0, 20, 20], [])
    rng = np.random.default_rng(3)
    for max_speed in (1.0, 0.0):
        params = PlannerParams(max_speed=max_speed)
        for trial in range(200):
            robots = crowd(6, seed=trial)
            state = rng.uniform(0.0, 6.0, 2)
            command = rng.normal(0.0, 2.0, 2)
            expected = None
            after = PointMass().integrate(state, command, 0.05)
            for other in robots:   # the loop the guard ran before
                centre = np.asarray(other.position, dtype=float)
                speed = float(np.hypot(*other.velocity))   # a robot at max_speed at most, a faster one at its own
                reach = (max(max_speed, speed) if max_speed > 0 else speed) * 0.05 + 0.25 * 0.2
                gap_now, gap_then = float(np.hypot(*(state - centre))), float(np.hypot(*(after - centre)))
                if gap_then < 0.5 + other.radius + reach and gap_then < gap_now:
                    expected = other.name
                    break
            for others in (robots, OtherRobots.views([OtherRobot('me', tuple(state))] + robots)[0]):
                guard = Guard(PointMass(), 0.5, params)
                out = guard.check(world, state, command, 0.05, others)
                if expected is None:
                    assert out is command
                else:
                    assert out is not command and guard.reason == f'stopped: giving way to {expected}'


def test_a_view_is_finite_unless_one_of_its_others_is_not():
    robots = crowd(4)
    robots[1] = OtherRobot('lost', (float('nan'), 1.0))
    views = OtherRobots.views(robots)
    assert views[1].finite and not views[0].finite and not views[2].finite
