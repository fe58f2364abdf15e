"""Batch experiments: many seeded runs of several planners on several scenarios, and their statistics.

Why pure functions: the paper's Table 2 is the project's main claim, so regenerating it must be one reproducible call
from `fastep-bench`, `benchmarks/table2.py`, tuning and tests alike. `run_batch` spreads (scenario, algorithm, seed)
runs over a process pool or a Dask cluster (experiments.cluster); every run draws only from its own seed, so records
(returned sorted) do not depend on the engine, workers or finishing order. `summarise`: mean and sample std (ddof 1)
per scenario, planner and robot of path length and time to goal (runs that arrived without collision) and compute
time (all runs). `compare`: two planners on one metric, the paper's enhancement (ACO - FAStep) / ACO * 100 and a
two-sided Mann-Whitney U test (no distribution assumed: compute times are skewed, lengths bounded by the optimum).
`optimal_lengths`: the exact shortest path per robot, for the ratio path / optimum (a little below 1 is possible: runs
end within goal_tolerance and cut corners). `markdown_report` writes docs/table2.md; `example_paths` feeds its figure,
drawn one layer up (msg_tools.plots). 'optimal' draws no random numbers, so a batch runs it once, with the first seed.
"""

from __future__ import annotations

import contextlib
import functools
import math
import multiprocessing
import os
import time
from dataclasses import asdict, dataclass
from typing import TYPE_CHECKING, Iterable, Sequence, overload

import numpy as np

from fastep_core.cli import progress_bar
from fastep_core.errors import ParameterError
from fastep_core.experiments.random_worlds import parse_family_source, random_family_data
from fastep_core.planning.algorithms import algorithm_name, drives
from fastep_core.planning.shortest_path.optimal import OptimalPath, shortest_path
from fastep_core.scenario import Scenario, load_scenario, parse_scenario
from fastep_core.simulator import Run, simulate

if TYPE_CHECKING:
    from fastep_core.experiments.cluster import BatchIncomplete, ClusterSpec, Engine

__all__ = [
    'PAPER', 'TABLE2', 'DETERMINISTIC', 'METRICS', 'Record', 'Summary', 'Comparison',
    'Tasks', 'tasks', 'drives_scenario', 'run_task', 'run_batch', 'pool_context', 'summarise', 'compare', 'enhancement',
    'optimal_lengths', 'straight_lengths', 'markdown_report', 'metric_values', 'cached_scenario', 'ExamplePaths',
    'example_paths',
]

TABLE2: tuple[str, ...] = ('table2_s1', 'table2_s2', 'table2_s3')
"""The built-in scenarios of the paper's Table 2."""

PAPER: dict[str, dict[str, dict[str, float]]] = {
    # Table 2 of the paper: means of 30 runs; 'time' is MATLAB run time (s), dominated by step generation.
    'table2_s1': {'fastep': {'path': 56.56, 'time': 69.62}, 'aco': {'path': 56.77, 'time': 133.76}},
    'table2_s2': {'fastep': {'path': 59.69, 'time': 154.04}, 'aco': {'path': 65.75, 'time': 283.25}},
    'table2_s3': {'fastep': {'path': 45.73, 'time': 95.80}, 'aco': {'path': 48.54, 'time': 173.27}},
}

DETERMINISTIC = frozenset({'optimal'})
"""Algorithms without random draws: run once per scenario."""

METRICS: dict[str, str] = {
    'path_length': 'path length (m)',
    'sim_time': 'simulated time to goal (s)',
    'compute_time': 'compute time (s)',
    'cpu_time': 'CPU time per run (s)',
}


