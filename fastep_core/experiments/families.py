"""The families benchmark: every planner on many unseen random worlds of each family, judged against the optimum.

Why: Table 2's three worlds are the ones the paper (and every tuning) looked at. A planner's worth is what it
does on worlds nobody picked (fastep_core.experiments.random_worlds.FAMILIES). `fastep-bench --families` runs this
module; docs/clutter.md shows its tables.

- Worlds: world k of a family is `random_family_data(family, FAMILY_SEED0 + k)`, named 'FAMILY:SEED', solvable
  by construction; the runs are batches.run_batch over them, and the records do not depend on the engine or
  the number of workers (only the times in them do).
- Collisions: the simulator's judgement against the true world (fastep_core.metrics.trajectory_margins).
- Optimum: per robot, alone, the exact shortest path keeping radius + clearance_margin (docs/optimality.md);
  path / optimum over the robots that arrived without collision.
- Compute: wall seconds spent planning and simulating, and CPU seconds of the whole simulate call (not
  inflated by other load), also per metre driven; activations per metre: swarm (or ant colony) runs per metre.
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

from fastep_core.errors import ParameterError
from fastep_core.experiments import batches
from fastep_core.experiments.batches import Record
from fastep_core.experiments.random_worlds import ALL_FAMILIES, FAMILY_SEED0, family_source, parse_family_source
from fastep_core.planning.algorithms import algorithm_name

if TYPE_CHECKING:
    from fastep_core.experiments.cluster import ClusterSpec, Engine

__all__ = ['FAMILY_NAMES', 'Row', 'Summary', 'family_sources', 'run_families', 'rows_of', 'summarise',
           'worst_runs', 'markdown_report', 'load_average']

FAMILY_NAMES: dict[str, str] = {'circle_field': 'circle fields', 'circles_walls': 'circles + walls',
                                'u_trap': 'U-traps', 'multi_robot': '2-4 robots',
                                'tractor_trailer': 'tractor-trailers',
                                'diff_drive_walls': 'diff drive: circles + walls',
                                'diff_drive_robots': 'diff drive: 1-4 robots', 'crossing_movers': 'crossing movers',
                                'unknown_obstacles': 'unknown obstacles', 'misplaced_obstacles': 'misplaced obstacles',
                                'dynamic_mix': 'movers + unknown + misplaced, 2-4 robots',
                                'dense_clutter': 'dense clutter', 'dense_clutter_laser': 'dense clutter, laser only',
                                'dense_clutter_jackal': 'dense clutter, laser only, Jackal box'}
"""What tables and figures call each family."""


def family_sources(families: Sequence[str], worlds: int) -> list[str]:
    """The sources of the first `worlds` worlds of each family, family by family."""
    return [family_source(f, FAMILY_SEED0 + k) for f in families for k in range(worlds)]


def run_families(families: Sequence[str], algorithms: Sequence[str], worlds: int, runs: int = 1,
                 workers: int = 2, *, seed0: int = 0, progress: bool | None = False, label: str = 'families',
                 overrides: dict[str, float] | None = None, realtime: float | None = None,
                 cluster: ClusterSpec | Engine | str | None = None) -> list[Record]:
    """Every planner on `worlds` worlds per family, run seeds seed0..seed0+runs-1 (deterministic planners once);
    `realtime`: fastep_core.simulator.simulate's latency factor (None: lock step); `cluster`: run on Dask
    (batches.run_batch)."""
    for family in families:
        if family not in ALL_FAMILIES:
            raise ParameterError(f'unknown world family {family!r}; choose one of {", ".join(ALL_FAMILIES)}')
    return batches.run_batch(family_sources(families, worlds), algorithms, runs, workers, seed0=seed0,
                                 progress=progress, label=label, overrides=overrides, realtime=realtime,
                                 cluster=cluster)


@dataclass(frozen=True)
class Row:
    """One robot in one run, with what the family table needs (the JSON's per-run rows)."""

    family: str
    world: int                 # the world's seed
    algorithm: str
    seed: int                  # the run's seed
    robot: str
    robots: int                # robots in the world
    reached: bool
    collided: bool
    min_clearance: float
    path_length: float
    optimum: float | None      # the exact shortest path of this robot alone (None: none keeps the clearance)
    path_opt: float | None     # path_length / optimum, for a robot that arrived without collision
    sim_time: float | None
    compute_time: float        # this robot's wall seconds
    cpu_time: float            # CPU seconds of the whole run (all robots)
    activations: int
    activations_per_m: float
    status: str
    ticks: int | None = None              # --realtime: control ticks ...
    stale_ticks: int | None = None        # ... of which without a fresh plan
    max_plan_latency: float | None = None  # the longest planning latency (s)

    def to_json(self) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def rows_of(records: Sequence[Record]) -> list[Row]:
    """The records of run_families as rows, each with its robot's optimum (computed once per world)."""
    optimum = {source: batches.optimal_lengths(source) for source in dict.fromkeys(r.scenario for r in records)}
    robots = {source: len(lengths) for source, lengths in optimum.items()}
    out = []
    for r in records:
        parsed = parse_family_source(r.scenario)
        family, world = parsed if parsed is not None else (r.scenario, 0)
        best = optimum[r.scenario].get(r.robot)
        out.append(Row(family, world, r.algorithm, r.seed, r.robot, robots[r.scenario], r.reached, r.collided,
                       r.min_clearance, r.path_length, best, r.path_length / best if best and r.ok else None,
                       r.sim_time, r.compute_time, r.cpu_time, r.activations,
                       r.activations / r.path_length if r.path_length > 0 else math.nan, r.status,
                       r.ticks, r.stale_ticks, r.max_plan_latency))
    return out


def _runs(rows: Sequence[Row]) -> dict[tuple[int, int], list[Row]]:
    """The rows of each run (world, seed): a multi-robot run has one row per robot."""
    out: dict[tuple[int, int], list[Row]] = {}
    for row in rows:
        out.setdefault((row.world, row.seed), []).append(row)
    return out


def _median(values: Sequence[float]) -> float:
    finite = [v for v in values if v is not None and math.isfinite(v)]
    return float(np.median(finite)) if finite else math.nan


@dataclass(frozen=True)
class Summary:
    """One family and planner over all its runs."""

    family: str
    algorithm: str
    worlds: int
    runs: int                  # simulate calls
    robot_runs: int
    arrived: int               # robots that arrived without collision
    collided: int              # robots that touched an obstacle or another robot
    path_opt_mean: float
    path_opt_worst: float
    cpu_per_run: float         # median CPU seconds per run
    cpu_per_run_mean: float
    compute_per_run: float     # median wall seconds per run (robots' compute_time summed)
    cpu_vs_aco: float          # median over the (world, seed) runs of CPU / ACO-Kinematic's CPU (nan without aco)
    cpu_ms_per_m: float        # median over runs of CPU milliseconds per metre driven
    compute_ms_per_m: float    # the same with wall compute time
    activations_per_m: float   # median over robots
    activations: int           # total
    sim_time: float            # median simulated time to goal of the robots that arrived

    def to_json(self) -> dict[str, Any]:
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def summarise(rows: Sequence[Row]) -> list[Summary]:
    """One Summary per family and planner, families then planners in the order the rows come in."""
    aco_cpu = {(r.family, r.world, r.seed): r.cpu_time for r in rows if r.algorithm == 'aco'}
    aco_any = {(r.family, r.world): r.cpu_time for r in rows if r.algorithm == 'aco'}
    out = []
    for family in dict.fromkeys(r.family for r in rows):
        for algorithm in dict.fromkeys(r.algorithm for r in rows):
            mine = [r for r in rows if r.family == family and r.algorithm == algorithm]
            if not mine:
                continue
            runs = _runs(mine)
            firsts = [run[0] for run in runs.values()]
            ratios = [r.path_opt for r in mine if r.path_opt is not None]
            driven = {key: sum(r.path_length for r in run) for key, run in runs.items()}
            # A deterministic planner ran once per world: compare it with ACO's run of the same seed, else any.
            vs_aco = [r.cpu_time / aco_cpu.get((family, r.world, r.seed), aco_any.get((family, r.world), math.nan))
                      for r in firsts if (family, r.world) in aco_any]
            out.append(Summary(
                family, algorithm, len({r.world for r in mine}), len(runs), len(mine),
                sum(r.reached and not r.collided for r in mine), sum(r.collided for r in mine),
                float(np.mean(ratios)) if ratios else math.nan, float(np.max(ratios)) if ratios else math.nan,
                _median([r.cpu_time for r in firsts]), float(np.mean([r.cpu_time for r in firsts])),
                _median([sum(r.compute_time for r in run) for run in runs.values()]), _median(vs_aco),
                _median([1e3 * run[0].cpu_time / driven[key] for key, run in runs.items() if driven[key] > 0]),
                _median([1e3 * sum(r.compute_time for r in run) / driven[key] for key, run in runs.items()
                         if driven[key] > 0]),
                _median([r.activations_per_m for r in mine]), sum(r.activations for r in mine),
                _median([r.sim_time for r in mine if r.reached and not r.collided and r.sim_time is not None])))
    return out


def worst_runs(rows: Sequence[Row], algorithm: str | None = None) -> dict[str, Row]:
    """Per family the robot run with the largest path / optimum (of `algorithm`, or of any planner but the
    optimal one when there are others); a family without such a run is left out."""
    others = any(row.algorithm != 'optimal' for row in rows)
    out: dict[str, Row] = {}
    for row in rows:
        if row.path_opt is None or (row.algorithm != algorithm if algorithm else
                                    others and row.algorithm == 'optimal'):
            continue
        best = out.get(row.family)
        if best is None or row.path_opt > (best.path_opt or 0.0):
            out[row.family] = row
    return out


def load_average() -> float:
    """The 1-minute load average (nan where the platform has none)."""
    try:
        return os.getloadavg()[0]
    except OSError:
        return math.nan


def _num(x: float, digits: int = 2) -> str:
    return '-' if x is None or not math.isfinite(x) else f'{x:.{digits}f}'


def realtime_table(rows: Sequence[Row]) -> list[str]:
    """With --realtime: per family and planner, the control ticks without a fresh plan and the planning latencies
    (none without it)."""
    timed = [r for r in rows if r.ticks is not None and r.stale_ticks is not None and r.max_plan_latency is not None]
    if not timed:
        return []
    groups: dict[tuple[str, str], list[Row]] = {}
    for r in timed:
        groups.setdefault((r.family, r.algorithm), []).append(r)
    lines = ['', '### Planning latency (--realtime)', '',
             'Stale ticks: control ticks that drove on a plan no newer than the last tick\'s, of all ticks; latency: '
             'the longest planning pass of a robot run in seconds of the simulated robot (wall time x FACTOR), median '
             'and worst over the robot runs.', '',
             '| family | planner | stale ticks | latency median of the longest (s) | longest (s) |',
             '|---|---|---|---|---|']
    for (family, algorithm), group in groups.items():
        ticks = sum(r.ticks or 0 for r in group)
        stale = sum(r.stale_ticks or 0 for r in group)
        longest = [r.max_plan_latency or 0.0 for r in group]
        lines.append(f'| {FAMILY_NAMES.get(family, family)} | {algorithm_name(algorithm)} | '
                     f'{100.0 * stale / max(ticks, 1):.1f} % | {_num(_median(longest), 3)} | {_num(max(longest), 3)} |')
    return lines


def markdown_report(rows: Sequence[Row], *, command: str = '', notes: Sequence[str] = (),
                    worst_of: str | None = None) -> str:
    """Markdown: the family table (one line per family and planner) and each family's worst run (of planner
    `worst_of`, or of any planner but the optimal one; see worst_runs)."""
    summaries = summarise(rows)
    lines = ['## Planners on random world families', '']
    if command:
        lines += ['```', command, '```', '']
    lines += [*notes, *([''] if notes else [])]
    lines += ['Arrived: robots that reached the goal without collision / robot runs; collided: robots that touched '
              'an obstacle or another robot (the simulator\'s margins from every step, fastep_core.metrics). '
              'path / opt.: path length / the exact shortest path of the robot alone keeping radius + clearance '
              'margin, mean and worst over the robots that arrived. CPU per run: CPU seconds of a whole run (all '
              'robots; median and mean), immune to other load; compute: the wall seconds the robots spent '
              'planning and simulating (median per run); CPU / ACO\'s: median over the worlds of the ratio to '
              'ACO-Kinematic\'s run with the same world and seed; per metre: per metre driven (median over runs); '
              'activations per metre: median over robots; sim time: median over the robots that arrived.', '',
              '| family | planner | worlds | runs | arrived | collided | path / opt. mean | worst | '
              'CPU per run (median / mean s) | compute per run (median s) | CPU / ACO\'s | CPU ms per m | '
              'compute ms per m | activations per m | activations (total) | sim time (median s) |',
              '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|']
    for s in summaries:
        lines.append(
            f'| {FAMILY_NAMES.get(s.family, s.family)} | {algorithm_name(s.algorithm)} | {s.worlds} | {s.runs} | '
            f'{s.arrived}/{s.robot_runs} | {s.collided} | {_num(s.path_opt_mean, 3)} | {_num(s.path_opt_worst, 3)} | '
            f'{_num(s.cpu_per_run, 3)} / {_num(s.cpu_per_run_mean, 3)} | {_num(s.compute_per_run, 3)} | '
            f'{_num(s.cpu_vs_aco)} | {_num(s.cpu_ms_per_m, 1)} | {_num(s.compute_ms_per_m, 1)} | '
            f'{_num(s.activations_per_m, 3)} | {s.activations} | {_num(s.sim_time, 1)} |')
    lines += realtime_table(rows)
    worst = worst_runs(rows, worst_of)
    if worst:
        whose = f' ({algorithm_name(worst_of)})' if worst_of else ''
        lines += ['', f'### Worst path / optimum per family{whose}', '',
                  '| family | world | planner | seed | robot | path (m) | optimum (m) | path / opt. |',
                  '|---|---|---|---|---|---|---|---|']
        for family, row in worst.items():
            lines.append(f'| {FAMILY_NAMES.get(family, family)} | {family_source(family, row.world)} | '
                         f'{algorithm_name(row.algorithm)} | {row.seed} | {row.robot} | {row.path_length:.2f} | '
                         f'{_num(row.optimum or math.nan)} | {_num(row.path_opt or math.nan, 3)} |')
    return '\n'.join(lines) + '\n'
