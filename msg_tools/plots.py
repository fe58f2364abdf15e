"""The paper's figures: robot paths among obstacles with waypoints (Fig. 2/5/8), cost over time (Fig. 3/6/9).

Plotting lives here, never in the algorithms: these functions take finished runs (from the simulator or,
later, from a recording) and write PNG files with matplotlib's Agg backend (no display needed).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import matplotlib

matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from fastep_core.geometry import Circle, Segment  # noqa: E402

if TYPE_CHECKING:
    from fastep_core.scenario import Scenario
    from fastep_core.simulator import Run

__all__ = ['plot_costs', 'plot_paths']


def plot_paths(scenario: 'Scenario', run: 'Run', out: str | Path) -> Path:
    """Obstacles, each robot's path, the waypoints its swarm generated, start (o) and goal (*)."""
    fig, ax = plt.subplots(figsize=(6.4, 6.4), dpi=110)
    xmin, ymin, xmax, ymax = scenario.world.workspace
    for obstacle in scenario.world.obstacle_list:
        if isinstance(obstacle, Circle):
            ax.add_patch(plt.Circle(obstacle.center, obstacle.radius, color='0.55', alpha=0.8, lw=0))
        elif isinstance(obstacle, Segment):
            ax.plot(*zip(obstacle.start, obstacle.end), color='0.25', lw=2.5, solid_capstyle='round')
    colours = plt.rcParams['axes.prop_cycle'].by_key()['color']
    specs = {spec.name: spec for spec in scenario.robots}
    for k, robot in enumerate(run.robots):
        colour = colours[k % len(colours)]
        path = np.array([row[1:3] for row in robot.trajectory], dtype=float).reshape(-1, 2)
        # A robot with no trajectory (nothing recorded) still gets its start, goal and legend entry.
        ax.plot(path[:, 0], path[:, 1], color=colour, lw=1.6, label=f'{robot.name} ({robot.path_length:.1f} m)')
        if robot.waypoints:
            wp = np.array(robot.waypoints)
            ax.plot(wp[:, 0], wp[:, 1], 'x', color=colour, ms=5, mew=1.2)
        spec = specs[robot.name]
        ax.plot(*spec.start[:2], 'o', color=colour, ms=7, mfc='white', mew=2)
        ax.plot(*spec.goal, '*', color=colour, ms=13)
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect('equal')
    ax.set_xlabel('x (m)')
    ax.set_ylabel('y (m)')
    ax.set_title(f'{scenario.name}: {"FAStep" if run.algorithm == "fastep" else "ACO"}-Kinematic, seed {run.seed}')
    ax.legend(loc='upper right', fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out)
    plt.close(fig)
    return out


def plot_costs(run: 'Run', out: str | Path) -> Path:
    """The fitness of the step in use over time, one line per robot: zero while only kinematics run."""
    fig, ax = plt.subplots(figsize=(7, 3.2), dpi=110)
    for robot in run.robots:
        if robot.cost:
            series = np.array(robot.cost)
            ax.plot(series[:, 0], series[:, 1], lw=1.2, label=robot.name)
    ax.set_xlabel('time (s)')
    ax.set_ylabel('cost f (eq. 10)')
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out)
    plt.close(fig)
    return out