@dataclass(frozen=True)
class Record:
    """One robot in one run (what fastep-sim reports, without the trajectory)."""

    scenario: str
    algorithm: str
    seed: int
    robot: str
    reached: bool
    collided: bool
    path_length: float
    sim_time: float | None
    compute_time: float
    min_clearance: float
    activations: int
    status: str
    cpu_time: float = math.nan   # CPU seconds of the whole simulate call (all robots): immune to other load
    ticks: int | None = None     # --realtime: control ticks, those without a fresh plan, the longest latency (s)
    stale_ticks: int | None = None
    max_plan_latency: float | None = None

    @property
    def ok(self) -> bool:
        """Arrived without touching anything."""
        return self.reached and not self.collided

    def to_json(self) -> dict[str, object]:
        return asdict(self)


Task = tuple[str, str, int]


class Tasks(Sequence[Task]):
    """Every (scenario, algorithm, seed) simulate call of a batch, made when asked for: a batch of a million runs
    built every task first (1.8 GB after 60 s of `--runs 3000000`, no result). Deterministic algorithms get one
    seed; an algorithm is left out of a scenario with a robot it cannot drive (dwa and a tractor-trailer): its row
    is missing from the report, the rest of the batch runs."""

    def __init__(self, scenarios: Sequence[str], algorithms: Sequence[str], runs: int, seed0: int = 0) -> None:
        self.seed0 = seed0
        self.blocks = [(s, a, 1 if a in DETERMINISTIC else runs) for s in scenarios for a in algorithms
                       if drives_scenario(a, s)]
        self.ends = np.cumsum([count for _, _, count in self.blocks], dtype=np.int64)

    def __len__(self) -> int:
        return int(self.ends[-1]) if len(self.ends) else 0

    @overload
    def __getitem__(self, index: int) -> Task: ...

    @overload
    def __getitem__(self, index: slice) -> list[Task]: ...

    def __getitem__(self, index: int | slice) -> Task | list[Task]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        if index < 0:
            index += len(self)
        if not 0 <= index < len(self):
            raise IndexError(f'task {index} of {len(self)}')
        block = int(np.searchsorted(self.ends, index, side='right'))
        source, algorithm, _ = self.blocks[block]
        first = int(self.ends[block - 1]) if block else 0
        return source, algorithm, self.seed0 + index - first


def tasks(scenarios: Sequence[str], algorithms: Sequence[str], runs: int, seed0: int = 0) -> list[Task]:
    """Every task of a batch (Tasks), as a list."""
    return list(Tasks(scenarios, algorithms, runs, seed0))


def drives_scenario(algorithm: str, source: str) -> bool:
    """Can the algorithm drive every robot of the scenario (planning.algorithms.drives)?"""
    return all(drives(algorithm, spec.model) for spec in cached_scenario(source).robots)


@functools.lru_cache(maxsize=1024)
def cached_scenario(source: str) -> Scenario:
    """The scenario of a built-in name, a YAML path or a random family world ('u_trap:1000004',
    random_worlds.family_source), built once per process (a worker runs many seeds)."""
    family = parse_family_source(source)
    if family is not None and not os.path.exists(source):
        return parse_scenario(random_family_data(*family))
    return load_scenario(source)


def run_task(task: Task, overrides: tuple[tuple[str, float], ...] = (), realtime: float | None = None) -> list[Record]:
    """One simulate call (in a worker process); `overrides` replace planner parameters (used by tuning);
    `realtime`: simulate's latency factor (None: lock step)."""
    from dataclasses import replace

    source, algorithm, seed = task
    scenario = cached_scenario(source)
    if overrides:
        scenario = replace(scenario, planner=scenario.planner.with_overrides(dict(overrides)))
    cpu = time.process_time()
    run = simulate(scenario, algorithm, seed, realtime=realtime)
    cpu = time.process_time() - cpu
    return [Record(source, algorithm, seed, r.name, r.reached, r.collided, r.path_length, r.sim_time,
                   r.compute_time, r.min_clearance, r.activations, r.status, cpu,
                   *((None, None, None) if r.realtime is None else
                     (r.realtime.ticks, r.realtime.stale_ticks, r.realtime.max_latency)))
            for r in run.robots]


