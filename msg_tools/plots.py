"""Every figure of the project, in one place: the paper's path, cost and velocity figures and fastep-bench's.

- paths among the obstacles with the waypoints, start (o) and goal (*) (Fig. 2/5/8): of a simulated or live
  run (fastep-sim --plot, fastep-launch --plot) and of a recording (fastep-report paths.png), one drawing;
- cost over time (Fig. 3/6/9) and the controller's velocities (Fig. 4) of a recording (fastep-report);
- fastep-bench: box plots of path length and compute time per scenario and planner, and example paths with
  the exact optimum; with --families box plots of path / optimum and CPU per run per family and planner, and
  each family's worst world.

Plotting lives here, never in the algorithms (fastep_core imports no matplotlib). Each figure is built by a
function that returns the matplotlib Figure (tests read its lines and patches); `save` writes it as PNG with
the Agg backend (no display needed) and closes it. Titles name planners by
fastep_core.planning.algorithms.algorithm_name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Mapping, Sequence

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.artist import Artist  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from numpy.typing import ArrayLike, NDArray  # noqa: E402

from fastep_core.dynamic_world import DynamicWorld, map_generator  # noqa: E402
from fastep_core.experiments.batches import METRICS, PAPER, ExamplePaths, Record, example_paths, metric_values  # noqa: E402
from fastep_core.experiments.families import FAMILY_NAMES, worst_runs  # noqa: E402
from fastep_core.experiments.families import Row as FamilyRow  # noqa: E402
from fastep_core.experiments.random_worlds import family_source  # noqa: E402
from fastep_core.geometry import Circle, Obstacle, Segment  # noqa: E402
from fastep_core.planning.algorithms import algorithm_name  # noqa: E402

if TYPE_CHECKING:
    from fastep_core.perception.belief import Belief
    from fastep_core.scenario import Scenario
    from fastep_core.simulator import Run

__all__ = ['HEADING_ARROWS', 'HEADING_MODELS', 'PLOT_POINTS', 'RobotPath', 'Velocities', 'bench_figures',
           'box_plot_figure', 'close_all', 'cost_figure', 'draw_beliefs', 'draw_dynamic', 'draw_headings', 'draw_world',
           'example_paths_figure', 'family_box_figure', 'family_figures', 'paths_figure', 'plot_paths',
           'run_paths_figure', 'save', 'title', 'velocity_figure', 'yield_figure']

FloatArray = NDArray[np.float64]
PLOT_POINTS = 5000   # points drawn per line at most: long recordings are thinned for drawing only
OBSTACLE_GREY = '0.55'
WALL_GREY = '0.25'
MOVER_COLOUR = 'tab:purple'
MOVER_SNAPSHOTS = 5   # positions of each mover drawn over a run, t = 0 included
HEADING_ARROWS = 15   # arrows showing a robot's heading along its path (the start's included)
HEADING_MODELS = ('diff_drive', 'tractor_trailer')   # models whose trajectory rows carry a heading (row[3])
# fastep-bench's planners keep their colours across panels.
ALGORITHM_COLOURS = {'fastep': 'tab:red', 'fastep_paper': 'tab:orange', 'aco': 'tab:blue', 'optimal': 'tab:olive',
                     'dwa': 'tab:brown', 'fastep_route': 'tab:pink'}


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


def close_all(figures: Iterable[Figure]) -> None:
    """Close figures (pyplot keeps every figure it made until it is closed; closing one twice is harmless)."""
    for fig in figures:
        plt.close(fig)


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
    headings: FloatArray | None = None  # (n,) the heading at each point of xy (diff_drive, tractor-trailer)


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
        draw_headings(ax, robot, colour)
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


def draw_headings(ax: Axes, robot: RobotPath, colour: str) -> None:
    """Arrows of the robot's heading at HEADING_ARROWS points evenly spaced in time along its path, if it has one
    (a differential-drive base turns on the spot: its path alone does not show where it faced)."""
    if robot.headings is None:
        return
    xy = np.asarray(robot.xy, dtype=float).reshape(-1, 2)
    headings = np.asarray(robot.headings, dtype=float).reshape(-1)
    if not len(xy) or len(headings) != len(xy):
        return
    pick = np.unique(np.linspace(0, len(xy) - 1, HEADING_ARROWS).round().astype(int))
    ax.quiver(xy[pick, 0], xy[pick, 1], np.cos(headings[pick]), np.sin(headings[pick]), color=colour,
              angles='xy', scale_units='inches', scale=4.0, width=0.004, zorder=3)


def _outline(ax: Axes, obstacle: Obstacle, style: str, colour: str) -> None:
    if isinstance(obstacle, Circle):
        ax.add_patch(plt.Circle(obstacle.center, obstacle.radius, fill=False, ls=style, lw=1.4, ec=colour))
    else:
        ax.plot(*zip(obstacle.start, obstacle.end), ls=style, color=colour, lw=1.6)


def draw_dynamic(ax: Axes, scenario: Scenario, seed: int, duration: float) -> list[tuple[Artist, str]]:
    """What a v2 world adds to the paths figure; returns legend entries (handle, label).

    Unknown obstacles: their true place dashed, not filled (the planner was never told of them). Misplaced
    ones: their true place as every obstacle (filled), where the run's map put them dotted. Movers: their
    polyline dotted, and discs at MOVER_SNAPSHOTS evenly spaced times from 0 to `duration`, fading in and
    labelled with the time.
    """
    specs = scenario.obstacle_specs
    truth = DynamicWorld(scenario.world.workspace, specs)
    believed = truth.planner_map(map_generator(seed))
    entries: list[tuple[Artist, str]] = []
    unknown = [o.shape for o in specs if o.still and not o.known]
    for shape in unknown:
        _outline(ax, shape, '--', 'black')
    if unknown:
        entries.append((plt.Line2D([], [], ls='--', color='black'), 'unknown: true place'))
    known_true = [o.shape for o in specs if o.still and o.known]
    misplaced = [b for t, b in zip(known_true, believed.world.obstacle_list) if t != b]
    for shape in misplaced:
        _outline(ax, shape, ':', 'tab:green')
    if misplaced:
        entries.append((plt.Line2D([], [], ls=':', color='tab:green'), 'misplaced: on the map'))
    movers = truth.movers
    if len(movers):
        times = np.linspace(0.0, max(duration, 0.0), MOVER_SNAPSHOTS)
        centres = movers.positions(times)                                   # (snapshots, movers, 2)
        for k in range(len(movers)):
            path = movers.vertices[k]
            ax.plot(path[:, 0], path[:, 1], ':', color=MOVER_COLOUR, lw=1.2)
            for j, t in enumerate(times):
                centre = centres[j, k]
                ax.add_patch(plt.Circle(tuple(centre), movers.radii[k], color=MOVER_COLOUR, lw=0,
                                        alpha=0.15 + 0.5 * j / max(1, len(times) - 1)))
                ax.annotate(f'{t:.0f}s', tuple(centre), fontsize=6, ha='center', va='center', color='white')
            if not truth.known_movers[k]:
                ax.add_patch(plt.Circle(tuple(centres[0, k]), movers.radii[k], fill=False, ls='--', ec='black'))
        entries.append((plt.Line2D([], [], ls=':', marker='o', color=MOVER_COLOUR), 'mover: track, positions'))
    return entries


BELIEF_COLOUR = 'darkgoldenrod'   # apart from the robots' colour cycle


def draw_beliefs(ax: Axes, beliefs: Sequence[Belief]) -> list[tuple[Artist, str]]:
    """What robots with a sensor believed at the end of a run (fastep_core.perception): the still obstacles their
    scans showed (dash-dotted outlines), the map's obstacles their scans saw through (grey crosses at the
    centre), and the movers they tracked last (arrows of their velocity over 2 s); legend entries."""
    entries: list[tuple[Artist, str]] = []
    seen = [o for b in beliefs for o in b.seen_obstacles]
    for shape in seen:
        _outline(ax, shape, '-.', BELIEF_COLOUR)
    if seen:
        entries.append((plt.Line2D([], [], ls='-.', color=BELIEF_COLOUR), 'believed: seen by a scan'))
    dropped = [o for b in beliefs for o in b.dropped]
    for shape in dropped:
        x, y = shape.center if isinstance(shape, Circle) else np.mean([shape.start, shape.end], axis=0)
        ax.plot([x], [y], 'x', color='0.35', ms=7)
    if dropped:
        entries.append((plt.Line2D([], [], ls='', marker='x', color='0.35'), 'dropped: a scan saw through it'))
    movers = [m for b in beliefs for m in b.movers]
    for m in movers:
        ax.annotate('', xy=(m.position[0] + 2.0 * m.velocity[0], m.position[1] + 2.0 * m.velocity[1]),
                    xytext=m.position, arrowprops={'arrowstyle': '->', 'color': BELIEF_COLOUR, 'lw': 1.2})
    if movers:
        entries.append((plt.Line2D([], [], color=BELIEF_COLOUR, marker='>'), 'tracked at the end: 2 s ahead'))
    return entries


def run_paths_figure(scenario: Scenario, run: Run) -> Figure:
    """The paths figure of a simulated (fastep-sim) or live (fastep-launch) run of a scenario; a v2 world's
    movers, unknown and misplaced obstacles drawn as draw_dynamic says."""
    specs = {spec.name: spec for spec in scenario.robots}
    robots = []
    for robot in run.robots:
        spec = specs[robot.name]
        headings = np.array([row[3] for row in robot.trajectory], dtype=float) if spec.model in HEADING_MODELS \
            else None
        robots.append(RobotPath(
            robot.name, np.array([row[1:3] for row in robot.trajectory], dtype=float).reshape(-1, 2),
            robot.path_length, np.array(robot.waypoints, dtype=float).reshape(-1, 2),
            (float(spec.start[0]), float(spec.start[1])), (float(spec.goal[0]), float(spec.goal[1])), headings))
    if scenario.is_static:
        return paths_figure(scenario.world.obstacle_list, scenario.world.workspace, robots,
                            title(scenario.name, run.algorithm, run.seed))
    known = [o.shape for o in scenario.obstacle_specs if o.still and o.known]   # unknown: outlines only
    fig = paths_figure(known, scenario.world.workspace, robots, title(scenario.name, run.algorithm, run.seed))
    ax = fig.axes[0]
    duration = max((row[0] for robot in run.robots for row in robot.trajectory[-1:]), default=0.0)
    entries = draw_dynamic(ax, scenario, run.seed, duration)
    entries += draw_beliefs(ax, [robot.belief for robot in run.robots if robot.belief is not None])
    handles, labels = ax.get_legend_handles_labels()
    ax.legend(handles + [h for h, _ in entries], labels + [text for _, text in entries], loc='upper right',
              fontsize=8)
    return fig


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
    model: str             # point_mass: vx, vy and the speed; tractor_trailer, diff_drive: v and omega
    rows: FloatArray


def velocity_figure(robots: Sequence[Velocities], text: str) -> Figure:
    """One panel per robot with its velocities over time (t in seconds since the goal)."""
    n = max(1, len(robots))
    fig, axes = plt.subplots(n, 1, figsize=(7, 2.4 * n), dpi=110, sharex=True, squeeze=False)
    for ax, robot in zip(axes[:, 0], robots):
        data = _thin(np.asarray(robot.rows, dtype=float).reshape(-1, 4))
        if len(data):
            t = data[:, 0]
            if robot.model in HEADING_MODELS:   # commanded by (v, omega): linear.x, angular.z
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


YIELD_COLOURS = {'': 'tab:red', 'yielding': 'tab:orange', 'waiting': 'gold', 'evading': 'tab:cyan'}


def yield_figure(scenario: Scenario, seed: int, rows: ArrayLike, kinds: Sequence[str], text: str,
                 snapshots: Sequence[float], window: tuple[float, float] | None = None) -> Figure:
    """A robot meeting movers (planning/safety/yielding.py): left, its path among the obstacles coloured by what
    yielding did each tick, with the robot and every mover at the same `snapshots` (s, numbered alike);
    right, its speed over time, shaded the same way. rows: (t, x, y, speed) per tick; kinds: per tick, '' (the
    command as planned), 'yielding', 'waiting' or 'evading'; window: the times (s) drawn (default: all)."""
    data = np.asarray(rows, dtype=float).reshape(-1, 4)
    kind_of = np.asarray(list(kinds), dtype=object)
    if window is not None and len(data):
        inside = (data[:, 0] >= window[0]) & (data[:, 0] <= window[1])
        data, kind_of = data[inside], kind_of[inside]
    fig, (ax, speed_ax) = plt.subplots(1, 2, figsize=(12, 5), dpi=110, gridspec_kw={'width_ratios': [1.1, 1]})
    draw_world(ax, [o.shape for o in scenario.obstacle_specs if o.still], scenario.world.workspace)
    truth = DynamicWorld(scenario.world.workspace, scenario.obstacle_specs)
    movers = truth.movers
    for k in range(len(movers)):
        path = movers.vertices[k]
        ax.plot(path[:, 0], path[:, 1], ':', color=MOVER_COLOUR, lw=1.2)
    for kind, colour in YIELD_COLOURS.items():
        mask = np.asarray(kind_of == kind, dtype=bool)
        if mask.any():
            ax.scatter(data[mask, 1], data[mask, 2], s=3, color=colour, zorder=3,
                       label=kind or 'as planned')
            speed_ax.scatter(data[mask, 0], data[mask, 3], s=3, color=colour, label=kind or 'as planned')
    radius = scenario.robots[0].radius
    for j, t in enumerate(snapshots):
        k = int(np.clip(np.searchsorted(data[:, 0], t), 0, len(data) - 1))
        ax.add_patch(plt.Circle((data[k, 1], data[k, 2]), radius, fill=False, ec='black', lw=0.8, zorder=4))
        ax.annotate(str(j + 1), (data[k, 1], data[k, 2]), fontsize=7, ha='center', va='center', zorder=5)
        if len(movers):
            for centre, r in zip(movers.positions(np.array([data[k, 0]]))[0], movers.radii):
                ax.add_patch(plt.Circle(tuple(centre), r, color=MOVER_COLOUR, alpha=0.35, lw=0, zorder=4))
                ax.annotate(str(j + 1), tuple(centre), fontsize=7, ha='center', va='center', color='white', zorder=5)
        speed_ax.axvline(data[k, 0], color='0.6', lw=0.6)
        speed_ax.annotate(str(j + 1), (data[k, 0], 0.0), fontsize=7, ha='center', va='bottom')
    if len(data):
        pad = 6.0
        xs, ys = data[:, 1], data[:, 2]
        ax.set_xlim(max(scenario.world.workspace[0], xs.min() - pad), min(scenario.world.workspace[2], xs.max() + pad))
        ax.set_ylim(max(scenario.world.workspace[1], ys.min() - pad), min(scenario.world.workspace[3], ys.max() + pad))
    ax.set_aspect('equal')
    ax.legend(fontsize=7, loc='upper left', markerscale=3)
    ax.set_title('path; numbers: the robot and the movers at the same time', fontsize=9)
    fig.suptitle(text, fontsize=10)
    speed_ax.set_ylim(bottom=0.0)
    speed_ax.set_xlabel('time (s)')
    speed_ax.set_ylabel('speed (m/s)')
    speed_ax.grid(alpha=0.3)
    speed_ax.legend(fontsize=7, loc='lower right', markerscale=3)
    speed_ax.set_title('speed, by what yielding did', fontsize=9)
    fig.tight_layout()
    return fig


# ----------------------------------------------------------------------------------------------- fastep-bench

def box_plot_figure(records: Sequence[Record], optimal: Mapping[str, Mapping[str, float | None]],
                    metric: str) -> Figure:
    """One panel per scenario: a box per planner of `metric` (fastep_core.experiments.batches.metric_values); for path
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
    planner (fastep_core.experiments.batches.example_paths)."""
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


# ----------------------------------------------------------------------------------------------- families

def family_box_figure(rows: Sequence[FamilyRow], metric: str, label: str, log: bool = False) -> Figure:
    """One panel per family: a box per planner of `metric`, a field of experiments.families.Row (None and nan
    values left out: path_opt exists only for robots that arrived); cpu_time counted once per run."""
    family_list = list(dict.fromkeys(r.family for r in rows))
    algorithms = list(dict.fromkeys(r.algorithm for r in rows))
    rows_, cols = _grid(len(family_list), max_cols=5)
    fig, axes = plt.subplots(rows_, cols, figsize=(3.4 * cols, 3.8 * rows_), squeeze=False)
    for ax in axes.flat[len(family_list):]:
        ax.set_visible(False)
    for ax, family in zip(axes.flat, family_list):
        data = []
        for a in algorithms:
            mine = [r for r in rows if r.family == family and r.algorithm == a]
            if metric == 'cpu_time':   # one value per run, not per robot
                mine = list({(r.world, r.seed): r for r in mine}.values())
            values = [getattr(r, metric) for r in mine]
            data.append(np.array([v for v in values if v is not None and math.isfinite(v)], dtype=float))
        ax.boxplot(data, tick_labels=[algorithm_name(a).replace('-Kinematic', '') for a in algorithms])
        if log:
            ax.set_yscale('log')
        ax.set_title(FAMILY_NAMES.get(family, family))
        ax.set_ylabel(label)
        ax.grid(axis='y', alpha=0.3)
        ax.tick_params(axis='x', labelrotation=30)
    fig.tight_layout()
    return fig


def family_figures(rows: Sequence[FamilyRow], out_dir: Path, prefix: str = 'families',
                   overrides: Mapping[str, float] | None = None, worst_of: str | None = None) -> list[Path]:
    """fastep-bench --families' figures: out_dir/PREFIX_path_opt.png (path / optimum per family and planner),
    PREFIX_cpu.png (CPU seconds per run, log scale) and PREFIX_worst.png (each family's world where a planner's
    path / optimum was worst - planner `worst_of`'s, or any but the optimal one's - every planner's run on it with
    that seed, and the exact optimum)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written = [save(family_box_figure(rows, 'path_opt', 'path / exact optimum'), out_dir / f'{prefix}_path_opt.png',
                    dpi=100),
               save(family_box_figure(rows, 'cpu_time', 'CPU seconds per run', log=True),
                    out_dir / f'{prefix}_cpu.png', dpi=100)]
    worst = worst_runs(rows, worst_of)
    if worst:
        algorithms = list(dict.fromkeys(r.algorithm for r in rows))
        examples = [example_paths([family_source(row.family, row.world)], algorithms, row.seed,
                                  dict(overrides or {}))[0] for row in worst.values()]
        written.append(save(example_paths_figure(examples), out_dir / f'{prefix}_worst.png', dpi=80))
    return written
