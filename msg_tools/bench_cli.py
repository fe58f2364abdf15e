"""fastep-bench: regenerate the paper's Table 2 (and optimality ratios) from many seeded in-process runs, or run
every planner on random world families.

    fastep-bench [--runs 30] [--scenarios table2_s1 table2_s2 table2_s3 | all] [--algorithms fastep aco optimal dwa]
                 [--workers 2 | --cluster ADDRESS|local:N] [--seed 0] [--out docs/] [--report table2] ...
    fastep-bench --families [FAMILY ...] [--worlds 30] [--runs 1] [--algorithms ...] [--seed 0] [--out DIR] ...

Writes OUT/REPORT.md (Markdown tables), OUT/figures/REPORT_*.png (drawn by msg_tools.plots) and, with --families,
OUT/REPORT.json (per-run rows and summaries); prints the Markdown on stdout. The engine is `experiments.batches`
(the command lives in msg_tools because fastep_core draws nothing); `python -m benchmarks.table2` is the same
command. --cluster runs the same tasks on a Dask cluster (fastep_core.experiments.cluster) with the same records.
Exit 0 when the runs were made, 2 with one line on stderr for bad input (a --cluster that is no Dask scheduler
among it). A batch on a cluster that can run no more (no worker left within the bound, experiments.cluster) ends
early: the same files with the runs done, a "Runs missing" section and a JSON "missing" list naming the others,
one line on stderr, exit 1. Options: docs/reference/commands.md.
"""

from __future__ import annotations

import argparse
import json
import math
import shlex
import sys
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from fastep_core.cli import MAX_RUNS, MAX_WORKERS, REALTIME_HELP, Parser, count, fail, guard, realtime_factor, seed
from fastep_core.experiments import batches, families
from fastep_core.experiments.cluster import CLUSTER_HELP, BatchIncomplete, cluster_spec
from fastep_core.experiments.random_worlds import ALL_FAMILIES, FAMILIES, FAMILY_SEED0
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.planning.params import PlannerParams
from fastep_core.scenario import builtin_names, load_scenario

__all__ = ['main']


def _parser(prog: str) -> argparse.ArgumentParser:
    p = Parser(prog=prog, description='Regenerate Table 2: FAStep-Kinematic vs ACO-Kinematic (vs the optimum); '
                                      'or run every planner on random world families (--families).')
    p.add_argument('--runs', type=count(MAX_RUNS),
                   help='seeded runs per scenario (default 30) or per family world (default 1) and planner')
    what = p.add_mutually_exclusive_group()
    what.add_argument('--scenarios', nargs='+', metavar='SCENARIO',
                      help='built-in names or YAML paths, or "all" for every built-in (default: Table 2)')
    what.add_argument('--families', nargs='*', choices=ALL_FAMILIES, metavar='FAMILY',
                      help=f'random world families among {", ".join(ALL_FAMILIES)} (none named: the static ones, '
                           f'{", ".join(FAMILIES)})')
    p.add_argument('--worlds', type=count(MAX_RUNS), help='worlds per family with --families (default 30)')
    p.add_argument('--worst-of', choices=ALGORITHMS, metavar='ALG',
                   help='with --families: the worst-world table and figure show where this planner\'s path / '
                        'optimum was worst (default: any planner but optimal)')
    p.add_argument('--algorithms', nargs='+', default=list(ALGORITHMS), choices=ALGORITHMS, metavar='ALG',
                   help=f'planners among {", ".join(ALGORITHMS)} (default: all; optimal runs once; dwa skips '
                   'scenarios with a tractor-trailer)')
    p.add_argument('--planner-set', nargs='+', default=[], type=_override, metavar='NAME=VALUE',
                   help='planner parameter overrides for every planner, e.g. stuck_steps=1 plan_horizon=2')
    engine = p.add_mutually_exclusive_group()
    engine.add_argument('--workers', type=count(MAX_WORKERS), help='worker processes (default 2)')
    engine.add_argument('--cluster', type=cluster_spec, metavar='ADDRESS|local:N', help=CLUSTER_HELP)
    p.add_argument('--realtime', type=realtime_factor, nargs='?', const=1.0, default=None, metavar='FACTOR',
                   help=REALTIME_HELP)
    p.add_argument('--seed', type=seed, default=0, help='first run seed (default 0)')
    p.add_argument('--out', type=Path, default=Path('docs'), help='output folder (default docs/)')
    p.add_argument('--report', help='report name: OUT/REPORT.md, figures/REPORT_*.png (default table2, or '
                                    'families with --families)')
    p.add_argument('--json', type=Path, metavar='FILE',
                   help='also write every run record as JSON (--families: instead of OUT/REPORT.json)')
    p.add_argument('--no-figures', action='store_true', help='skip the PNG figures')
    p.add_argument('--progress', action='store_true',
                   help='show the progress bar on stderr even when it is not a terminal (e.g. a log file)')
    return p


