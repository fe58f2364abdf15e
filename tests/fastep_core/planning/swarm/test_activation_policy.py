"""FAStep-Kinematic's activation policy (plan_horizon, stuck_steps, waypoint_lead; docs/architecture.md).

`fastep` runs plan_horizon = 2 m and stuck_steps = 1 by default; `fastep_paper` is the paper's literal policy
(it ignores all three). These tests show what each switch changes against the paper's policy.
"""

from __future__ import annotations

import math
from typing import Any

from fastep_core.scenario import parse_scenario
from fastep_core.simulator import Tick, simulate

# Five circles of a random circle field (benchmarks/clutter_diagnosis.py, circle field 6) whose wedge lies across
# the straight run: the greedy step (c*d dominates eq. 10) leads into it, and there the swarm's best point is
# within waypoint_tolerance of the robot, so each step counts as reached on the next tick.
WEDGE = [([39.537, 26.597], 0.597), ([38.848, 29.222], 1.907), ([41.454, 26.965], 1.281),
         ([45.052, 28.757], 1.217), ([44.958, 26.674], 2.176)]


def _scenario(planner: dict[str, Any], obstacles: list[tuple[list[float], float]], start: list[float],
              goal: list[float]) -> Any:
    return parse_scenario({
        'name': 'policy', 'workspace': [0, 0, 50, 50],
        'obstacles': [{'circle': {'center': c, 'radius': r}} for c, r in obstacles],
        'robots': [{'name': 'r1', 'model': 'point_mass', 'start': start, 'goal': goal, 'radius': 0.5}],
        'planner': planner})


OFF = {'plan_horizon': 0.0, 'stuck_steps': 0, 'waypoint_lead': 0.0}


def test_fastep_runs_the_policy_by_default_and_fastep_paper_ignores_it():
    wedge = _scenario({}, WEDGE, [45.2, 36.595], [36.0, 22.0])
    default = simulate(wedge, 'fastep', 6).robots[0]
    switched = simulate(_scenario({'plan_horizon': 2.0, 'stuck_steps': 1}, WEDGE, [45.2, 36.595], [36.0, 22.0]),
                        'fastep', 6).robots[0]
    paper = simulate(wedge, 'fastep_paper', 6).robots[0]
    paper_all_on = simulate(_scenario({'plan_horizon': 2.0, 'stuck_steps': 1, 'waypoint_lead': 2.0}, WEDGE,
                                      [45.2, 36.595], [36.0, 22.0]), 'fastep_paper', 6).robots[0]
    off = simulate(_scenario(OFF, WEDGE, [45.2, 36.595], [36.0, 22.0]), 'fastep', 6).robots[0]
    assert default.trajectory == switched.trajectory
    assert paper.trajectory == paper_all_on.trajectory == off.trajectory   # the switches at 0 are the paper
    assert default.activations < paper.activations


def test_stuck_steps_start_the_escape_at_once_instead_of_a_swarm_run_every_tick():
    paper = simulate(_scenario(OFF, WEDGE, [45.2, 36.595], [36.0, 22.0]), 'fastep', 6).robots[0]
    stuck = simulate(_scenario({**OFF, 'stuck_steps': 1}, WEDGE, [45.2, 36.595], [36.0, 22.0]), 'fastep',
                     6).robots[0]
    assert paper.reached and paper.escapes == 1 and paper.activations > 100   # one swarm run per tick for ~20 s
    assert stuck.reached and not stuck.collided and stuck.escapes == 1
    assert stuck.activations <= 10
    assert stuck.sim_time is not None and paper.sim_time is not None and stuck.sim_time < paper.sim_time


def _first_activation(planner: dict[str, Any]) -> tuple[float, int, Any]:
    """Surface distance to the obstacle when the swarm first ran, the run's activations, the run."""
    where: list[float] = []

    def observe(tick: Tick) -> None:
        if not where and tick.navigator.activations:
            where.append(math.hypot(tick.state[0] - 25.0, tick.state[1] - 25.0) - 2.0)

    scenario = _scenario(planner, [([25.0, 25.0], 2.0)], [5.0, 25.0], [45.0, 25.3])
    run = simulate(scenario, 'fastep', 0, observer=observe)
    return where[0], run.robots[0].activations, run.robots[0]


def test_plan_horizon_plans_only_once_the_blocker_is_within_the_step_the_swarm_could_take():
    paper_at, paper_count, paper = _first_activation(OFF)
    near_at, near_count, near = _first_activation({**OFF, 'plan_horizon': 2.0})
    assert paper_at > 2.8                      # detected at sensing_range (eq. 11, epsilon = 3 m)
    assert near_at < 2.0 + 0.5 + 0.1 + 0.1     # horizon + radius + half the margin (+ detection_interval)
    assert near_count <= paper_count
    assert near.reached and not near.collided
    # Planning later swerves later: here 2 % longer (43.2 -> 44.1 m); in circle fields it was shorter on average.
    assert near.path_length <= 1.03 * paper.path_length


def test_waypoint_lead_keeps_the_path_and_arrives_sooner():
    # Against eq. 12's crawl (the paper's gains): min_approach_speed, on by default, already spares most of it.
    _, _, paper = _first_activation({**OFF, 'min_approach_speed': 0.0})
    _, _, lead = _first_activation({**OFF, 'waypoint_lead': 2.0, 'min_approach_speed': 0.0})
    assert lead.reached and not lead.collided and paper.sim_time is not None and lead.sim_time is not None
    assert abs(lead.path_length - paper.path_length) < 0.05 * paper.path_length
    assert lead.sim_time < 0.95 * paper.sim_time   # eq. 12 no longer slows it to a crawl at each waypoint
