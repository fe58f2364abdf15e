"""fastep-sim: run a scenario in-process (no ROS) and report what every robot did.

    fastep-sim SCENARIO [--algorithm fastep|aco] [--seed N] [--runs K] [--json OUT] [--plot OUT.png]
               [--mcap OUT.mcap]
    fastep-sim --list

Exit 0 when the runs were simulated (arrived or not), 2 with one line on stderr for bad input.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import NoReturn, Sequence

from fastep_core.errors import FastepError
from fastep_core.scenario import builtin_names, load_scenario
from fastep_core.simulator import ALGORITHMS, Run, simulate

__all__ = ['main']


class _Parser(argparse.ArgumentParser):
    """argparse, but bad flags give one line on stderr (and exit 2) instead of usage + error."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f'{self.prog}: error: {message} (see --help)\n')


def seed(text: str) -> int:
    """argparse type of a seed: a whole number >= 0 (numpy's SeedSequence takes no negative seeds)."""
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f'a seed must be >= 0, got {value}')
    return value


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog='fastep-sim', description='Simulate a scenario with FAStep-Kinematic or ACO-Kinematic.')
    p.add_argument('scenario', nargs='?', help='scenario YAML file or built-in name (see --list)')
    p.add_argument('--algorithm', choices=ALGORITHMS, default='fastep', help='planner (default: fastep)')
    p.add_argument('--seed', type=seed, default=0, help='seed of the first run (default: 0)')
    p.add_argument('--runs', type=int, default=1, help='number of runs, seeds seed..seed+runs-1 (default: 1)')
    p.add_argument('--json', type=Path, metavar='OUT', help='write all runs as JSON')
    p.add_argument('--plot', type=Path, metavar='OUT.png', help='draw the first run like the paper\'s Fig. 2')
    p.add_argument('--mcap', type=Path, metavar='OUT.mcap',
                   help='record the first run as MCAP with the topics of a live run (msg_tools.sim_mcap)')
    p.add_argument('--list', action='store_true', help='list built-in scenarios and exit')
    return p


def _summary(run: Run) -> str:
    lines = []
    for r in run.robots:
        state = 'arrived' if r.reached else 'NOT arrived'
        when = f'{r.sim_time:.1f} s' if r.sim_time is not None else '-'
        lines.append(f'seed {run.seed} {r.name}: {state}{" COLLIDED" if r.collided else ""}, '
                     f'path {r.path_length:.2f} m, time {when}, compute {r.compute_time * 1e3:.0f} ms, '
                     f'min clearance {r.min_clearance:.2f} m, activations {r.activations} ({r.status})')
    return '\n'.join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    try:
        return _run(argv)
    except KeyboardInterrupt:
        print('fastep-sim: interrupted', file=sys.stderr)
        return 130
    except BrokenPipeError:
        # The reader went away (e.g. `| head`): stop quietly, without a second error at interpreter exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def _run(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.list:
        print('\n'.join(builtin_names()))
        return 0
    if args.scenario is None:
        parser.error('a SCENARIO is required (a YAML file or one of: ' + ', '.join(builtin_names()) + ')')
    if args.runs < 1:
        parser.error(f'--runs must be at least 1, got {args.runs}')
    try:
        scenario = load_scenario(args.scenario)
    except FastepError as exc:
        print(f'fastep-sim: error: {exc}', file=sys.stderr)
        return 2
    recorder = None
    if args.mcap is not None:
        try:  # the ROS message packages only when a recording is asked for
            from msg_tools.sim_mcap import SimRecorder
        except ImportError as exc:
            print(f'fastep-sim: error: --mcap needs the ROS 2 message packages: {exc}', file=sys.stderr)
            return 2
        recorder = SimRecorder(scenario, args.algorithm, args.seed)
    runs = [simulate(scenario, args.algorithm, seed,
                     observer=recorder.observe if recorder is not None and seed == args.seed else None)
            for seed in range(args.seed, args.seed + args.runs)]
    for run in runs:
        print(_summary(run))
    try:
        if args.json is not None:
            doc = {'scenario': scenario.name, 'algorithm': args.algorithm, 'runs': [r.to_json() for r in runs]}
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps(doc) + '\n')
            print(f'wrote {args.json}')
        if args.plot is not None:
            from msg_tools.plots import plot_paths  # matplotlib only when a figure is asked for
            args.plot.parent.mkdir(parents=True, exist_ok=True)
            plot_paths(scenario, runs[0], args.plot)
            print(f'wrote {args.plot}')
        if recorder is not None:
            recorder.finish(runs[0])
            args.mcap.parent.mkdir(parents=True, exist_ok=True)
            count = recorder.write(args.mcap)
            print(f'wrote {args.mcap} ({count} messages of the run with seed {args.seed})')
    except OSError as exc:
        print(f'fastep-sim: error: cannot write output: {exc}', file=sys.stderr)
        return 2
    except FastepError as exc:  # msg_tools.errors.RecordingError: e.g. the MCAP file cannot be created
        print(f'fastep-sim: error: {exc}', file=sys.stderr)
        return 2
    return 0


if __name__ == '__main__':
    sys.exit(main())
