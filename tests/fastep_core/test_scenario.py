"""Tests for fastep_core.scenario: the v1 scenario format, its validation and the built-in scenarios."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from fastep_core.errors import ScenarioError
from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import (
    RobotSpec,
    Scenario,
    builtin_names,
    builtin_path,
    load_scenario,
    parse_scenario,
)

BUILTINS = {  # name -> robot models, in order
    'application': ('tractor_trailer', 'tractor_trailer'),
    'case_study_1': ('point_mass', 'point_mass'),
    'case_study_2': ('point_mass', 'point_mass'),
    'crossing_movers': ('point_mass',),
    'crossing_robots_movers': ('point_mass', 'point_mass'),
    'diff_drive_swap': ('diff_drive', 'diff_drive'),
    'diff_drive_walls': ('diff_drive',),
    'open_field': ('point_mass',),
    'table2_s1': ('point_mass',),
    'table2_s2': ('point_mass',),
    'table2_s3': ('point_mass',),
}

TRACTOR: dict[str, Any] = {
    'name': 't1', 'model': 'tractor_trailer', 'start': [5, 5, 0.5, 0.5], 'goal': [45, 45], 'radius': 0.6,
    'length': 1.0, 'trailer_length': 1.0, 'width': 0.5, 'hitch_offset': 0.0,
}


def base() -> dict[str, Any]:
    """A small valid scenario; tests break one thing in a copy of it."""
    return {
        'name': 'base',
        'workspace': [0, 0, 50, 50],
        'obstacles': [
            {'circle': {'center': [25, 25], 'radius': 4}},
            {'segment': {'start': [10, 30], 'end': [20, 30]}},
        ],
        'robots': [
            {'name': 'r1', 'model': 'point_mass', 'start': [5, 45], 'goal': [45, 5], 'radius': 0.5},
            {'name': 'r2', 'model': 'point_mass', 'start': [5, 5], 'goal': [45, 45], 'radius': 0.5},
        ],
    }


def write(tmp_path: Path, data: Any, name: str = 'x.yaml') -> Path:
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    return path


def expect_error(path: Path | str, *fragments: str) -> str:
    """Load `path`, expect a ScenarioError whose one-line message names the file and holds every fragment."""
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    message = str(info.value)
    assert '\n' not in message and '\r' not in message, message
    assert str(path) in message, message
    for fragment in fragments:
        assert fragment in message, f'{fragment!r} not in {message!r}'
    return message


def bad(tmp_path: Path, edit: Any, *fragments: str) -> str:
    """Apply edit(data) to a copy of base(), write it and expect an error holding the fragments."""
    data = copy.deepcopy(base())
    edit(data)
    return expect_error(write(tmp_path, data), *fragments)


# ----------------------------------------------------------------------------------------------- happy path

def test_base_loads(tmp_path: Path) -> None:
    scenario = load_scenario(write(tmp_path, base()))
    assert isinstance(scenario, Scenario)
    assert scenario.name == 'base'
    assert scenario.world.workspace == (0.0, 0.0, 50.0, 50.0)
    assert scenario.world.obstacle_list == (Circle((25.0, 25.0), 4.0), Segment((10.0, 30.0), (20.0, 30.0)))
    assert scenario.robots[0] == RobotSpec('r1', 'point_mass', (5.0, 45.0), (45.0, 5.0), 0.5)
    assert scenario.planner == PlannerParams()
    assert scenario.description == ''


def test_name_defaults_to_file_stem(tmp_path: Path) -> None:
    data = base()
    del data['name']
    assert load_scenario(write(tmp_path, data, 'my_map.yaml')).name == 'my_map'


def test_obstacles_optional(tmp_path: Path) -> None:
    data = base()
    del data['obstacles']
    assert len(load_scenario(write(tmp_path, data)).world.obstacles) == 0
    data['obstacles'] = None   # `obstacles:` with every entry commented out
    assert len(load_scenario(write(tmp_path, data)).world.obstacles) == 0


def test_tractor_trailer_robot(tmp_path: Path) -> None:
    data = base()
    data['robots'] = [dict(TRACTOR, length=1.2, trailer_length=0.8, width=0.4, hitch_offset=0.1, radius=0.7)]
    robot = load_scenario(write(tmp_path, data)).robots[0]
    assert robot == RobotSpec('t1', 'tractor_trailer', (5.0, 5.0, 0.5, 0.5), (45.0, 45.0), 0.7,
                              length=1.2, trailer_length=0.8, width=0.4, hitch_offset=0.1)


def test_tractor_trailer_defaults(tmp_path: Path) -> None:
    data = base()
    minimal = {k: TRACTOR[k] for k in ('name', 'model', 'start', 'goal', 'radius')}
    data['robots'] = [minimal]
    robot = load_scenario(write(tmp_path, data)).robots[0]
    assert (robot.length, robot.trailer_length, robot.width, robot.hitch_offset) == (1.0, 1.0, 0.5, 0.0)


def test_planner_override(tmp_path: Path) -> None:
    data = base()
    data['planner'] = {'c': 0.005, 'n_fireflies': 20}
    planner = load_scenario(write(tmp_path, data)).planner
    assert planner.c == 0.005
    assert planner.n_fireflies == 20 and isinstance(planner.n_fireflies, int)
    assert planner.a == PlannerParams().a


def test_x_keys_ignored_and_description_kept(tmp_path: Path) -> None:
    data = base()
    data['x_anything'] = {'whatever': [1, 'two', None]}
    data['x_notes'] = 'free text'
    data['description'] = 'a test map'
    scenario = load_scenario(write(tmp_path, data))
    assert scenario.description == 'a test map'
    assert scenario == load_scenario(write(tmp_path, dict(base(), description='a test map'), 'y.yaml'))


def test_parse_scenario_mapping() -> None:
    data = base()
    del data['name']
    scenario = parse_scenario(data, default_name='inline')
    assert scenario.name == 'inline'
    assert len(scenario.robots) == 2


def test_parse_scenario_error_names_scenario() -> None:
    data = base()
    data['robots'][1]['radius'] = -1
    with pytest.raises(ScenarioError, match=r"^scenario 'base': robots\[1\]\.radius must be > 0, got -1$"):
        parse_scenario(data)


def test_path_like_and_str_agree(tmp_path: Path) -> None:
    path = write(tmp_path, base())
    assert load_scenario(path) == load_scenario(str(path))


# ----------------------------------------------------------------------------------------------- top level

@pytest.mark.parametrize('text, fragment', [
    ('- a\n- b\n', 'top level must be a mapping'),
    ('42\n', 'top level must be a mapping'),
    ('just text\n', 'top level must be a mapping'),
    ('', 'empty document'),
    ('# only a comment\n', 'empty document'),
])
def test_top_level_not_mapping(tmp_path: Path, text: str, fragment: str) -> None:
    expect_error(write(tmp_path, text), fragment)


def test_non_string_top_key(tmp_path: Path) -> None:
    expect_error(write(tmp_path, yaml.safe_dump(base()) + '1: one\n'), 'keys must be strings', '1')


@pytest.mark.parametrize('text', [
    'workspace: [0, 0, 50, 50\nrobots: []\n',
    'workspace: [0, 0, 50, 50]\n  robots: x\n bad: indent\n',
    'a: b: c\n',
    'workspace: {a: 1\n',
    '---\na: 1\n---\nb: 2\n',
])
def test_yaml_syntax_error(tmp_path: Path, text: str) -> None:
    message = expect_error(write(tmp_path, text), 'invalid YAML')
    assert 'line ' in message and 'column ' in message


@pytest.mark.parametrize('text', [
    '!!python/object/apply:os.system ["echo hacked"]\n',
    'workspace: !!python/tuple [0, 0, 50, 50]\nrobots: []\n',
    'name: !!python/name:os.system\n',
])
def test_python_tags_rejected(tmp_path: Path, text: str) -> None:
    expect_error(write(tmp_path, text), 'invalid YAML', 'python/', 'line ')


def test_file_not_found(tmp_path: Path) -> None:
    expect_error(tmp_path / 'missing.yaml', 'file not found')
    expect_error(str(tmp_path / 'missing'), 'file not found')


def test_directory_is_not_a_file(tmp_path: Path) -> None:
    expect_error(tmp_path, 'not a regular file')


def test_unreadable_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = write(tmp_path, base())

    def deny(self: Path) -> bytes:
        raise PermissionError(13, 'Permission denied', str(self))

    monkeypatch.setattr(Path, 'read_bytes', deny)   # chmod does not stop root, which CI may run as
    expect_error(path, 'cannot read', 'Permission denied')


def test_unknown_name_lists_builtins() -> None:
    message = expect_error('no_such_scenario', 'no_such_scenario', 'built-ins:')
    for name in builtin_names():
        assert name in message


def test_not_utf8(tmp_path: Path) -> None:
    path = tmp_path / 'x.yaml'
    path.write_bytes(b'name: \xff\xfe\xfa\n')
    expect_error(path, 'invalid YAML')


@pytest.mark.parametrize('key', ['workspace', 'robots'])
def test_required_top_key(tmp_path: Path, key: str) -> None:
    bad(tmp_path, lambda d: d.pop(key), f"missing required top-level key '{key}'")


def test_unknown_top_key(tmp_path: Path) -> None:
    bad(tmp_path, lambda d: d.update(obstacle=[]), "unknown top-level key 'obstacle'", 'allowed:', 'x_')


@pytest.mark.parametrize('value', [7, ['a'], {'a': 1}, True])
def test_description_must_be_string(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d.update(description=value), 'description must be a string')


@pytest.mark.parametrize('value', ['', '   ', 3, None, ['a']])
def test_bad_scenario_name(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d.update(name=value), 'name must be a non-empty string')


# ----------------------------------------------------------------------------------------------- planner

def test_planner_unknown_parameter(tmp_path: Path) -> None:
    message = bad(tmp_path, lambda d: d.update(planner={'c': -1, 'fireflies': 10, 'zeta': 1}),
                  'planner: unknown planner parameter(s): fireflies, zeta')
    assert 'planner.c' not in message


@pytest.mark.parametrize('key, value', [('c', -1), ('alpha_damping', 2.0), ('n_fireflies', 1),
                                        ('n_fireflies', 2.5), ('a', True), ('a', None), ('a', [1])])
def test_planner_out_of_range(tmp_path: Path, key: str, value: Any) -> None:
    bad(tmp_path, lambda d: d.update(planner={'a': 0.5, key: value}), f'planner.{key}: planner parameter {key}')


def test_planner_number_as_text_has_hint(tmp_path: Path) -> None:
    path = write(tmp_path, yaml.safe_dump(base()) + 'planner:\n  c: 1e-3\n')   # YAML 1.1: a string
    expect_error(path, "planner.c must be a finite number, got '1e-3'", 'write 1.0e-3')
    text = yaml.safe_dump(base()).replace('- 50\n', '- 5E+1\n', 1)
    expect_error(write(tmp_path, text), "workspace[2] must be a finite number, got '5E+1'", 'write 5.0e+1')
    text = yaml.safe_dump(base()).replace('- 50\n', '- 5.0e1\n', 1)
    expect_error(write(tmp_path, text), "got '5.0e1'", 'write 5.0e+1')


@pytest.mark.parametrize('value', [[1, 2], 'c=1', 3])
def test_planner_not_mapping(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d.update(planner=value), 'planner must be a mapping')


def test_planner_non_string_key(tmp_path: Path) -> None:
    expect_error(write(tmp_path, yaml.safe_dump(base()) + 'planner: {1: 2}\n'), 'planner: keys must be strings')


# ----------------------------------------------------------------------------------------------- numbers

NOT_NUMBERS = [True, False, '5', None, float('nan'), float('inf'), -float('inf'), [5], {'x': 5}]


@pytest.mark.parametrize('value', NOT_NUMBERS)
@pytest.mark.parametrize('where, path', [
    (('workspace', 2), 'workspace[2]'),
    (('obstacles', 0, 'circle', 'center', 1), 'obstacles[0].circle.center[1]'),
    (('obstacles', 0, 'circle', 'radius'), 'obstacles[0].circle.radius'),
    (('obstacles', 1, 'segment', 'end', 0), 'obstacles[1].segment.end[0]'),
    (('robots', 1, 'start', 0), 'robots[1].start[0]'),
    (('robots', 0, 'goal', 1), 'robots[0].goal[1]'),
    (('robots', 1, 'radius'), 'robots[1].radius'),
])
def test_not_a_finite_number(tmp_path: Path, where: tuple[Any, ...], path: str, value: Any) -> None:
    def edit(d: dict[str, Any]) -> None:
        node = d
        for step in where[:-1]:
            node = node[step]
        node[where[-1]] = value
    bad(tmp_path, edit, f'{path} must be a finite number')


@pytest.mark.parametrize('key', ['length', 'trailer_length', 'width', 'hitch_offset'])
@pytest.mark.parametrize('value', [float('nan'), True, 'x', None])
def test_tractor_dimension_not_number(tmp_path: Path, key: str, value: Any) -> None:
    bad(tmp_path, lambda d: d.update(robots=[dict(TRACTOR, **{key: value})]),
        f'robots[0].{key} must be a finite number')


def test_huge_integer_is_not_finite(tmp_path: Path) -> None:
    text = yaml.safe_dump(base()).replace('- 50\n', '- ' + '9' * 400 + '\n', 1)
    expect_error(write(tmp_path, text), 'must be a finite number')


def test_quoted_number_hint(tmp_path: Path) -> None:
    message = bad(tmp_path, lambda d: d['robots'][0].update(radius='0.5'), 'robots[0].radius must be a finite')
    assert 'drop the quotes' in message
    message = bad(tmp_path, lambda d: d['robots'][0].update(radius='1.0e-3'), 'robots[0].radius must be a finite')
    assert 'drop the quotes' in message


# ----------------------------------------------------------------------------------------------- workspace

@pytest.mark.parametrize('value, fragment', [
    ([0, 0, 50], 'workspace must be a list of 4 numbers'),
    ([0, 0, 50, 50, 1], 'workspace must be a list of 4 numbers'),
    ({'xmin': 0}, 'workspace must be a list of 4 numbers'),
    ('0 0 50 50', 'workspace must be a list of 4 numbers'),
    ([50, 0, 0, 50], 'workspace needs xmin < xmax'),
    ([0, 0, 0, 50], 'workspace needs xmin < xmax'),
    ([0, 50, 50, 0], 'workspace needs ymin < ymax'),
    ([0, 10, 50, 10], 'workspace needs ymin < ymax'),
])
def test_bad_workspace(tmp_path: Path, value: Any, fragment: str) -> None:
    bad(tmp_path, lambda d: d.update(workspace=value), fragment)


# ----------------------------------------------------------------------------------------------- obstacles

@pytest.mark.parametrize('value, fragment', [
    ({'circle': {'center': [25, 25], 'radius': 4}}, 'obstacles must be a list'),
    ('circle', 'obstacles must be a list'),
    ([['circle']], 'obstacles[0] must be a mapping'),
    (['circle'], 'obstacles[0] must be a mapping'),
    ([{}], 'obstacles[0] must have exactly one key'),
    ([{'circle': {'center': [1, 1], 'radius': 1}, 'segment': {'start': [0, 0], 'end': [1, 1]}}],
     'obstacles[0] must have exactly one key'),
    ([{'rectangle': {'center': [25, 25]}}], "obstacles[0]: unknown key 'rectangle'"),
])
def test_bad_obstacle_list(tmp_path: Path, value: Any, fragment: str) -> None:
    bad(tmp_path, lambda d: d.update(obstacles=value), fragment)


@pytest.mark.parametrize('body, fragment', [
    ({'center': [25, 25], 'radius': 4, 'colour': 'red'}, "obstacles[0].circle: unknown key 'colour'"),
    ({'centre': [25, 25], 'radius': 4}, "obstacles[0].circle: unknown key 'centre'"),
    ({'center': [25, 25]}, "obstacles[0].circle: missing required key 'radius'"),
    ({'radius': 4}, "obstacles[0].circle: missing required key 'center'"),
    ({'center': [25, 25], 'radius': 0}, 'obstacles[0].circle.radius must be > 0, got 0'),
    ({'center': [25, 25], 'radius': -2.5}, 'obstacles[0].circle.radius must be > 0, got -2.5'),
    ({'center': [25, 25, 0], 'radius': 4}, 'obstacles[0].circle.center must be a list of 2 numbers'),
    ({'center': 25, 'radius': 4}, 'obstacles[0].circle.center must be a list of 2 numbers'),
    ([25, 25, 4], 'obstacles[0].circle must be a mapping'),
])
def test_bad_circle(tmp_path: Path, body: Any, fragment: str) -> None:
    bad(tmp_path, lambda d: d['obstacles'].__setitem__(0, {'circle': body}), fragment)


@pytest.mark.parametrize('body, fragment', [
    ({'start': [10, 30], 'end': [20, 30], 'width': 1}, "obstacles[1].segment: unknown key 'width'"),
    ({'start': [10, 30]}, "obstacles[1].segment: missing required key 'end'"),
    ({'end': [10, 30]}, "obstacles[1].segment: missing required key 'start'"),
    ({'start': [10, 30], 'end': [10, 30]}, 'obstacles[1].segment: start and end must differ'),
    ({'start': [10, 30], 'end': [10.0, 30.0]}, 'obstacles[1].segment: start and end must differ'),
    ({'start': [10], 'end': [20, 30]}, 'obstacles[1].segment.start must be a list of 2 numbers'),
    (None, 'obstacles[1].segment must be a mapping'),
])
def test_bad_segment(tmp_path: Path, body: Any, fragment: str) -> None:
    bad(tmp_path, lambda d: d['obstacles'].__setitem__(1, {'segment': body}), fragment)


# ----------------------------------------------------------------------------------------------- robots

@pytest.mark.parametrize('value, fragment', [
    ([], 'robots must list at least one robot'),
    (None, 'robots must be a list'),
    ({'name': 'r1'}, 'robots must be a list'),
    (['r1'], 'robots[0] must be a mapping'),
])
def test_bad_robot_list(tmp_path: Path, value: Any, fragment: str) -> None:
    bad(tmp_path, lambda d: d.update(robots=value), fragment)


def test_unknown_robot_key(tmp_path: Path) -> None:
    bad(tmp_path, lambda d: d['robots'][1].update(colour='red'), "robots[1]: unknown key 'colour'", 'allowed:')


@pytest.mark.parametrize('key', ['name', 'model', 'start', 'goal', 'radius'])
def test_missing_robot_key(tmp_path: Path, key: str) -> None:
    bad(tmp_path, lambda d: d['robots'][1].pop(key), f"robots[1]: missing required key '{key}'")


@pytest.mark.parametrize('value', ['', '1r', 'r-1', 'r 1', 'r/1', 'robot.one', 'ü', 7, None, True, ['r1']])
def test_bad_robot_name(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d['robots'][1].update(name=value), 'robots[1].name must match', 'ROS namespace')


@pytest.mark.parametrize('value', ['_r', 'R2D2', 'robot_one', 'a'])
def test_good_robot_name(tmp_path: Path, value: str) -> None:
    data = base()
    data['robots'][1]['name'] = value
    assert load_scenario(write(tmp_path, data)).robots[1].name == value


def test_duplicate_robot_name(tmp_path: Path) -> None:
    bad(tmp_path, lambda d: d['robots'][1].update(name='r1'), "robots[1].name 'r1' is already used by robots[0]")


@pytest.mark.parametrize('value', ['car', 'Point_Mass', 'pointmass', None, 1])
def test_bad_model(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d['robots'][0].update(model=value),
        'robots[0].model must be one of point_mass, tractor_trailer')


@pytest.mark.parametrize('value', [[5], [5, 45, 0], [5, 45, 0, 0], 5])
def test_point_mass_start_length(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d['robots'][0].update(start=value), 'robots[0].start must be a list of 2 numbers')


@pytest.mark.parametrize('value', [[5, 5], [5, 5, 0], [5, 5, 0, 0, 0]])
def test_tractor_start_length(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d.update(robots=[dict(TRACTOR, start=value)]),
        'robots[0].start must be a list of 4 numbers [x, y, theta0, theta1]')


@pytest.mark.parametrize('value', [[45], [45, 5, 0], 'home'])
def test_goal_length(tmp_path: Path, value: Any) -> None:
    bad(tmp_path, lambda d: d['robots'][1].update(goal=value), 'robots[1].goal must be a list of 2 numbers')


@pytest.mark.parametrize('value', [0, -1, -0.5])
def test_radius_positive(tmp_path: Path, value: float) -> None:
    bad(tmp_path, lambda d: d['robots'][1].update(radius=value), f'robots[1].radius must be > 0, got {value}')


@pytest.mark.parametrize('key', ['length', 'trailer_length', 'width', 'hitch_offset'])
def test_tractor_keys_rejected_on_point_mass(tmp_path: Path, key: str) -> None:
    bad(tmp_path, lambda d: d['robots'][0].update({key: 1.0}),
        f'robots[0].{key} is only valid for model tractor_trailer')


@pytest.mark.parametrize('key, value, fragment', [
    ('length', 0, 'robots[0].length must be > 0'),
    ('length', -1, 'robots[0].length must be > 0'),
    ('trailer_length', 0, 'robots[0].trailer_length must be > 0'),
    ('width', -0.5, 'robots[0].width must be > 0'),
    ('hitch_offset', -0.1, 'robots[0].hitch_offset must be >= 0'),
])
def test_tractor_dimensions(tmp_path: Path, key: str, value: float, fragment: str) -> None:
    bad(tmp_path, lambda d: d.update(robots=[dict(TRACTOR, **{key: value})]), fragment)


def test_tractor_radius_clearance(tmp_path: Path) -> None:
    needed = math.hypot(2.0, 1.0) / 2.0   # 1.118
    bad(tmp_path, lambda d: d.update(robots=[dict(TRACTOR, length=2.0, width=1.0, radius=1.1)]),
        'robots[0].radius must be >= sqrt(length^2 + width^2)/2', '1.118')
    data = base()
    data['robots'] = [dict(TRACTOR, length=2.0, width=1.0, radius=needed)]   # exactly enough is fine
    assert load_scenario(write(tmp_path, data)).robots[0].radius == needed


def test_tractor_default_dimensions_need_radius(tmp_path: Path) -> None:
    # Defaults L = 1, b = 0.5 need radius >= 0.559; a point-mass-like 0.5 is too small.
    bad(tmp_path, lambda d: d.update(robots=[{k: v for k, v in TRACTOR.items() if k in
                                              ('name', 'model', 'start', 'goal')} | {'radius': 0.5}]),
        'robots[0].radius must be >=', '0.559')


# ----------------------------------------------------------------------------------------------- placement

@pytest.mark.parametrize('key, value', [('start', [-1, 5]), ('start', [5, 50.5]), ('goal', [51, 5]),
                                        ('goal', [45, -0.1])])
def test_outside_workspace(tmp_path: Path, key: str, value: list[float]) -> None:
    bad(tmp_path, lambda d: d['robots'][0].update({key: value}), f'robots[0] (r1): {key} (', 'outside the map')


def test_tractor_start_outside(tmp_path: Path) -> None:
    bad(tmp_path, lambda d: d.update(robots=[dict(TRACTOR, start=[60, 5, 0, 0])]),
        'robots[0] (t1): start (60, 5) is outside the map')


@pytest.mark.parametrize('key, value', [('start', [25, 25]), ('start', [25, 29.3]), ('goal', [15, 30.2]),
                                        ('goal', [20.4, 30])])
def test_occupied(tmp_path: Path, key: str, value: list[float]) -> None:
    # circle (25, 25) r 4 and wall (10, 30)-(20, 30); robot radius 0.5
    bad(tmp_path, lambda d: d['robots'][1].update({key: value}), f'robots[1] (r2): {key} (', 'is occupied')


def test_clear_by_just_the_radius(tmp_path: Path) -> None:
    data = base()
    data['robots'][1]['goal'] = [25, 29.5]   # exactly radius 0.5 from the circle's surface
    assert load_scenario(write(tmp_path, data)).robots[1].goal == (25.0, 29.5)


def test_starts_too_close(tmp_path: Path) -> None:
    bad(tmp_path, lambda d: d['robots'][1].update(start=[5.5, 44.5]),
        'robots[0] (r1) and robots[1] (r2): starts are', 'sum of their radii 1 m')


def test_goals_too_close(tmp_path: Path) -> None:
    bad(tmp_path, lambda d: d['robots'][1].update(goal=[45, 5.9]),
        'robots[0] (r1) and robots[1] (r2): goals are', 'sum of their radii 1 m')


def test_starts_exactly_touching_ok(tmp_path: Path) -> None:
    data = base()
    data['robots'][1]['start'] = [6, 45]   # 1 m apart = 0.5 + 0.5
    assert len(load_scenario(write(tmp_path, data)).robots) == 2


def test_robot_start_may_be_other_goal(tmp_path: Path) -> None:
    data = base()   # case study 2 swaps corners: a start may equal another robot's goal
    data['robots'][1].update(start=[45, 5], goal=[5, 45])
    assert load_scenario(write(tmp_path, data)).robots[1].start == (45.0, 5.0)


# ----------------------------------------------------------------------------------------------- built-ins

def test_builtin_names_sorted_and_complete() -> None:
    names = builtin_names()
    assert names == sorted(names)                   # what `fastep-sim --list` prints, in this order
    assert names == sorted(BUILTINS)
    folder = Path(__file__).resolve().parents[2] / 'fastep_core' / 'scenarios'
    assert names == sorted(p.stem for p in folder.glob('*.yaml'))


def test_builtin_path() -> None:
    for name in builtin_names():
        path = builtin_path(name)
        assert path.is_file() and path.name == f'{name}.yaml'
    with pytest.raises(ScenarioError, match='built-ins: application, case_study_1'):
        builtin_path('nope')
    with pytest.raises(ScenarioError):
        builtin_path('../scenario')


@pytest.mark.parametrize('name', sorted(BUILTINS))
def test_builtin_round_trip(name: str) -> None:
    scenario = load_scenario(name)
    assert scenario.name == name
    assert tuple(r.model for r in scenario.robots) == BUILTINS[name]
    assert scenario.description.strip()
    assert scenario == load_scenario(builtin_path(name))
    assert scenario.world.workspace == (0.0, 0.0, 50.0, 50.0)


def test_builtin_paper_endpoints() -> None:
    def ends(name: str) -> list[tuple[tuple[float, ...], tuple[float, float]]]:
        return [(r.start[:2], r.goal) for r in load_scenario(name).robots]
    assert ends('case_study_1') == [((5, 45), (45, 5)), ((5, 5), (45, 45))]
    assert ends('case_study_2') == [((5, 5), (45, 45)), ((45, 45), (5, 5))]
    assert ends('application') == [((5, 45), (45, 5)), ((5, 5), (45, 45))]
    assert ends('table2_s1') == [((5, 45), (45, 5))]
    assert ends('table2_s2') == [((5, 5), (45, 45))]
    assert ends('table2_s3') == [((5, 25), (45, 5))]


def test_application_tractors_face_their_goals() -> None:
    for robot in load_scenario('application').robots:
        x, y, theta0, theta1 = robot.start
        bearing = math.atan2(robot.goal[1] - y, robot.goal[0] - x)
        assert abs(math.remainder(theta0 - bearing, math.tau)) < math.radians(30)
        assert abs(math.remainder(theta1 - theta0, math.tau)) < math.radians(30)
        assert (robot.length, robot.trailer_length, robot.width, robot.radius) == (1.0, 1.0, 0.5, 0.6)


def _border_clearance(item: Circle | Segment, workspace: tuple[float, float, float, float]) -> float:
    xmin, ymin, xmax, ymax = workspace
    if isinstance(item, Circle):
        (x, y), r = item.center, item.radius
        return min(x - xmin, xmax - x, y - ymin, ymax - y) - r
    return min(min(x - xmin, xmax - x, y - ymin, ymax - y) for x, y in (item.start, item.end))


@pytest.mark.parametrize('name', sorted(BUILTINS))
def test_builtin_design_constraints(name: str) -> None:
    """Sanity of the hand-made layouts: free starts/goals, obstacles inside the map, a free border."""
    world = load_scenario(name).world
    for item in world.obstacle_list:
        assert _border_clearance(item, world.workspace) >= 2.0, item
        if isinstance(item, Circle):
            assert 1.5 <= item.radius <= 5.0, item
    for robot in load_scenario(name).robots:
        for point in (robot.start[:2], robot.goal):
            assert world.obstacles.clearance(np.array(point)) >= 3.0, (robot.name, point)


def _gap(a: Circle | Segment, b: Circle | Segment) -> float:
    """Surface-to-surface distance between two obstacles (negative when circles overlap)."""
    if isinstance(a, Circle) and isinstance(b, Circle):
        return math.dist(a.center, b.center) - a.radius - b.radius
    if isinstance(a, Circle):
        a, b = b, a
    assert isinstance(a, Segment)
    return float(Obstacles([b]).path_clearance(np.array(a.start), np.array(a.end)))


@pytest.mark.parametrize('name', sorted(BUILTINS))
def test_builtin_gaps_open_or_closed(name: str) -> None:
    """Neighbouring obstacles either overlap or leave a gap a robot with its margins passes easily."""
    items = load_scenario(name).world.obstacle_list
    wide = 5.0 if name == 'application' else 3.0   # the tractor-trailer turns with a radius
    for i, item in enumerate(items):
        for other in items[i + 1:]:
            gap = _gap(item, other)
            assert gap < 0.0 or gap >= wide, (item, other, gap)


def test_table2_s1_line_is_clear() -> None:
    scenario = load_scenario('table2_s1')
    robot = scenario.robots[0]
    clearance = scenario.world.obstacles.path_clearance(np.array(robot.start[:2]), np.array(robot.goal))
    assert clearance >= 4.0
    assert len(scenario.world.obstacles) >= 8


def test_open_field_line_is_clear() -> None:
    scenario = load_scenario('open_field')
    for robot in scenario.robots:
        clearance = scenario.world.obstacles.path_clearance(np.array(robot.start[:2]), np.array(robot.goal))
        assert clearance > scenario.planner.sensing_range + robot.radius


@pytest.mark.parametrize('name', ['case_study_1', 'case_study_2', 'application', 'table2_s2', 'table2_s3'])
def test_obstacles_on_the_way(name: str) -> None:
    """The paper's scenarios put obstacles on each robot's straight line (and others off it)."""
    scenario = load_scenario(name)
    obstacles = scenario.world.obstacles
    for robot in scenario.robots:
        d = obstacles.path_distances(np.array(robot.start[:2]), np.array(robot.goal))
        assert (d < robot.radius).sum() >= 2, robot.name
        assert (d > 4.0).sum() >= 2, robot.name


def test_table2_s2_has_walls_on_the_way() -> None:
    scenario = load_scenario('table2_s2')
    obstacles = scenario.world.obstacles
    robot = scenario.robots[0]
    assert len(obstacles) > obstacles.n_circles   # line obstacles present
    d = obstacles.path_distances(np.array(robot.start[:2]), np.array(robot.goal))
    assert (d[obstacles.n_circles:] < robot.radius).sum() >= 1


# ----------------------------------------------------------------------------------------------- hostile files
# Issue "Hardening", items 3, 17, 18, 24: what a hostile or careless scenario file did to every tool loading it.

GOOD_ROBOT = "robots:\n  - {name: r1, model: point_mass, start: [5, 5], goal: [45, 45], radius: 0.5}\n"
LAUGHS = ''.join(f"x_{b}: &{b} [{', '.join([f'*{a}'] * 9)}]\n" for a, b in zip('abcdefgh', 'bcdefghi'))
BOMB = 'x_a: &a [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n' + LAUGHS   # 9^9 = 387 million items


def good_file(tmp_path: Path, extra: str) -> Path:
    return write(tmp_path, 'workspace: [0, 0, 50, 50]\n' + GOOD_ROBOT + extra)


def test_alias_bomb_is_refused_before_it_is_expanded(tmp_path: Path) -> None:
    assert len(BOMB) < 600
    expect_error(good_file(tmp_path, BOMB), 'beyond the limits', 'more than 1000000 nodes once its aliases are '
                 'expanded', 'line 10,')   # x_g (after 3 lines): 9^7 = 4.8 million items, the first over
    expect_error(write(tmp_path, BOMB + 'workspace: *i\n' + GOOD_ROBOT), 'more than 1000000 nodes')


def test_aliases_within_the_limits_load_and_mean_the_same(tmp_path: Path) -> None:
    text = ('x_defaults: &robot {model: point_mass, radius: 0.5}\nworkspace: &ws [0, 0, 50, 50]\n'
            'x_copy: *ws\nrobots:\n  - {<<: *robot, name: r1, start: [5, 45], goal: [45, 5]}\n'
            '  - {<<: *robot, name: r2, start: [5, 5], goal: [45, 45]}\n'
            'obstacles:\n  - circle: {center: [25, 25], radius: 4}\n  - segment: {start: [10, 30], end: [20, 30]}\n'
            'name: base\n')
    assert load_scenario(write(tmp_path, text)) == load_scenario(write(tmp_path, base(), 'plain.yaml'))


def test_too_many_aliases(tmp_path: Path) -> None:
    expect_error(good_file(tmp_path, 'x_r: &r 1\nx_list: [' + ', '.join(['*r'] * 10_001) + ']\n'),
                 'more than 10000 aliases')
    assert load_scenario(good_file(tmp_path, 'x_r: &r 1\nx_list: [' + ', '.join(['*r'] * 10_000) + ']\n'))


def test_an_alias_inside_itself_is_refused(tmp_path: Path) -> None:
    expect_error(good_file(tmp_path, 'x_loop: &a [1, *a]\n'), 'an alias refers to a collection that contains it')


class CountedRepr:
    """A value whose repr counts its calls: an error message must not render a huge value whole."""

    calls = 0

    def __repr__(self) -> str:
        CountedRepr.calls += 1
        return 'item'


@pytest.mark.parametrize('where', ['workspace', 'robots.0.radius', 'planner.a', 'obstacles.0.circle',
                                   'description'])
def test_error_messages_never_render_a_huge_value(where: str) -> None:
    huge = [CountedRepr()] * 1_000_000   # what an alias bomb builds: one object, shared
    data = base()
    *parents, last = where.split('.')
    node: Any = data
    for step in parents:
        node = node[int(step)] if step.isdigit() else node.setdefault(step, {})
    node[int(last) if last.isdigit() else last] = huge
    CountedRepr.calls = 0
    with pytest.raises(ScenarioError) as info:
        parse_scenario(data)
    assert CountedRepr.calls < 100 and len(str(info.value)) < 300, (CountedRepr.calls, str(info.value)[:300])


def test_error_messages_never_show_a_huge_key_or_name(tmp_path: Path) -> None:
    long = 'k' * 400_000   # within the 1 MiB file limit, also twice
    assert len(bad(tmp_path, lambda d: d.update({long: 1}), 'unknown top-level key')) < 400
    assert len(bad(tmp_path, lambda d: d.update(planner={long: 1}), 'unknown planner parameter')) < 400
    assert len(bad(tmp_path, lambda d: d['obstacles'][0]['circle'].update({long: 1}), 'unknown key')) < 400
    name = 'r' * 400_000
    assert len(bad(tmp_path, lambda d: [r.update(name=name) for r in d['robots']], 'is already used')) < 400


def test_a_huge_integer_planner_parameter_is_one_line(tmp_path: Path) -> None:
    expect_error(good_file(tmp_path, 'planner: {n_fireflies: ' + '9' * 400 + '}\n'),
                 'planner.n_fireflies: planner parameter n_fireflies must be a finite number, got an integer of 400 '
                 'digits')


def test_deep_nesting_is_refused_even_where_it_is_ignored(tmp_path: Path) -> None:
    expect_error(good_file(tmp_path, 'x_deep: ' + '[' * 1000 + ']' * 1000 + '\n'),
                 'collections nested deeper than 64 levels', 'line 4,')
    expect_error(good_file(tmp_path, 'x_deep:\n' + ''.join('  ' * i + '- \n' for i in range(100))), 'deeper than 64')
    assert load_scenario(good_file(tmp_path, 'x_deep: ' + '[' * 63 + ']' * 63 + '\n'))   # with the top level: 64
    nested = 'x_a: &a ' + '[' * 40 + ']' * 40 + '\nx_b: ' + '[' * 30 + '*a' + ']' * 30 + '\n'
    expect_error(good_file(tmp_path, nested), 'nested deeper than 64 levels once its aliases are expanded')


def test_an_integer_longer_than_python_reads_is_refused(tmp_path: Path) -> None:
    expect_error(good_file(tmp_path, 'x_big: ' + '7' * 5000 + '\n'), 'an integer of 5000 digits (at most 4300)')
    expect_error(good_file(tmp_path, 'x_big: 0x' + 'f' * 5000 + '\n'), 'an integer of 5000 digits')
    assert load_scenario(good_file(tmp_path, 'x_big: ' + '7' * 4300 + '\n'))   # ignored, as before


def test_a_file_over_the_size_limit_is_not_read(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = good_file(tmp_path, 'x_pad: "' + 'x' * (1024 * 1024) + '"\n')

    def refuse(self: Path) -> bytes:
        raise AssertionError('read a file over the limit')

    monkeypatch.setattr(Path, 'read_bytes', refuse)
    expect_error(path, 'bytes, more than scenario files may have (1048576, 1 MiB)')


@pytest.mark.parametrize('text', ['!!int abc', '!!float abc', '2001-02-30', '!!timestamp abc', '!!bool maybe',
                                  '!!int ""', '!!int 0x'])
def test_bad_tagged_scalars_are_invalid_yaml(tmp_path: Path, text: str) -> None:
    expect_error(good_file(tmp_path, f'x_value: {text}\n'), 'invalid YAML at line 4, column 10: cannot read')


# YAML 1.1 numbers (item 17): refused where their reading differs from their digits, naming the key.

@pytest.mark.parametrize('text, reading, fix', [
    ('[045, 25]', 'is 045, which YAML 1.1 reads as the octal number 37', 'write 45 without the leading zero'),
    ('[-0_45, 25]', 'is -0_45, which YAML 1.1 reads as the octal number -37', 'write -45'),
    ('[08, 25]', 'is 08, which YAML 1.1 reads as text', 'write 8 without the leading zero'),
    ('[50:00, 25]', 'is 50:00, which YAML 1.1 reads as 3000 (base 60', 'write the number itself'),
    ('[1:30.5, 25]', 'is 1:30.5, which YAML 1.1 reads as 90.5 (base 60', 'write the number itself'),
])
def test_yaml_1_1_numbers_that_change_are_refused(tmp_path: Path, text: str, reading: str, fix: str) -> None:
    path = write(tmp_path, f'workspace: [0, 0, 50, 50]\nrobots:\n  - {{name: r1, model: point_mass, start: {text}, '
                           'goal: [45, 45], radius: 0.5}\n')
    expect_error(path, f'robots[0].start[0] {reading}', fix)


def test_yaml_1_1_numbers_in_planner_and_workspace(tmp_path: Path) -> None:
    expect_error(good_file(tmp_path, 'planner: {max_sim_time: 50:00}\n'), 'planner.max_sim_time is 50:00',
                 '3000')
    expect_error(write(tmp_path, 'workspace: [0, 0, 050, 50]\n' + GOOD_ROBOT), 'workspace[2] is 050',
                 'octal number 40')


def test_leading_zeros_that_change_nothing_load_as_their_digits_say(tmp_path: Path) -> None:
    text = ('workspace: [00, 0, 50, 50]\nrobots:\n  - {name: r1, model: point_mass, start: [05, 007], '
            'goal: [45, 45], radius: 0.5}\nplanner: {n_fireflies: 0x20, max_iter: 1_0}\nname: 045\n'
            'x_note: 09:30\n')
    scenario = load_scenario(write(tmp_path, text))
    assert scenario.world.workspace == (0.0, 0.0, 50.0, 50.0) and scenario.robots[0].start == (5.0, 7.0)
    assert (scenario.planner.n_fireflies, scenario.planner.max_iter) == (32, 10)
    assert scenario.name == '045' and type(scenario.name) is str    # text, as a reader reads it


# Headings (item 24): normalised beyond one turn, kept as written within it.

@pytest.mark.parametrize('heading, expected', [
    (1e15, math.atan2(math.sin(1e15), math.cos(1e15))), (-7.0, -7.0 + 2 * math.pi), (3.5, 3.5), (-6.0, -6.0),
    (math.tau, math.tau)])
def test_start_headings_beyond_a_turn_are_normalised(tmp_path: Path, heading: float, expected: float) -> None:
    data = base()
    data['robots'] = [dict(TRACTOR, start=[5, 5, heading, heading])]
    start = load_scenario(write(tmp_path, data)).robots[0].start
    assert start[2] == pytest.approx(expected, abs=1e-12) and start[3] == start[2]
    assert abs(start[2]) <= math.tau


def test_an_integer_too_long_for_repr_is_shown_by_its_size() -> None:
    data = base()
    data['robots'][0]['radius'] = 10 ** 5000   # parse_scenario takes Python values: repr() of it raises
    with pytest.raises(ScenarioError, match=r'robots\[0\].radius must be a finite number, got an integer of about '
                                            r'5001 digits'):
        parse_scenario(data)


def test_a_robot_started_at_a_huge_heading_stays_on_the_map(tmp_path: Path) -> None:
    from fastep_core.simulator import simulate
    data = base()
    data.update(obstacles=[], robots=[dict(TRACTOR, start=[5, 5, 1e15, 1e15])])   # before: drove off to x = 90
    run = simulate(load_scenario(write(tmp_path, data)), 'fastep', 0).robots[0]
    rows = np.asarray(run.trajectory)
    assert run.reached and rows[:, 1:3].min() >= 0.0 and rows[:, 1:3].max() <= 50.0
