"""The figures: what they hold (lines, patches, titles), read back from the matplotlib Figures."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle as CirclePatch

from fastep_core.experiments.batches import PAPER, Record, example_paths
from fastep_core.geometry import Circle, Segment
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.scenario import load_scenario, parse_scenario
from fastep_core.simulator import RobotRun, Run, simulate
from msg_tools import plots

PNG = b'\x89PNG\r\n\x1a\n'

# Two robots, a circle and a wall: every kind of artist of the paths figure.
SCENARIO = {
    'name': 'crossing_wall', 'workspace': [0, 0, 20, 20],
    'obstacles': [{'circle': {'center': [10, 10], 'radius': 1.5}},
                  {'segment': {'start': [4, 15], 'end': [8, 17]}}],
    'robots': [{'name': 'r1', 'model': 'point_mass', 'start': [2, 10], 'goal': [18, 10.5], 'radius': 0.5},
               {'name': 'r2', 'model': 'point_mass', 'start': [10, 2], 'goal': [10.5, 18], 'radius': 0.4}],
    'planner': {'alpha1': 0.5, 'alpha2': 0.5, 'max_speed': 2.0},
}


def lines(fig: Figure, ax: int = 0) -> list[Line2D]:
    return list(fig.axes[ax].get_lines())


def xy(line: Line2D) -> np.ndarray:
    return np.column_stack([np.asarray(line.get_xdata(), dtype=float), np.asarray(line.get_ydata(), dtype=float)])


def by_marker(fig: Figure, marker: str) -> list[Line2D]:
    return [line for line in lines(fig) if line.get_marker() == marker]


@pytest.fixture(scope='module')
def simulated() -> tuple[Any, Run]:
    scenario = parse_scenario(SCENARIO)
    return scenario, simulate(scenario, 'fastep', 3)


def test_paths_figure_of_a_simulated_run(simulated: tuple[Any, Run]) -> None:
    scenario, run = simulated
    fig = plots.run_paths_figure(scenario, run)
    ax = fig.axes[0]
    assert ax.get_title() == 'crossing_wall: FAStep-Kinematic, seed 3'
    assert (ax.get_xlim(), ax.get_ylim()) == ((0.0, 20.0), (0.0, 20.0))
    # The obstacles: the circle as a patch, the wall as a line between its ends.
    circles = [p for p in ax.patches if isinstance(p, CirclePatch)]
    assert [(tuple(p.center), p.radius) for p in circles] == [((10.0, 10.0), 1.5)]
    assert any(xy(line).tolist() == [[4.0, 15.0], [8.0, 17.0]] for line in lines(fig))
    # One line per robot holding its trajectory, named with its length; its waypoints, start and goal.
    labels = [f'{r.name} ({r.path_length:.1f} m)' for r in run.robots]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == labels
    for label, robot, spec in zip(labels, run.robots, scenario.robots):
        (path,) = [line for line in lines(fig) if line.get_label() == label]
        assert xy(path).tolist() == [row[1:3] for row in robot.trajectory]
        colour = path.get_color()
        mine = [line for line in lines(fig) if line.get_color() == colour]
        assert [xy(line).tolist() for line in mine if line.get_marker() == 'o'] == [[list(spec.start)]]
        assert [xy(line).tolist() for line in mine if line.get_marker() == '*'] == [[list(spec.goal)]]
        assert [xy(line).tolist() for line in mine if line.get_marker() == 'x'] == ([robot.waypoints]
                                                                                  if robot.waypoints else [])
    assert any(r.waypoints for r in run.robots)   # the run planned steps, so the waypoints were drawn


@pytest.mark.parametrize('algorithm', ALGORITHMS)
def test_the_title_names_the_algorithm(algorithm: str) -> None:
    scenario = load_scenario('open_field')
    run = Run(7, algorithm, [RobotRun(name=spec.name, model=spec.model) for spec in scenario.robots])
    expected = {'fastep': 'FAStep-Kinematic', 'fastep_paper': 'FAStep-Kinematic (paper policy)', 'aco': 'ACO-Kinematic',
                'optimal': 'Optimal-Kinematic', 'dwa': 'DWA', 'fastep_route': 'FAStep-Route'}[algorithm]
    assert plots.run_paths_figure(scenario, run).axes[0].get_title() == f'open_field: {expected}, seed 7'


def test_a_robot_without_trajectory_is_drawn_without_a_path(tmp_path: Path) -> None:
    # fastep-launch reports from odometry: a robot whose odometry never arrived has no rows (CI once crashed here).
    scenario = load_scenario('case_study_1')
    run = Run(0, 'fastep', [RobotRun(name=spec.name, model=spec.model) for spec in scenario.robots])
    fig = plots.run_paths_figure(scenario, run)
    paths = [line for line in lines(fig) if line.get_label().startswith(('r1 ', 'r2 '))]
    assert [len(line.get_xdata()) for line in paths] == [0, 0]
    assert len(by_marker(fig, 'o')) == len(by_marker(fig, '*')) == 2     # starts and goals are still there
    circles = [o for o in scenario.world.obstacle_list if isinstance(o, Circle)]
    assert len([p for p in fig.axes[0].patches if isinstance(p, CirclePatch)]) == len(circles)
    out = plots.plot_paths(scenario, run, tmp_path / 'empty.png')
    assert out.read_bytes().startswith(PNG)


def test_long_paths_are_thinned_for_drawing_only() -> None:
    t = np.linspace(0.0, 1.0, 3 * plots.PLOT_POINTS + 1)
    robot = plots.RobotPath('r1', np.column_stack([t, t * t]), 1.5, np.zeros((0, 2)))
    fig = plots.paths_figure([Segment((0.0, 1.0), (1.0, 1.0))], None, [robot], 'long')
    (path,) = [line for line in lines(fig) if line.get_label() == 'r1 (1.5 m)']
    drawn = xy(path)
    assert len(drawn) <= plots.PLOT_POINTS + 1 and drawn[-1].tolist() == [1.0, 1.0] and drawn[0].tolist() == [0, 0]


def test_cost_and_velocity_figures_have_one_line_per_robot_and_one_panel_per_robot() -> None:
    costs = {'r1': [[0.0, 0.0], [1.0, 2.5]], 'r2': [[0.5, 1.0]], 'r3': np.zeros((0, 2))}
    fig = plots.cost_figure(costs, 'two')
    assert [(line.get_label(), xy(line).tolist()) for line in lines(fig)] == [
        ('r1', [[0.0, 0.0], [1.0, 2.5]]), ('r2', [[0.5, 1.0]])]
    velocities = [plots.Velocities('a', 'cmd_vel', 'point_mass', np.array([[0.0, 3.0, 4.0, 0.0]])),
                  plots.Velocities('b', 'odom', 'tractor_trailer', np.array([[0.0, 1.0, 0.2, -0.5]]))]
    fig = plots.velocity_figure(velocities, 'two')
    assert len(fig.axes) == 2 and fig.axes[0].get_title() == 'two: controller velocities'
    assert [line.get_label() for line in lines(fig, 0)] == ['vx (m/s)', 'vy (m/s)', 'speed (m/s)']
    assert lines(fig, 0)[2].get_ydata()[0] == 5.0
    assert [(line.get_label(), line.get_ydata()[0]) for line in lines(fig, 1)] == [('v (m/s)', 1.0),
                                                                                  ('omega (rad/s)', -0.5)]
    assert [ax.get_ylabel() for ax in fig.axes] == ['a: cmd_vel', 'b: odom']


def record(algorithm: str, seed: int, path_length: float, compute_time: float) -> Record:
    return Record('table2_s1', algorithm, seed, 'r1', True, False, path_length, 30.0, compute_time, 0.2, 3, 'arrived')


def test_bench_box_plots_show_each_planner_the_paper_and_the_optimum() -> None:
    records = [record(a, seed, base + seed, 0.1 * seed) for a, base in (('fastep', 57.0), ('aco', 60.0))
               for seed in range(3)]
    fig = plots.box_plot_figure(records, {'table2_s1': {'r1': 52.0}}, 'path_length')
    ax = fig.axes[0]
    assert ax.get_title() == 'table2_s1' and ax.get_ylabel() == 'path length (m)'
    assert [t.get_text() for t in ax.get_xticklabels()] == ['FAStep', 'ACO']
    paper = by_marker(fig, 'x')
    assert [xy(line).tolist() for line in paper] == [[[1.0, PAPER['table2_s1']['fastep']['path']]],
                                                     [[2.0, PAPER['table2_s1']['aco']['path']]]]
    assert any(list(line.get_ydata()) == [52.0, 52.0] and line.get_linestyle() == '--' for line in lines(fig))
    # One box per planner: its median (58, 61 m) drawn across it at x = 1, 2.
    for k, median in ((1, 58.0), (2, 61.0)):
        (line,) = [line for line in lines(fig) if list(line.get_ydata()) == [median, median]]
        assert np.mean(line.get_xdata()) == pytest.approx(k)


def test_bench_example_paths_draw_the_optimum_and_one_run_per_planner(tmp_path: Path) -> None:
    examples = example_paths(['table2_s1'], ['fastep', 'optimal'], seed=0)
    assert list(examples[0].runs) == ['fastep']        # the optimum is drawn as the exact path
    fig = plots.example_paths_figure(examples)
    ax = fig.axes[0]
    assert ax.get_title() == 'table2_s1 (seed 0)'
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    exact = examples[0].optimal['r1']
    robot = examples[0].runs['fastep'].robots[0]
    assert exact is not None
    assert labels == [f'optimal {exact.length:.2f} m', f'FAStep-Kinematic {robot.path_length:.2f} m']
    (driven,) = [line for line in lines(fig) if line.get_label().startswith('FAStep')]
    assert xy(driven).tolist() == [row[1:3] for row in robot.trajectory]
    circles = [o for o in examples[0].scenario.world.obstacle_list if isinstance(o, Circle)]
    assert len([p for p in ax.patches if isinstance(p, CirclePatch)]) == len(circles)
    written = plots.bench_figures([record('fastep', 0, 57.0, 0.1)], {}, tmp_path, prefix='t')
    assert [p.name for p in written] == ['t_path_length.png', 't_compute_time.png', 't_paths.png']
    assert all(p.read_bytes().startswith(PNG) for p in written)


@pytest.mark.parametrize('name, magic', [('fig', PNG), ('fig.PNG', PNG), ('fig.svg', b'<?xml'), ('fig.pdf', b'%PDF')])
def test_save_writes_exactly_the_file_it_is_given(tmp_path: Path, name: str, magic: bytes) -> None:
    """Without a suffix matplotlib wrote fig.png and the commands said 'wrote fig' (issue "Hardening", 19)."""
    path = plots.save(Figure(), tmp_path / name)
    assert path == tmp_path / name and path.read_bytes().startswith(magic)
    assert [p.name for p in tmp_path.iterdir()] == [name]