def pool_context() -> multiprocessing.context.BaseContext:
    """fork where the platform has it: workers start fast and need no importable __main__ (a script read
    from stdin, a notebook); elsewhere the platform's default."""
    return multiprocessing.get_context('fork' if 'fork' in multiprocessing.get_all_start_methods() else None)


def run_batch(scenarios: Sequence[str], algorithms: Sequence[str], runs: int, workers: int = 2, *,
              seed0: int = 0, progress: bool | None = False, label: str = 'runs',
              overrides: dict[str, float] | None = None, realtime: float | None = None,
              cluster: ClusterSpec | Engine | str | None = None) -> list[Record]:
    """Simulate every scenario with every algorithm for seeds seed0..seed0+runs-1; records sorted.

    workers <= 1 runs in this process. `progress`: a progress bar titled `label` on stderr, None when stderr
    is a terminal, True always, False never (fastep_core.cli.progress_bar). `cluster` (fastep_core.experiments.cluster:
    'local:N', a scheduler address, or an open Engine) runs the tasks there instead, `workers` unused; the
    records are the same. A cluster that can run no more (no worker left in time, no scheduler) raises
    cluster.BatchIncomplete, its `done` the records made (sorted), its `missing` the tasks without any.
    """
    if runs < 1:
        raise ParameterError(f'runs must be >= 1, got {runs}')
    every = Tasks(scenarios, algorithms, runs, seed0)
    # A shuffled order spreads whatever else loads the machine evenly over planners and scenarios (in
    # scenario-major order one planner's runs would share one stretch of background load). Made as they are
    # handed out: the pool's pipe, not a list, holds those not started.
    order = np.random.default_rng(seed0).permutation(len(every))
    todo = (every[int(k)] for k in order)
    frozen = tuple(sorted((overrides or {}).items()))
    job = functools.partial(run_task, overrides=frozen, realtime=realtime)
    out: list[Record] = []
    incomplete: BatchIncomplete | None = None
    with progress_bar(len(every), label, progress) as bar:
        if cluster is not None:
            from fastep_core.experiments.cluster import (  # Dask only when asked for
                BatchIncomplete,
                Engine,
                open_cluster,
            )
            with contextlib.ExitStack() as stack:
                engine = cluster if isinstance(cluster, Engine) else stack.enter_context(open_cluster(cluster))
                try:
                    for records in engine.map_unordered(job, todo, name=label):
                        out.extend(records)
                        bar.update()
                except BatchIncomplete as exc:   # the cluster is gone: the runs done still count, sorted below
                    incomplete = exc
        elif workers <= 1 or len(every) == 1:
            for task in todo:
                out.extend(job(task))
                bar.update()
        else:
            with pool_context().Pool(min(workers, len(every))) as pool:
                for records in pool.imap_unordered(job, todo):
                    out.extend(records)
                    bar.update()
    rows = {(s, a): i for i, (s, a) in enumerate((s, a) for s in scenarios for a in algorithms)}
    out.sort(key=lambda r: (rows[(r.scenario, r.algorithm)], r.seed, r.robot))
    if incomplete is not None:
        incomplete.done = out
        raise incomplete
    return out


# ----------------------------------------------------------------------------------------- statistics

@dataclass(frozen=True)
class Summary:
    """Per scenario, algorithm and robot: counts, and mean / sample std of each metric."""

    scenario: str
    algorithm: str
    robot: str
    runs: int
    arrived: int           # arrived without collision
    collided: int
    mean: dict[str, float]
    std: dict[str, float]


def metric_values(records: Iterable[Record], metric: str) -> np.ndarray:
    """The metric over the records it is defined for: compute time always, the rest for arrived runs."""
    if metric in ('compute_time', 'cpu_time'):
        return np.array([getattr(r, metric) for r in records], dtype=float)
    return np.array([getattr(r, metric) for r in records if r.ok], dtype=float)


