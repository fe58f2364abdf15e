"""fastep-bench: regenerate the paper's Table 2 (and optimality ratios) from many seeded in-process runs.

    fastep-bench [--runs 30] [--scenarios table2_s1 table2_s2 table2_s3 | all] [--algorithms fastep aco optimal dwa]
                 [--workers 2] [--seed 0] [--out docs/] [--report table2] [--json FILE] [--no-figures]
                 [--progress]

Writes OUT/REPORT.md (the Markdown tables) and OUT/figures/REPORT_{path_length,compute_time,paths}.png (box
plots and example paths, drawn by msg_tools.plots), prints the Markdown on stdout and a progress bar on stderr
(when stderr is a terminal, or with --progress). The engine is `fastep_core.experiments` (why this command
lives in msg_tools: fastep_core draws nothing); `python -m benchmarks.table2` is the same command. Exit 0 when
the runs were made, 2 with one line on stderr for bad input.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path
from typing import Sequence

from fastep_core import experiments
from fastep_core.cli import Parser, fail, guard, positive_int, seed
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.scenario import builtin_names, load_scenario

__all__ = ['main']


def _parser(prog: str) -> argparse.ArgumentParser:
    p = Parser(prog=prog, description='Regenerate Table 2: FAStep-Kinematic vs ACO-Kinematic (vs the optimum).')
    p.add_argument('--runs', type=positive_int, default=30, help='seeded runs per scenario and planner (default 30)')
    p.add_argument('--scenarios', nargs='+', default=list(experiments.TABLE2), metavar='SCENARIO',
                   help='built-in names or YAML paths, or "all" for every built-in (default: Table 2)')
    p.add_argument('--algorithms', nargs='+', default=list(ALGORITHMS), choices=ALGORITHMS, metavar='ALG',
                   help=f'planners among {", ".join(ALGORITHMS)} (default: all; optimal runs once; dwa skips '
                   'scenarios with a tractor-trailer)')
    p.add_argument('--workers', type=positive_int, default=2, help='worker processes (default 2)')
    p.add_argument('--seed', type=seed, default=0, help='first seed (default 0)')
    p.add_argument('--out', type=Path, default=Path('docs'), help='output folder (default docs/)')
    p.add_argument('--report', default='table2', help='report name: OUT/REPORT.md, figures/REPORT_*.png')
    p.add_argument('--json', type=Path, metavar='FILE', help='also write every run record as JSON')
    p.add_argument('--no-figures', action='store_true', help='skip the PNG figures')
    p.add_argument('--progress', action='store_true',
                   help='show the progress bar on stderr even when it is not a terminal (e.g. a log file)')
    return p


def main(argv: Sequence[str] | None = None, prog: str = 'fastep-bench') -> int:
    return guard(prog, lambda: _run(argv, prog))


def _run(argv: Sequence[str] | None, prog: str) -> int:
    parser = _parser(prog)
    args = parser.parse_args(argv)
    if not args.report or '/' in args.report:
        parser.error(f'--report must be a plain file name, got {args.report!r}')
    scenarios = builtin_names() if args.scenarios == ['all'] else list(dict.fromkeys(args.scenarios))
    for name in scenarios:  # a bad one is a FastepError: one line before any run starts
        load_scenario(name)
    records = experiments.run_batch(scenarios, args.algorithms, args.runs, args.workers, seed0=args.seed,
                                    progress=True if args.progress else None, label=prog)
    optimal = {s: experiments.optimal_lengths(s) for s in scenarios}
    command = ' '.join([prog, *map(shlex.quote, sys.argv[1:] if argv is None else argv)])
    title = 'Table 2 regenerated' if scenarios == list(experiments.TABLE2) else \
        'FAStep-Kinematic, ACO-Kinematic and the optimum'
    text = experiments.markdown_report(records, optimal, title=title, command=command)
    try:
        args.out.mkdir(parents=True, exist_ok=True)
        report = args.out / f'{args.report}.md'
        report.write_text(text)
        written = [report]
        if not args.no_figures:
            from msg_tools.plots import bench_figures  # matplotlib only when figures are drawn
            written += bench_figures(records, optimal, args.out / 'figures', prefix=args.report)
        if args.json is not None:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({'records': [r.to_json() for r in records], 'optimal': optimal}) + '\n')
            written.append(args.json)
    except OSError as exc:
        return fail(prog, f'cannot write output: {exc}')
    print(text)
    for path in written:
        print(f'wrote {path}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
