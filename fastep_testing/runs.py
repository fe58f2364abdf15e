"""Runs to compare: the circle world the graph benchmarks and the multi-host harness drive, and whether a live run
is fastep-sim's (benchmarks.lock_step, fastep_testing.multi_host)."""

from __future__ import annotations

import math
from typing import Any

__all__ = ['circle_yaml', 'compare']


def circle_yaml(n: int, radius: float, max_speed: float, step_iterations: int = 0) -> str:
    """n point-mass robots on a circle swapping sides; step_iterations: PlannerParams' (0, the default, left out)."""
    lines = [f'name: circle_swap_{n}',
             f'description: {n} point-mass robots on a circle of radius {radius:g} m swapping to the opposite side',
             'workspace: [0, 0, 50, 50]', 'robots:']
    for k in range(n):
        a = 2.0 * math.pi * k / n
        dx, dy = radius * math.cos(a), radius * math.sin(a)
        lines += [f'  - name: r{k + 1}', '    model: point_mass',
                  f'    start: [{25 + dx:.4f}, {25 + dy:.4f}]', f'    goal: [{25 - dx:.4f}, {25 - dy:.4f}]',
                  '    radius: 0.5']
    budget = f', step_iterations: {step_iterations}' if step_iterations else ''
    lines += [f'planner: {{max_speed: {max_speed!r}{budget}}}']
    return '\n'.join(lines) + '\n'


def compare(live: list[dict[str, Any]], sim: list[dict[str, Any]]) -> tuple[bool, float]:
    """(same outcome to the rounding of --json, largest position difference at common trajectory times)."""
    same, worst = True, 0.0
    for a, b in zip(live, sim):
        same &= a['reached'] == b['reached'] and a['sim_time'] == b['sim_time'] and \
            abs(a['path_length'] - b['path_length']) <= 2e-6 and abs(a['min_clearance'] - b['min_clearance']) <= 2e-6
        rows = {round(r[0], 3): r[1:3] for r in b['trajectory']}
        for r in a['trajectory']:
            other = rows.get(round(r[0], 3))
            if other is not None:
                worst = max(worst, abs(r[1] - other[0]), abs(r[2] - other[1]))
    return same and worst <= 2e-6, worst