def _mean_std(x: np.ndarray) -> tuple[float, float]:
    if x.size == 0:
        return math.nan, math.nan
    return float(x.mean()), float(x.std(ddof=1)) if x.size > 1 else 0.0


def summarise(records: Sequence[Record]) -> list[Summary]:
    """One Summary per (scenario, algorithm, robot), in the order the records come in."""
    groups: dict[tuple[str, str, str], list[Record]] = {}
    for r in records:
        groups.setdefault((r.scenario, r.algorithm, r.robot), []).append(r)
    out = []
    for (scenario, algorithm, robot), group in groups.items():
        mean, std = {}, {}
        for metric in METRICS:
            mean[metric], std[metric] = _mean_std(metric_values(group, metric))
        out.append(Summary(scenario, algorithm, robot, len(group), sum(r.ok for r in group),
                           sum(r.collided for r in group), mean, std))
    return out


def enhancement(aco: float, fastep: float) -> float:
    """The paper's enhancement of FAStep over ACO in percent: (ACO - FAStep) / ACO * 100."""
    return (aco - fastep) / aco * 100.0 if aco else math.nan


@dataclass(frozen=True)
class Comparison:
    """Planner a (FAStep) against planner b (ACO) on one metric of one scenario (all robots pooled)."""

    metric: str
    mean_a: float
    mean_b: float
    enhancement: float     # (b - a) / b * 100
    u: float
    p_value: float         # two-sided Mann-Whitney U
    n_a: int
    n_b: int

    @property
    def a_better(self) -> bool:
        """a has the smaller mean, significantly at p < 0.05."""
        return self.mean_a < self.mean_b and self.p_value < 0.05


def compare(records: Sequence[Record], scenario: str, metric: str, a: str = 'fastep',
            b: str = 'aco') -> Comparison:
    """Means, enhancement % and the two-sided Mann-Whitney U test of `metric` for planners a and b."""
    from scipy.stats import mannwhitneyu
    xa = metric_values([r for r in records if r.scenario == scenario and r.algorithm == a], metric)
    xb = metric_values([r for r in records if r.scenario == scenario and r.algorithm == b], metric)
    if xa.size == 0 or xb.size == 0:
        return Comparison(metric, _mean_std(xa)[0], _mean_std(xb)[0], math.nan, math.nan, math.nan,
                          int(xa.size), int(xb.size))
    if np.ptp(np.concatenate([xa, xb])) == 0.0:
        u, p = xa.size * xb.size / 2.0, 1.0            # all equal: nothing to tell apart
    else:
        res = mannwhitneyu(xa, xb, alternative='two-sided')
        u, p = float(res.statistic), float(res.pvalue)
    ma, mb = float(xa.mean()), float(xb.mean())
    return Comparison(metric, ma, mb, enhancement(mb, ma), u, p, int(xa.size), int(xb.size))


def optimal_lengths(source: str) -> dict[str, float | None]:
    """Exact shortest path length per robot (clearance radius + clearance_margin); None when there is none."""
    scenario = cached_scenario(source)
    out: dict[str, float | None] = {}
    for spec in scenario.robots:
        path = shortest_path(scenario.world, spec.start[:2], spec.goal,
                             spec.radius + scenario.planner.clearance_margin)
        out[spec.name] = None if path is None else path.length
    return out


def straight_lengths(source: str) -> dict[str, float]:
    scenario = cached_scenario(source)
    return {spec.name: math.dist(spec.start[:2], spec.goal) for spec in scenario.robots}


# ----------------------------------------------------------------------------------------- report

def _pm(mean: float, std: float, digits: int = 2) -> str:
    if math.isnan(mean):
        return '-'
    return f'{mean:.{digits}f} ± {std:.{digits}f}'


def _num(x: float | None, digits: int = 2, suffix: str = '') -> str:
    return '-' if x is None or (isinstance(x, float) and math.isnan(x)) else f'{x:.{digits}f}{suffix}'