def _override(text: str) -> tuple[str, float]:
    """argparse type of NAME=VALUE: a planner parameter and a number (checked against PlannerParams later)."""
    name, equals, value = text.partition('=')
    if not equals or not name:
        raise argparse.ArgumentTypeError(f'expected NAME=VALUE, got {text!r}')
    try:
        number = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{name}: expected a number, got {value!r}') from None
    if not math.isfinite(number):
        raise argparse.ArgumentTypeError(f'{name}: expected a finite number, got {value!r}')
    return name, number


def main(argv: Sequence[str] | None = None, prog: str = 'fastep-bench') -> int:
    return guard(prog, lambda: _run(argv, prog))


def _run(argv: Sequence[str] | None, prog: str) -> int:
    parser = _parser(prog)
    args = parser.parse_args(argv)
    report_name = args.report if args.report is not None else 'table2' if args.families is None else 'families'
    if not report_name or '/' in report_name:
        parser.error(f'--report must be a plain file name, got {report_name!r}')
    for flag in ('worlds', 'worst_of'):
        if getattr(args, flag) is not None and args.families is None:
            parser.error(f'--{flag.replace("_", "-")} needs --families')
    if args.worst_of is not None and args.worst_of not in args.algorithms:
        parser.error(f'--worst-of {args.worst_of} is not among --algorithms')
    overrides = dict(args.planner_set)
    PlannerParams().with_overrides(overrides)   # an unknown name or a bad value: one line before any run starts
    command = ' '.join([prog, *map(shlex.quote, sys.argv[1:] if argv is None else argv)])
    if args.workers is None and args.cluster is None:
        args.workers = 2
    if args.families is not None:
        return _run_families(args, prog, report_name, overrides, command)
    scenarios = list(batches.TABLE2) if args.scenarios is None else \
        builtin_names() if args.scenarios == ['all'] else list(dict.fromkeys(args.scenarios))
    for name in scenarios:  # a bad one is a FastepError: one line before any run starts
        load_scenario(name)
    records, lost = _batch(lambda: batches.run_batch(
        scenarios, args.algorithms, args.runs or 30, args.workers or 2, seed0=args.seed,
        progress=True if args.progress else None, label=prog, overrides=overrides,
        realtime=args.realtime, cluster=args.cluster))
    optimal = {s: batches.optimal_lengths(s) for s in scenarios}
    title = 'Table 2 regenerated' if scenarios == list(batches.TABLE2) else \
        'FAStep-Kinematic, ACO-Kinematic and the optimum'
    text = batches.markdown_report(records, optimal, title=title, command=command) + _missing_section(lost)
    try:
        args.out.mkdir(parents=True, exist_ok=True)
        report = args.out / f'{report_name}.md'
        report.write_text(text)
        written = [report]
        if not args.no_figures and records:
            from msg_tools.plots import bench_figures  # matplotlib only when figures are drawn
            written += bench_figures(records, optimal, args.out / 'figures', prefix=report_name)
        if args.json is not None:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({'records': [r.to_json() for r in records], 'optimal': optimal,
                                             **_missing_json(lost)}) + '\n')
            written.append(args.json)
    except OSError as exc:
        return fail(prog, f'cannot write output: {exc}')
    print(text)
    for path in written:
        print(f'wrote {path}')
    return _ended(prog, lost)


def _batch(run: Callable[[], list[batches.Record]]) -> tuple[list[batches.Record], BatchIncomplete | None]:
    """run()'s records, or those a batch that ended early made and why it ended."""
    try:
        return run(), None
    except BatchIncomplete as lost:
        return lost.done, lost


def _seed_ranges(seeds: list[int]) -> str:
    """'0-3, 7, 9-10': sorted seeds, runs of consecutive ones as ranges."""
    ordered = np.unique(np.asarray(seeds, dtype=np.int64))
    chunks = np.split(ordered, np.flatnonzero(np.diff(ordered) != 1) + 1)
    return ', '.join(f'{c[0]}' if len(c) == 1 else f'{c[0]}-{c[-1]}' for c in chunks)


