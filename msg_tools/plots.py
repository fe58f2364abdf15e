"""Every figure of the project, in one place: the paper's path, cost and velocity figures and fastep-bench's.

- paths among the obstacles with the waypoints, start (o) and goal (*) (Fig. 2/5/8): of a simulated or live
  run (fastep-sim --plot, fastep-launch --plot) and of a recording (fastep-report paths.png), one drawing;
- cost over time (Fig. 3/6/9) and the controller's velocities (Fig. 4) of a recording (fastep-report);
- fastep-bench: box plots of path length and compute time per scenario and planner, and example paths with
  the exact optimum.

Plotting lives here, never in the algorithms (fastep_core imports no matplotlib). Each figure is built by a
function that returns the matplotlib Figure (tests read its lines and patches); `save` writes it as PNG with
the Agg backend (no display needed) and closes it. Titles name planners by
fastep_core.planning.algorithms.algorithm_name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Sequence

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from numpy.typing import ArrayLike, NDArray  # noqa: E402

from fastep_core.experiments import METRICS, PAPER, ExamplePaths, Record, example_paths, metric_values  # noqa: E402
from fastep_core.geometry import Circle, Obstacle, Segment  # noqa: E402
from fastep_core.planning.algorithms import algorithm_name  # noqa: E402

if TYPE_CHECKING:
    from fastep_core.scenario import Scenario
    from fastep_core.simulator import Run

__all__ = ['PLOT_POINTS', 'RobotPath', 'Velocities', 'bench_figures', 'box_plot_figure', 'cost_figure',
           'draw_world', 'example_paths_figure', 'paths_figure', 'plot_paths', 'run_paths_figure', 'save', 'title',
           'velocity_figure']

FloatArray = NDArray[np.float64]
PLOT_POINTS = 5000   # points drawn per line at most: long recordings are thinned for drawing only
OBSTACLE_GREY = '0.55'
WALL_GREY = '0.25'
# fastep-bench's planners keep their colours across panels.
ALGORITHM_COLOURS = {'fastep': 'tab:red', 'aco': 'tab:blue', 'optimal': 'tab:olive', 'fastep_route': 'tab:purple'}


def title(what: str, algorithm: str = '', seed: int | None = None) -> str:
    """'table2_s1: FAStep-Kinematic, seed 0': the scenario (or file), the planner's name, the seed if known."""
    text = f'{what}: {algorithm_name(algorithm)}' if algorithm else what
    return text if seed is None else f'{text}, seed {seed}'


def save(fig: Figure, out: str | Path, dpi: float | None = None) -> Path:
    """Write the figure to exactly ``out`` (the format from its suffix, PNG without one) and close it.

    The format is passed explicitly: given no suffix, matplotlib would write ``out.png`` instead of ``out``,
    and the caller would report a file that does not exist.
    """
    path = Path(out)
    form = path.suffix[1:].lower() or 'png'
    try:
        if dpi is None:
            fig.savefig(path, format=form)
        else:
            fig.savefig(path, format=form, dpi=dpi)
    finally:
        plt.close(fig)
    return path


def _thin(rows: ArrayLike) -> FloatArray:
    """At most PLOT_POINTS rows, evenly spread, the last one kept."""
    data = np.asarray(rows, dtype=float)
    if len(data) <= PLOT_POINTS:
        return data
    step = int(math.ceil(len(data) / PLOT_POINTS))
    return np.concatenate([data[::step], data[-1:]])


def _colours() -> list[str]:
    return list(plt.rcParams['axes.prop_cycle'].by_key()['color'])