def _p(p: float) -> str:
    if math.isnan(p):
        return '-'
    return f'{p:.2g}' if p >= 1e-3 else f'{p:.1e}'


def markdown_report(records: Sequence[Record], optimal: dict[str, dict[str, float | None]], *,
                    title: str = 'Table 2 regenerated', command: str = '') -> str:
    """Markdown: the Table 2 layout with the paper's numbers, the comparisons, and optimality ratios."""
    summaries = summarise(records)
    scenarios = list(dict.fromkeys(r.scenario for r in records))
    algorithms = list(dict.fromkeys(r.algorithm for r in records))
    runs = {a: len({r.seed for r in records if r.algorithm == a}) for a in algorithms}
    lines = [f'## {title}', '']
    if command:
        lines += ['```', command, '```', '']
    lines += ['Runs per cell: ' + ', '.join(f'{algorithm_name(a)} {n}' for a, n in runs.items()) +
              '. Means ± sample standard deviation; path length and simulated time over the runs that '
              'arrived without collision, compute time (wall seconds planning and simulating the robot, as '
              'fastep-sim reports it) and CPU time (process CPU seconds of the whole run, not inflated by other '
              'load on the machine) over all runs. "opt." is path length / exact shortest path keeping radius + '
              'clearance margin (planning/shortest_path/optimal.py: the tangent visibility graph of the inflated '
              'obstacles, searched with A*).', '']
    lines += ['| scenario | robot | planner | arrived | path (m) | paper path | path / opt. | '
              'sim time (s) | compute time (s) | CPU time (s) | paper time (s) |',
              '|---|---|---|---|---|---|---|---|---|---|---|']
    for s in summaries:
        paper = PAPER.get(s.scenario, {}).get(s.algorithm, {})
        opt = optimal.get(s.scenario, {}).get(s.robot)
        ratio = s.mean['path_length'] / opt if opt else math.nan
        lines.append(f'| {s.scenario} | {s.robot} | {algorithm_name(s.algorithm)} | '
                     f'{s.arrived}/{s.runs}{f" ({s.collided} collided)" if s.collided else ""} | '
                     f'{_pm(s.mean["path_length"], s.std["path_length"])} | {_num(paper.get("path"))} | '
                     f'{_num(ratio, 3)} | {_pm(s.mean["sim_time"], s.std["sim_time"], 1)} | '
                     f'{_pm(s.mean["compute_time"], s.std["compute_time"], 3)} | '
                     f'{_pm(s.mean["cpu_time"], s.std["cpu_time"], 3)} | {_num(paper.get("time"))} |')
    if 'fastep' in algorithms and 'aco' in algorithms:
        lines += ['', '### FAStep-Kinematic against ACO-Kinematic',
                  '', 'Enhancement = (ACO - FAStep) / ACO * 100 (positive: FAStep better); p: two-sided '
                  'Mann-Whitney U. The paper\'s "time" is MATLAB run time, so it compares with our compute '
                  'time; simulated time to goal is shown as well.', '',
                  '| scenario | path enh. | paper | p (path) | compute-time enh. | paper (time) | p (compute) | '
                  'CPU-time enh. | p (CPU) | sim-time enh. | p (sim time) |',
                  '|---|---|---|---|---|---|---|---|---|---|---|']
        for scenario in scenarios:
            c = {m: compare(records, scenario, m) for m in METRICS}
            table = PAPER.get(scenario)
            pe = enhancement(table['aco']['path'], table['fastep']['path']) if table else None
            te = enhancement(table['aco']['time'], table['fastep']['time']) if table else None
            lines.append(f'| {scenario} | {_num(c["path_length"].enhancement, 2, " %")} | {_num(pe, 2, " %")} | '
                         f'{_p(c["path_length"].p_value)} | {_num(c["compute_time"].enhancement, 2, " %")} | '
                         f'{_num(te, 2, " %")} | {_p(c["compute_time"].p_value)} | '
                         f'{_num(c["cpu_time"].enhancement, 2, " %")} | {_p(c["cpu_time"].p_value)} | '
                         f'{_num(c["sim_time"].enhancement, 2, " %")} | {_p(c["sim_time"].p_value)} |')
    baselines = [b for b in ('aco', 'dwa') if b in algorithms]
    others = [a for a in algorithms if a != 'optimal']
    if baselines and len(others) > 1:
        lines += ['', '### Every planner against the baselines: path length', '',
                  'Mean path of each planner against ACO-Kinematic\'s and DWA\'s in the same scenario (all robots '
                  'pooled); enhancement = (baseline - planner) / baseline * 100 (positive: shorter); p: two-sided '
                  'Mann-Whitney U ("1" where every run of both has the same length).', '',
                  '| scenario | planner | path (m) | ' +
                  ' | '.join(f'vs {algorithm_name(b)}: enh. | p' for b in baselines) + ' |',
                  '|---|---|---|' + '---|---|' * len(baselines)]
        for scenario in scenarios:
            for a in others:
                cells = []
                for b in baselines:
                    versus = compare(records, scenario, 'path_length', a, b) if a != b else None
                    cells.append('- | -' if versus is None else
                                 f'{_num(versus.enhancement, 2, " %")} | {_p(versus.p_value)}')
                mean = compare(records, scenario, 'path_length', a, baselines[0]).mean_a
                lines.append(f'| {scenario} | {algorithm_name(a)} | {_num(mean)} | ' + ' | '.join(cells) + ' |')
    lines += ['', '### Optimality', '',
              '| scenario | robot | straight line (m) | optimal (m) | ' +
              ' | '.join(f'{algorithm_name(a)} path / opt.' for a in algorithms) + ' |',
              '|---|---|---|---|' + '---|' * len(algorithms)]
    by_key = {(s.scenario, s.algorithm, s.robot): s for s in summaries}
    for scenario in scenarios:
        lines_for = straight_lengths(scenario)
        for robot, opt in optimal.get(scenario, {}).items():
            cells = []
            for a in algorithms:
                found = by_key.get((scenario, a, robot))
                cells.append(_num(found.mean['path_length'] / opt, 3) if found and opt else '-')
            lines.append(f'| {scenario} | {robot} | {lines_for[robot]:.2f} | {_num(opt)} | ' +
                         ' | '.join(cells) + ' |')
    return '\n'.join(lines) + '\n'