def _missing_section(lost: BatchIncomplete | None) -> str:
    """The report's 'Runs missing' section of a batch that ended early ('' for a whole batch)."""
    if lost is None:
        return ''
    seeds: dict[tuple[str, str], list[int]] = {}
    for source, algorithm, seed_ in lost.missing:
        seeds.setdefault((source, algorithm), []).append(seed_)
    which = '; '.join(f'{source} {algorithm} seeds {_seed_ranges(s)}' for (source, algorithm), s in seeds.items())
    return (f'\n\n### Runs missing\n\nThe batch ended early ({lost.reason}): {len(lost.missing)} of {lost.total} '
            f'runs did not finish and are in no table above: {which}.\n')


def _missing_json(lost: BatchIncomplete | None) -> dict[str, object]:
    """The JSON's 'missing' runs of a batch that ended early (nothing for a whole batch)."""
    if lost is None:
        return {}
    return {'missing': [{'scenario': s, 'algorithm': a, 'seed': seed_} for s, a, seed_ in lost.missing],
            'ended_early': lost.reason}


def _ended(prog: str, lost: BatchIncomplete | None) -> int:
    """0 after a whole batch; after one that ended early, its one line on stderr and 1."""
    if lost is None:
        return 0
    print(f'{prog}: error: {lost} (the runs done are written)', file=sys.stderr)
    return 1


def _run_families(args: argparse.Namespace, prog: str, report_name: str, overrides: dict[str, float],
                  command: str) -> int:
    """--families: the family table, its JSON and figures (fastep_core.experiments.families)."""
    chosen = list(dict.fromkeys(args.families)) or list(FAMILIES)
    worlds, runs = args.worlds or 30, args.runs or 1
    load_before, wall = families.load_average(), time.perf_counter()
    records, lost = _batch(lambda: families.run_families(
        chosen, args.algorithms, worlds, runs, args.workers or 2, seed0=args.seed,
        progress=True if args.progress else None, label=prog, overrides=overrides,
        realtime=args.realtime, cluster=args.cluster))
    rows = families.rows_of(records)
    wall = time.perf_counter() - wall
    load_after = families.load_average()
    where = f'with {args.workers} worker(s)' if args.cluster is None else f'on the Dask cluster {args.cluster}'
    run_cpu = sum({(r.scenario, r.algorithm, r.seed): r.cpu_time for r in records}.values())
    notes = [f'Worlds per family: {worlds} (seeds {FAMILY_SEED0}-{FAMILY_SEED0 + worlds - 1}); '
             f'runs per world: {runs} (seeds {args.seed}-{args.seed + runs - 1}; deterministic planners once). '
             f'Wall time {wall:.0f} s {where}, CPU in the runs {run_cpu:.0f} s; load average '
             f'(1 min) {load_before:.2f} at the start, {load_after:.2f} at the end.' +
             (f' Planner overrides: {", ".join(f"{k}={v:g}" for k, v in overrides.items())}.' if overrides else '') +
             ('' if args.realtime is None else f' Realtime x{args.realtime:g}: planning latency counted '
              '(fastep-sim --realtime), so runs differ from machine to machine.')]
    text = families.markdown_report(rows, command=command, notes=notes, worst_of=args.worst_of) + \
        _missing_section(lost)
    summary = families.summarise(rows)
    try:
        args.out.mkdir(parents=True, exist_ok=True)
        report = args.out / f'{report_name}.md'
        report.write_text(text)
        out_json = args.json if args.json is not None else args.out / f'{report_name}.json'
        out_json.parent.mkdir(parents=True, exist_ok=True)
        out_json.write_text(json.dumps({
            'command': command, 'families': chosen, 'worlds': worlds, 'runs': runs, 'algorithms': args.algorithms,
            'overrides': overrides, 'workers': args.workers, 'cluster': args.cluster and str(args.cluster),
            'realtime': args.realtime, 'wall_time': wall, 'load_average': [load_before, load_after],
            'summary': [s.to_json() for s in summary], 'rows': [r.to_json() for r in rows], **_missing_json(lost)},
            indent=1) + '\n')
        written = [report, out_json]
        if not args.no_figures and rows:
            from msg_tools.plots import family_figures  # matplotlib only when figures are drawn
            written += family_figures(rows, args.out / 'figures', prefix=report_name, overrides=overrides,
                                      worst_of=args.worst_of)
    except OSError as exc:
        return fail(prog, f'cannot write output: {exc}')
    print(text)
    for path in written:
        print(f'wrote {path}')
    return _ended(prog, lost)


if __name__ == '__main__':
    sys.exit(main())
