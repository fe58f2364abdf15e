"""Figures of a batch of experiments (fastep-bench): box plots per scenario and planner, and the paths.

The numbers come from fastep_core.experiments; the drawing lives here because fastep_core imports no
matplotlib (nor anything above itself). Moved as it was from fastep_core/experiments.py.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from fastep_core.experiments import METRICS, NAMES, PAPER, Record, cached_scenario, metric_values

__all__ = ['figures', 'paths_figure']


def _grid(n: int, max_cols: int = 4) -> tuple[int, int]:
    """Rows and columns for n panels, at most max_cols wide."""
    cols = min(n, max_cols)
    return -(-n // cols), cols


def figures(records: Sequence[Record], optimal: dict[str, dict[str, float | None]], out_dir: Path,
            prefix: str = 'table2') -> list[Path]:
    """Box plots of path length and compute time per scenario and planner, and the paths (PNG, Agg)."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    out_dir.mkdir(parents=True, exist_ok=True)
    scenarios = list(dict.fromkeys(r.scenario for r in records))
    algorithms = list(dict.fromkeys(r.algorithm for r in records))
    written = []
    for metric in ('path_length', 'compute_time'):
        rows, cols = _grid(len(scenarios))
        fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 4.0 * rows), squeeze=False)
        for ax in axes.flat[len(scenarios):]:
            ax.set_visible(False)
        for ax, scenario in zip(axes.flat, scenarios):
            data = [metric_values([r for r in records if r.scenario == scenario and r.algorithm == a], metric)
                    for a in algorithms]
            ax.boxplot(data, tick_labels=[NAMES.get(a, a).replace('-Kinematic', '') for a in algorithms])
            paper = PAPER.get(scenario, {})
            if metric == 'path_length':
                for k, a in enumerate(algorithms, 1):
                    if a in paper:
                        ax.plot(k, paper[a]['path'], 'rx', ms=9, label='paper mean' if k == 1 else None)
                for opt in {v for v in optimal.get(scenario, {}).values() if v}:
                    ax.axhline(opt, color='green', ls='--', lw=1, label='optimal')
                if ax.get_legend_handles_labels()[0]:
                    ax.legend(fontsize=8)
            ax.set_title(scenario)
            ax.set_ylabel(METRICS[metric])
            ax.grid(axis='y', alpha=0.3)
        fig.tight_layout()
        path = out_dir / f'{prefix}_{metric}.png'
        fig.savefig(path, dpi=100)
        plt.close(fig)
        written.append(path)
    written.append(paths_figure(scenarios, algorithms, out_dir / f'{prefix}_paths.png',
                                seed=min(r.seed for r in records)))
    return written


def paths_figure(scenarios: Sequence[str], algorithms: Sequence[str], out: Path, seed: int = 0) -> Path:
    """Each scenario's obstacles, one run of every planner (the given seed) and the exact optimal path."""
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    from fastep_core.geometry import Circle
    from fastep_core.planning.optimal import shortest_path
    from fastep_core.simulator import simulate

    colours = {'fastep': 'tab:red', 'aco': 'tab:blue', 'optimal': 'tab:olive'}
    rows, cols = _grid(len(scenarios))
    fig, axes = plt.subplots(rows, cols, figsize=(5.0 * cols, 5.2 * rows), squeeze=False)
    for ax in axes.flat[len(scenarios):]:
        ax.set_visible(False)
    for ax, source in zip(axes.flat, scenarios):
        scenario = cached_scenario(source)
        for o in scenario.world.obstacle_list:
            if isinstance(o, Circle):
                ax.add_patch(plt.Circle(o.center, o.radius, color='0.6'))
            else:
                ax.plot([o.start[0], o.end[0]], [o.start[1], o.end[1]], color='0.3', lw=2.5)
        for k, spec in enumerate(scenario.robots):
            exact = shortest_path(scenario.world, spec.start[:2], spec.goal,
                                  spec.radius + scenario.planner.clearance_margin)
            if exact is not None:
                ax.plot(*exact.points.T, color='tab:green', lw=3, alpha=0.5,
                        label=f'optimal {exact.length:.2f} m' if k == 0 else None)
        for algorithm in algorithms:
            if algorithm == 'optimal':
                continue
            run = simulate(scenario, algorithm, seed)
            for k, robot in enumerate(run.robots):
                xy = np.array(robot.trajectory)[:, 1:3]
                ax.plot(*xy.T, color=colours.get(algorithm), lw=1.2,
                        label=f'{NAMES.get(algorithm, algorithm)} {robot.path_length:.2f} m' if k == 0 else None)
        xmin, ymin, xmax, ymax = scenario.world.workspace
        ax.set_xlim(xmin, xmax)
        ax.set_ylim(ymin, ymax)
        ax.set_aspect('equal')
        ax.set_title(f'{source} (seed {seed})')
        ax.legend(fontsize=7, loc='best')
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return out