# ----------------------------------------------------------------------------------------- example paths

@dataclass(frozen=True)
class ExamplePaths:
    """One scenario's exact shortest paths and one run of each planner, for the paths figure."""

    source: str                              # the scenario as given (built-in name or YAML path)
    scenario: Scenario
    seed: int
    optimal: dict[str, OptimalPath | None]   # per robot (None: no path keeps the clearance)
    runs: dict[str, Run]                     # per algorithm but 'optimal', which is the exact path itself


def example_paths(scenarios: Sequence[str], algorithms: Sequence[str], seed: int = 0,
                  overrides: dict[str, float] | None = None) -> list[ExamplePaths]:
    """Per scenario: the exact optimal path of every robot and one run of every planner with the given seed
    (and the planner overrides of the batch, if any)."""
    from dataclasses import replace

    out = []
    for source in scenarios:
        scenario = cached_scenario(source)
        if overrides:
            scenario = replace(scenario, planner=scenario.planner.with_overrides(overrides))
        exact = {spec.name: shortest_path(scenario.world, spec.start[:2], spec.goal,
                                          spec.radius + scenario.planner.clearance_margin)
                 for spec in scenario.robots}
        runs = {a: simulate(scenario, a, seed) for a in algorithms if a != 'optimal' and drives_scenario(a, source)}
        out.append(ExamplePaths(source, scenario, seed, exact, runs))
    return out
