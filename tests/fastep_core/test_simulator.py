"""Whole runs of the in-process simulator: arrival, safety, determinism, and the paper's claims."""

import math

import numpy as np
import pytest

from fastep_core.kinematics import hitch_angle, lyapunov
from fastep_core.scenario import builtin_names, load_scenario, parse_scenario
from fastep_core.simulator import simulate

SEEDS = range(10)


def straight_line(spec):
    return math.hypot(spec.goal[0] - spec.start[0], spec.goal[1] - spec.start[1])


def check_run_is_safe(scenario, run):
    """Every trajectory sample keeps each robot's radius from every obstacle surface."""
    for spec, robot in zip(scenario.robots, run.robots):
        xy = np.array([row[1:3] for row in robot.trajectory])
        assert scenario.world.obstacles.clearance(xy).min() >= spec.radius - 1e-9, robot.name
        assert not robot.collided and robot.min_clearance >= 0.0, robot.name


@pytest.mark.parametrize('name', builtin_names())
def test_every_builtin_is_solved_safely_over_ten_seeds(name):
    scenario = load_scenario(name)
    for seed in SEEDS:
        run = simulate(scenario, 'fastep', seed)
        assert all(r.reached for r in run.robots), (seed, [r.status for r in run.robots])
        check_run_is_safe(scenario, run)


@pytest.mark.parametrize('name', ['table2_s2', 'case_study_2', 'application'])
def test_aco_kinematic_baseline_also_arrives_safely(name):
    scenario = load_scenario(name)
    for seed in range(3):
        run = simulate(scenario, 'aco', seed)
        assert all(r.reached for r in run.robots), (seed, [r.status for r in run.robots])
        check_run_is_safe(scenario, run)


@pytest.mark.parametrize('algorithm', ['fastep', 'aco'])
def test_same_seed_same_run_and_other_seed_differs(algorithm):
    scenario = load_scenario('table2_s3')
    a, b = simulate(scenario, algorithm, 7), simulate(scenario, algorithm, 7)
    timing = {'compute_time', 'plan_time'}   # wall-clock measurements, not part of the run

    def strip(run):
        return [{k: v for k, v in r.to_json().items() if k not in timing} for r in run.robots]

    assert strip(a) == strip(b)
    assert strip(simulate(scenario, algorithm, 8)) != strip(a)


@pytest.mark.parametrize('name', ['open_field', 'table2_s1'])
def test_nothing_on_the_way_means_no_swarm_and_a_straight_path(name):
    scenario = load_scenario(name)
    run = simulate(scenario, 'fastep', 0)
    for spec, robot in zip(scenario.robots, run.robots):
        assert robot.reached and robot.activations == 0 and robot.waypoints == []
        assert robot.path_length <= 1.01 * straight_line(spec)
        assert robot.cost and max(c for _, c in robot.cost) == 0.0


def test_aco_kinematic_plans_steps_even_when_the_way_is_clear():
    run = simulate(load_scenario('table2_s1'), 'aco', 0)
    assert run.robots[0].reached and run.robots[0].activations > 10


def test_point_mass_lyapunov_decreases_along_a_run():
    scenario = load_scenario('open_field')
    spec = scenario.robots[0]
    run = simulate(scenario, 'fastep', 0)
    goal = np.array(spec.goal)
    v = [lyapunov(np.array(row[1:3]), goal) for row in run.robots[0].trajectory]
    assert np.all(np.diff(v) < 0.0)


def test_tractor_trailer_hitch_angle_stays_under_80_degrees():
    scenario = load_scenario('application')
    for seed in range(3):
        run = simulate(scenario, 'fastep', seed)
        for robot in run.robots:
            hitch = [abs(math.degrees(hitch_angle(np.array(row[1:5])))) for row in robot.trajectory]
            assert robot.reached and max(hitch) < 80.0, (seed, robot.name, max(hitch))


def test_crossing_robots_keep_their_separation_every_tick():
    scenario = load_scenario('case_study_2')
    r1, r2 = scenario.robots
    for seed in range(3):
        positions: dict[float, dict[str, np.ndarray]] = {}

        def note(tick, positions=positions):
            positions.setdefault(round(tick.t, 6), {})[tick.name] = tick.state[:2]

        simulate(scenario, 'fastep', seed, observer=note)
        gaps = [np.hypot(*(p['r1'] - p['r2'])) for p in positions.values() if len(p) == 2]
        assert len(gaps) > 100 and min(gaps) >= r1.radius + r2.radius


