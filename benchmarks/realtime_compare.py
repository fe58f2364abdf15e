"""The families benchmark in lock step and with planning latency counted, side by side (docs/real_time.md).

    fastep-bench --families --worlds 30 --out /tmp/lock --report families --no-figures
    fastep-bench --families --worlds 30 --realtime --out /tmp/rt --report families --no-figures
    python -m benchmarks.realtime_compare /tmp/lock/families.json /tmp/rt/families.json

Per family and planner: arrived / robot runs, collided, mean path / optimum and the median simulated time to goal in
each, and the mean ratio of the time to goal to the time the robot's exact shortest path takes at its world's
max_speed.
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
from pathlib import Path
from typing import Any, Sequence

from fastep_core.experiments.batches import cached_scenario
from fastep_core.experiments.families import FAMILY_NAMES
from fastep_core.experiments.random_worlds import family_source
from fastep_core.planning.algorithms import algorithm_name


def _groups(rows: Sequence[dict[str, Any]]) -> dict[tuple[str, str], list[dict[str, Any]]]:
    out: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for row in rows:
        out.setdefault((row['family'], row['algorithm']), []).append(row)
    return out


def _top_speed(row: dict[str, Any]) -> float:
    return cached_scenario(family_source(row['family'], row['world'])).planner.max_speed


def _cells(rows: list[dict[str, Any]]) -> list[str]:
    ok = [r for r in rows if r['reached'] and not r['collided']]
    ratios = [r['path_opt'] for r in ok if r['path_opt'] is not None]
    times = [r['sim_time'] for r in ok if r['sim_time'] is not None]
    slow = [r['sim_time'] / (r['optimum'] / _top_speed(r)) for r in ok
            if r['sim_time'] is not None and r['optimum'] and _top_speed(r) > 0.0]
    return [f'{len(ok)}/{len(rows)}', str(sum(r['collided'] for r in rows)),
            f'{statistics.fmean(ratios):.3f}' if ratios else '-',
            f'{statistics.median(times):.1f}' if times else '-',
            f'{statistics.fmean(slow):.2f}' if slow else '-']


def compare(locked: dict[str, Any], timed: dict[str, Any]) -> str:
    """The markdown table of two fastep-bench --families JSON documents (lock step first)."""
    before, after = _groups(locked['rows']), _groups(timed['rows'])
    lines = ['| family | planner | arrived | collided | path / opt. | time (median s) | time / at max_speed | '
             'arrived | collided | path / opt. | time (median s) | time / at max_speed |',
             '|---|---|---|---|---|---|---|---|---|---|---|---|']
    for key in before:
        if key not in after:
            continue
        family, algorithm = key
        lines.append('| ' + ' | '.join([FAMILY_NAMES.get(family, family), algorithm_name(algorithm),
                                        *_cells(before[key]), *_cells(after[key])]) + ' |')
    return '\n'.join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('lock_step', type=Path, help='fastep-bench --families JSON without --realtime')
    parser.add_argument('realtime', type=Path, help='... and with it')
    args = parser.parse_args(argv)
    locked, timed = (json.loads(path.read_text()) for path in (args.lock_step, args.realtime))
    if timed.get('realtime') is None or locked.get('realtime') is not None:
        parser.error('give the lock-step JSON first, then the --realtime one')
    print(compare(locked, timed))
    factor = timed['realtime']
    print(f'\nLeft: lock step. Right: --realtime {factor:g}. time / at max_speed: time to goal over the time the '
          'exact shortest path takes at the world\'s max_speed, mean over the arrivals.')
    return 0 if math.isfinite(factor) else 1


if __name__ == '__main__':
    raise SystemExit(main())
