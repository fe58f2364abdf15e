"""Random solvable scenarios: reproducible, valid, solvable, and (a few of them) solved."""

import math

import numpy as np
import pytest
import yaml

from fastep_core.errors import ParameterError
from fastep_core.experiments.batches import cached_scenario
from fastep_core.experiments.random_worlds import (
    FAMILIES,
    FAMILY_SEED0,
    family_source,
    main,
    parse_family_source,
    random_family_data,
    random_scenario,
    random_scenario_data,
    solvable,
    u_trap_scenario_data,
)
from fastep_core.geometry import Circle
from fastep_core.scenario import parse_scenario
from fastep_core.simulator import simulate
from fastep_core.world import World


def test_same_seed_same_scenario_other_seed_other_scenario():
    assert random_scenario_data(7) == random_scenario_data(7)
    assert random_scenario_data(7) != random_scenario_data(8)


@pytest.mark.parametrize('seed', range(12))
def test_random_scenarios_are_valid_and_solvable_with_robots_parked_at_goals(seed):
    scenario = random_scenario(seed)
    assert 1 <= len(scenario.robots) <= 4
    assert solvable(scenario)
    for robot in scenario.robots:
        assert math.dist(robot.start[:2], robot.goal) >= 0.5 * max(scenario.world.workspace[2:])


def test_the_mix_has_tractor_trailers_u_traps_and_every_robot_count():
    scenarios = [random_scenario(seed) for seed in range(30)]
    models = {r.model for s in scenarios for r in s.robots}
    assert models == {'point_mass', 'tractor_trailer'}
    assert {len(s.robots) for s in scenarios} == {1, 2, 3, 4}
    assert sum(len([o for o in s.world.obstacle_list if not isinstance(o, Circle)]) >= 3 for s in scenarios) >= 10


def test_solvable_counts_robots_parked_at_their_goals():
    # r2 parks on the only gap r1 has: the obstacles alone leave a way, the parked robot does not.
    data = {'name': 'corridor', 'workspace': [0, 0, 20, 10],
            'obstacles': [{'segment': {'start': [10, 0], 'end': [10, 4]}},
                          {'segment': {'start': [10, 6], 'end': [10, 10]}}],
            'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [2, 5], 'goal': [18, 5], 'radius': 0.5},
                       {'name': 'r2', 'model': 'point_mass', 'start': [2, 2], 'goal': [10, 5], 'radius': 0.5}]}
    assert not solvable(parse_scenario(data))
    data['robots'][1]['goal'] = [5, 2]
    assert solvable(parse_scenario(data))


@pytest.mark.parametrize('model', ['point_mass', 'tractor_trailer'])
def test_u_trap_scenarios_put_the_trap_across_the_straight_line(model):
    scenario = parse_scenario(u_trap_scenario_data(3, model))
    robot = scenario.robots[0]
    assert robot.model == model
    walls = World(scenario.world.workspace, scenario.world.obstacle_list[:3]).obstacles
    assert walls.path_clearance(np.array(robot.start[:2]), np.array(robot.goal)) <= 0.0   # the U blocks it


def test_main_prints_the_scenario_as_yaml(capsys):
    assert main(['5']) == 0
    assert yaml.safe_load(capsys.readouterr().out) == random_scenario_data(5)


def test_bad_generator_arguments_are_parameter_errors():
    with pytest.raises(ParameterError, match='n_robots must be 1-4'):
        random_scenario_data(0, n_robots=5)
    with pytest.raises(ParameterError, match='model must be point_mass or tractor_trailer'):
        u_trap_scenario_data(0, model='hovercraft')


@pytest.mark.parametrize('argv', [['-1'], ['five'], ['1', '2']])
def test_main_refuses_a_bad_seed_with_one_line(capsys, argv):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == '' and len(captured.err.splitlines()) == 1


@pytest.mark.parametrize('seed', [0, 4, 10])
def test_a_small_soak_every_robot_arrives_and_none_collides(seed):
    run = simulate(random_scenario(seed), 'fastep', seed)
    assert all(r.reached and not r.collided for r in run.robots), [r.status for r in run.robots]


# ----------------------------------------------------------------------------------------- world families

@pytest.mark.parametrize('family', FAMILIES)
def test_a_family_world_is_valid_solvable_and_the_same_for_the_same_seed(family):
    seed = FAMILY_SEED0 + 3
    data = random_family_data(family, seed)
    assert data == random_family_data(family, seed)
    assert data != random_family_data(family, seed + 1)
    assert data['name'] == f'{family}_{seed}'
    scenario = parse_scenario(data)
    assert solvable(scenario)
    models = {r.model for r in scenario.robots}
    if family == 'multi_robot':
        assert 2 <= len(scenario.robots) <= 4
    elif family == 'diff_drive_robots':
        assert 1 <= len(scenario.robots) <= 4 and models == {'diff_drive'}
    else:
        assert len(scenario.robots) == 1
        assert models == {'tractor_trailer' if family == 'tractor_trailer' else
                          'diff_drive' if family == 'diff_drive_walls' else 'point_mass'}
    kinds = {type(o).__name__ for o in scenario.world.obstacle_list}
    if family == 'circle_field':
        assert kinds == {'Circle'}
    if family in ('circles_walls', 'u_trap', 'diff_drive_walls'):
        assert 'Segment' in kinds


def test_the_families_cover_their_ranges_over_a_few_worlds():
    counts = {len(random_family_data('multi_robot', FAMILY_SEED0 + k)['robots']) for k in range(12)}
    assert counts == {2, 3, 4}
    counts = {len(random_family_data('diff_drive_robots', FAMILY_SEED0 + k)['robots']) for k in range(12)}
    assert counts == {1, 2, 3, 4}


def test_a_diff_drive_world_is_the_point_mass_world_with_a_base_facing_anywhere():
    seed = FAMILY_SEED0 + 5
    point, base = random_family_data('circles_walls', seed), random_family_data('diff_drive_walls', seed)
    assert base['obstacles'] == point['obstacles'] and base['workspace'] == point['workspace']
    (p,), (b,) = point['robots'], base['robots']
    assert b['start'][:2] == p['start'] and b['goal'] == p['goal'] and b['radius'] == p['radius']
    headings = [random_family_data('diff_drive_walls', FAMILY_SEED0 + k)['robots'][0]['start'][2] for k in range(12)]
    assert min(headings) < -1.5 and max(headings) > 1.5


def test_a_family_world_is_a_source_the_experiments_load():
    source = family_source('u_trap', FAMILY_SEED0)
    assert parse_family_source(source) == ('u_trap', FAMILY_SEED0)
    assert cached_scenario(source).name == f'u_trap_{FAMILY_SEED0}'
    for other in ('table2_s1', 'nope:3', 'u_trap:x', 'u_trap:-1', 'u_trap'):
        assert parse_family_source(other) is None


def test_an_unknown_family_is_a_parameter_error():
    with pytest.raises(ParameterError, match='unknown world family'):
        random_family_data('nope', 1)


def test_main_prints_a_family_world(capsys):
    assert main(['--family', 'circles_walls', str(FAMILY_SEED0)]) == 0
    assert yaml.safe_load(capsys.readouterr().out) == random_family_data('circles_walls', FAMILY_SEED0)