def test_min_clearance_is_the_smallest_margin_after_any_step():
    """Every robot's position after each step, against the obstacles and the others (a stopped robot stays)."""
    scenario = load_scenario('case_study_2')   # two robots crossing among circles
    after_step: dict[float, dict[str, np.ndarray]] = {}
    run = simulate(scenario, 'fastep', 0,
                   observer=lambda tick: after_step.setdefault(tick.t, {}).__setitem__(tick.name, tick.state[:2]))
    where = {spec.name: np.array(spec.start[:2], dtype=float) for spec in scenario.robots}
    radius = {spec.name: spec.radius for spec in scenario.robots}
    smallest = dict.fromkeys(where, math.inf)
    for t in sorted(after_step):
        where.update(after_step[t])
        for name, p in where.items():
            margins = [float(scenario.world.obstacles.clearance(p[None])[0]) - radius[name]]
            margins += [math.hypot(*(p - q)) - radius[name] - radius[other] for other, q in where.items()
                        if other != name]
            smallest[name] = min(smallest[name], *margins)
    for robot in run.robots:
        assert robot.min_clearance == pytest.approx(smallest[robot.name], abs=1e-12)
        assert robot.collided == (smallest[robot.name] < 0.0)


def test_head_on_robots_in_open_space_get_past_each_other():
    scenario = parse_scenario({
        'name': 'swap', 'workspace': [0, 0, 30, 10],
        'robots': [{'name': 'a', 'model': 'point_mass', 'start': [3, 5], 'goal': [27, 5], 'radius': 0.5},
                   {'name': 'b', 'model': 'point_mass', 'start': [27, 5], 'goal': [3, 5], 'radius': 0.5}]})
    run = simulate(scenario, 'fastep', 0)
    assert all(r.reached and not r.collided for r in run.robots)
    assert all(r.activations > 0 for r in run.robots)


def test_unreachable_goal_fails_with_a_reason_instead_of_hanging():
    walls = [{'segment': {'start': s, 'end': e}} for s, e in
             [([20, 20], [30, 20]), ([30, 20], [30, 30]), ([30, 30], [20, 30]), ([20, 30], [20, 20])]]
    scenario = parse_scenario({
        'name': 'walled', 'workspace': [0, 0, 50, 50], 'obstacles': walls,
        'planner': {'progress_timeout': 30, 'max_sim_time': 300},
        'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [5, 5], 'goal': [25, 25], 'radius': 0.5}]})
    robot = simulate(scenario, 'fastep', 0).robots[0]
    assert not robot.reached and robot.sim_time is None and not robot.collided
    assert robot.status.startswith('failed: no valid path') and robot.path_length == 0.0


def test_trajectory_samples_are_at_most_a_tenth_of_a_metre_apart():
    run = simulate(load_scenario('table2_s3'), 'fastep', 0)
    xy = np.array([row[1:3] for row in run.robots[0].trajectory])
    assert np.hypot(*np.diff(xy, axis=0).T).max() <= 0.1 + 1e-9
    assert run.robots[0].trajectory[0][0] == 0.0


def test_a_robot_that_arrived_is_seen_standing_still(monkeypatch):
    """An arrived robot kept its last velocity, so the others saw it moving and never planned round it as a
    parked robot (a plant publishes the zero twist it is sent; the simulator now does the same)."""
    from fastep_core import simulator

    seen = []
    real = simulator.make_navigator

    def spy(algorithm, spec, *args):
        navigator = real(algorithm, spec, *args)
        if spec.name == 'far':
            update = navigator.update

            def recording(t, state, others=(), velocity=None):
                seen.append((t, [(o.name, tuple(o.velocity)) for o in others]))
                return update(t, state, others, velocity=velocity)
            navigator.update = recording
        return navigator

    monkeypatch.setattr(simulator, 'make_navigator', spy)
    scenario = parse_scenario({
        'name': 'park', 'workspace': [0, 0, 30, 10],
        'robots': [{'name': 'near', 'model': 'diff_drive', 'start': [3, 8, 0], 'goal': [6, 8], 'radius': 0.5},
                   {'name': 'far', 'model': 'diff_drive', 'start': [3, 2, 0], 'goal': [27, 2], 'radius': 0.5}]})
    run = simulate(scenario, 'fastep', 0)
    near = run.robots[0]
    assert near.reached and run.robots[1].reached
    after = [v for t, others in seen if t > near.sim_time for name, v in others if name == 'near']
    assert after and all(v == (0.0, 0.0) for v in after)


@pytest.mark.parametrize('world', ['diff_drive_robots:1000015', 'diff_drive_robots:1000019'])
def test_diff_drive_robots_held_face_to_face_or_by_a_parked_robot_get_out(world):
    """FAStep-Kinematic's two failures on the diff_drive_robots family (issue 14): a robot held by another
    turned in place between stops, which restarted the recovery clocks (1000015: two robots face to face for
    three minutes); a robot that arrived was seen moving and not planned round (1000019). Both now arrive."""
    from fastep_core.experiments.batches import cached_scenario

    scenario = cached_scenario(world)
    run = simulate(scenario, 'fastep', 0)
    assert all(r.reached and not r.collided for r in run.robots), [r.status for r in run.robots]