def _grid(n: int, max_cols: int = 4) -> tuple[int, int]:
    """Rows and columns for n panels, at most max_cols wide."""
    cols = max(1, min(n, max_cols))
    return max(1, -(-n // cols)), cols


def draw_world(ax: Axes, obstacles: Sequence[Obstacle], workspace: Sequence[float] | None) -> None:
    """Circles as grey discs (patches), walls as dark lines; the axes span the workspace when it is known."""
    for obstacle in obstacles:
        if isinstance(obstacle, Circle):
            ax.add_patch(plt.Circle(obstacle.center, obstacle.radius, color=OBSTACLE_GREY, alpha=0.8, lw=0))
        elif isinstance(obstacle, Segment):
            ax.plot(*zip(obstacle.start, obstacle.end), color=WALL_GREY, lw=2.5, solid_capstyle='round')
    if workspace is not None:
        xmin, ymin, xmax, ymax = workspace
        ax.set_xlim(xmin, xmax)
        ax.set_ylim(ymin, ymax)
    ax.set_aspect('equal')


# ----------------------------------------------------------------------------------------------- paths

@dataclass(frozen=True)
class RobotPath:
    """What the paths figure shows of one robot."""

    name: str
    xy: FloatArray                      # (n, 2) the path driven, in time order (may be empty)
    length: float                       # metres driven (measured on every sample, before thinning)
    waypoints: FloatArray               # (k, 2) the waypoints its swarm planned
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None


def paths_figure(obstacles: Sequence[Obstacle], workspace: Sequence[float] | None, robots: Sequence[RobotPath],
                 text: str) -> Figure:
    """Obstacles, each robot's path (one line labelled with its name and length), its waypoints (x), start (o)
    and goal (*), one colour per robot."""
    fig, ax = plt.subplots(figsize=(6.4, 6.4), dpi=110)
    draw_world(ax, obstacles, workspace)
    colours = _colours()
    for k, robot in enumerate(robots):
        colour = colours[k % len(colours)]
        xy = _thin(np.asarray(robot.xy, dtype=float).reshape(-1, 2))
        # A robot with no path (no odometry arrived) still gets its line in the legend, start and goal.
        ax.plot(xy[:, 0], xy[:, 1], color=colour, lw=1.6, label=f'{robot.name} ({robot.length:.1f} m)')
        waypoints = np.asarray(robot.waypoints, dtype=float).reshape(-1, 2)
        if len(waypoints):
            ax.plot(waypoints[:, 0], waypoints[:, 1], 'x', color=colour, ms=5, mew=1.2)
        if robot.start is not None:
            ax.plot(*robot.start, 'o', color=colour, ms=7, mfc='white', mew=2)
        if robot.goal is not None:
            ax.plot(*robot.goal, '*', color=colour, ms=13)
    ax.set_xlabel('x (m)')
    ax.set_ylabel('y (m)')
    ax.set_title(text)
    if robots:
        ax.legend(loc='upper right', fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def run_paths_figure(scenario: Scenario, run: Run) -> Figure:
    """The paths figure of a simulated (fastep-sim) or live (fastep-launch) run of a scenario."""
    specs = {spec.name: spec for spec in scenario.robots}
    robots = []
    for robot in run.robots:
        spec = specs[robot.name]
        robots.append(RobotPath(
            robot.name, np.array([row[1:3] for row in robot.trajectory], dtype=float).reshape(-1, 2),
            robot.path_length, np.array(robot.waypoints, dtype=float).reshape(-1, 2),
            (float(spec.start[0]), float(spec.start[1])), (float(spec.goal[0]), float(spec.goal[1]))))
    return paths_figure(scenario.world.obstacle_list, scenario.world.workspace, robots,
                        title(scenario.name, run.algorithm, run.seed))


def plot_paths(scenario: Scenario, run: Run, out: str | Path) -> Path:
    """Write run_paths_figure as PNG (fastep-sim --plot, fastep-launch --plot)."""
    return save(run_paths_figure(scenario, run), out)


# ----------------------------------------------------------------------------------------------- time series

def cost_figure(costs: Mapping[str, ArrayLike], text: str) -> Figure:
    """Cost of the step in use over time, one line per robot: rows (t, cost), t in seconds since the goal."""
    fig, ax = plt.subplots(figsize=(7, 3.2), dpi=110)
    colours = _colours()
    drawn = False
    for k, (name, rows) in enumerate(costs.items()):
        series = _thin(np.asarray(rows, dtype=float).reshape(-1, 2))
        if len(series):
            ax.plot(series[:, 0], series[:, 1], lw=1.2, color=colours[k % len(colours)], label=name)
            drawn = True
    ax.set_xlabel('time since the goal (s)')
    ax.set_ylabel('cost f (eq. 10)')
    ax.set_title(text)
    if drawn:
        ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


@dataclass(frozen=True)
class Velocities:
    """One robot's velocity commands (or odometry twist) over time: rows (t, linear.x, linear.y, angular.z)."""

    name: str
    source: str            # the topic they come from: cmd_vel or odom
    model: str             # point_mass: vx, vy and the speed; tractor_trailer: v and omega
    rows: FloatArray


def velocity_figure(robots: Sequence[Velocities], text: str) -> Figure:
    """One panel per robot with its velocities over time (t in seconds since the goal)."""
    n = max(1, len(robots))
    fig, axes = plt.subplots(n, 1, figsize=(7, 2.4 * n), dpi=110, sharex=True, squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        data = _thin(np.asarray(robot.rows, dtype=float).reshape(-1, 4))
        if len(data):
            t = data[:, 0]
            if robot.model == 'tractor_trailer':
                ax.plot(t, data[:, 1], lw=1.1, label='v (m/s)')
                ax.plot(t, data[:, 3], lw=1.1, label='omega (rad/s)')
            else:
                ax.plot(t, data[:, 1], lw=1.1, label='vx (m/s)')
                ax.plot(t, data[:, 2], lw=1.1, label='vy (m/s)')
                ax.plot(t, np.hypot(data[:, 1], data[:, 2]), lw=0.9, ls='--', color='0.4', label='speed (m/s)')
            ax.legend(fontsize=7, loc='upper right')
        ax.set_ylabel(f'{robot.name}: {robot.source}')
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel('time since the goal (s)')
    axes[0, 0].set_title(f'{text}: controller velocities')
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------------------------- fastep-bench

def box_plot_figure(records: Sequence[Record], optimal: Mapping[str, Mapping[str, float | None]],
                    metric: str) -> Figure:
    """One panel per scenario: a box per planner of `metric` (fastep_core.experiments.metric_values); for path
    length also the paper's means (red x) and the exact optimum (green dashed)."""
    scenarios = list(dict.fromkeys(r.scenario for r in records))
    algorithms = list(dict.fromkeys(r.algorithm for r in records))
    rows, cols = _grid(len(scenarios))
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4.0 * rows), squeeze=False)
    for ax in axes.flat[len(scenarios):]:
        ax.set_visible(False)
    for ax, scenario in zip(axes.flat, scenarios):
        data = [metric_values([r for r in records if r.scenario == scenario and r.algorithm == a], metric)
                for a in algorithms]
        ax.boxplot(data, tick_labels=[algorithm_name(a).replace('-Kinematic', '') for a in algorithms])
        paper = PAPER.get(scenario, {})
        if metric == 'path_length':
            for k, a in enumerate(algorithms, 1):
                if a in paper:
                    ax.plot(k, paper[a]['path'], 'rx', ms=9, label='paper mean' if k == 1 else None)
            for length in {v for v in optimal.get(scenario, {}).values() if v}:
                ax.axhline(length, color='green', ls='--', lw=1, label='optimal')
            if ax.get_legend_handles_labels()[0]:
                ax.legend(fontsize=8)
        ax.set_title(scenario)
        ax.set_ylabel(METRICS[metric])
        ax.grid(axis='y', alpha=0.3)
    fig.tight_layout()
    return fig


def example_paths_figure(examples: Sequence[ExamplePaths]) -> Figure:
    """One panel per scenario: its obstacles, every robot's exact optimal path (green) and one run of every
    planner (fastep_core.experiments.example_paths)."""
    rows, cols = _grid(len(examples))
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 5.2 * rows), squeeze=False)
    for ax in axes.flat[len(examples):]:
        ax.set_visible(False)
    for ax, example in zip(axes.flat, examples):
        world = example.scenario.world
        draw_world(ax, world.obstacle_list, world.workspace)
        for k, path in enumerate(p for p in example.optimal.values() if p is not None):
            ax.plot(*path.points.T, color='tab:green', lw=3, alpha=0.5,
                    label=f'optimal {path.length:.2f} m' if k == 0 else None)
        for algorithm, run in example.runs.items():
            for k, robot in enumerate(run.robots):
                xy = np.array([row[1:3] for row in robot.trajectory], dtype=float).reshape(-1, 2)
                ax.plot(*xy.T, color=ALGORITHM_COLOURS.get(algorithm), lw=1.2,
                        label=f'{algorithm_name(algorithm)} {robot.path_length:.2f} m' if k == 0 else None)
        ax.set_title(f'{example.source} (seed {example.seed})')
        ax.legend(fontsize=7, loc='best')
    fig.tight_layout()
    return fig


def bench_figures(records: Sequence[Record], optimal: Mapping[str, Mapping[str, float | None]], out_dir: Path,
                  prefix: str = 'table2') -> list[Path]:
    """fastep-bench's figures: out_dir/PREFIX_{path_length,compute_time}.png (box plots) and PREFIX_paths.png
    (example paths of the first seed)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written = [save(box_plot_figure(records, optimal, metric), out_dir / f'{prefix}_{metric}.png', dpi=100)
               for metric in ('path_length', 'compute_time')]
    scenarios = list(dict.fromkeys(r.scenario for r in records))
    algorithms = list(dict.fromkeys(r.algorithm for r in records))
    examples = example_paths(scenarios, algorithms, seed=min(r.seed for r in records))
    written.append(save(example_paths_figure(examples), out_dir / f'{prefix}_paths.png', dpi=90))
    return written
