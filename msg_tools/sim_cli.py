"""fastep-sim: run a scenario in-process (no ROS) and report what every robot did.

    fastep-sim SCENARIO [--algorithm fastep|aco|optimal|dwa] [--seed N] [--runs K] [--json OUT] [--plot OUT.png]
               [--mcap OUT.mcap]
    fastep-sim --list

Exit 0 when the runs were simulated (arrived or not), 2 with one line on stderr for bad input.

Runs are reported as they finish: each run's summary is printed and its JSON appended to --json as soon as it
ends, the figure (--plot) and recording (--mcap) of the first run are written as soon as it ends, and no run
is kept after that, so memory does not grow with --runs. Ctrl-C (or SIGTERM) stops the batch: the JSON file is
closed as a valid document holding every finished run, and the command exits 130 (143 on SIGTERM).

Why here and not in fastep_core: the simulation is fastep_core's, but --plot draws with msg_tools.plots and
--mcap records ROS messages with msg_tools.sim_mcap, and fastep_core imports nothing above itself.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import IO, TYPE_CHECKING, Callable, Iterator, Sequence

from fastep_core.cli import INTERRUPTED, MAX_RUNS, REALTIME_HELP, Parser, count, fail, guard, realtime_factor, seed
from fastep_core.dynamic_world import dynamic_feature
from fastep_core.planning.algorithms import ALGORITHMS
from fastep_core.scenario import Scenario, builtin_names, load_scenario
from fastep_core.simulator import Run, Tick, simulate

if TYPE_CHECKING:
    from msg_tools.sim_mcap import SimRecorder

__all__ = ['main']

PROG = 'fastep-sim'
FIGURE_SUFFIXES = ('.png', '.pdf', '.svg')
"""What --plot writes, chosen by the file's suffix (matplotlib draws each; others are refused up front)."""


def _figure_path(text: str) -> Path:
    """argparse type of --plot: a file whose suffix names a format, so the file written is the one named."""
    path = Path(text)
    if path.suffix.lower() not in FIGURE_SUFFIXES:
        raise argparse.ArgumentTypeError(f'the figure file must end in {", ".join(FIGURE_SUFFIXES)} (its format), '
                                         f'got {text!r}')
    return path


def _parser() -> argparse.ArgumentParser:
    p = Parser(prog=PROG, description='Simulate a scenario with FAStep-Kinematic or ACO-Kinematic.')
    p.add_argument('scenario', nargs='?', help='scenario YAML file or built-in name (see --list)')
    p.add_argument('--algorithm', choices=ALGORITHMS, default='fastep', help='planner (default: fastep)')
    p.add_argument('--seed', type=seed, default=0, help='seed of the first run (default: 0)')
    p.add_argument('--runs', type=count(MAX_RUNS), default=1,
                   help='number of runs, seeds seed..seed+runs-1 (default: 1)')
    p.add_argument('--json', type=Path, metavar='OUT', help='write all runs as JSON')
    p.add_argument('--plot', type=_figure_path, metavar='OUT.png',
                   help='draw the first run like the paper\'s Fig. 2 (.png, .pdf or .svg)')
    p.add_argument('--mcap', type=Path, metavar='OUT.mcap',
                   help='record the first run as MCAP with the topics of a live run (msg_tools.sim_mcap)')
    p.add_argument('--realtime', type=realtime_factor, nargs='?', const=1.0, default=None, metavar='FACTOR',
                   help=REALTIME_HELP)
    p.add_argument('--list', action='store_true', help='list built-in scenarios and exit')
    return p


def _summary(run: Run) -> str:
    lines = []
    for r in run.robots:
        state = 'arrived' if r.reached else 'NOT arrived'
        when = f'{r.sim_time:.1f} s' if r.sim_time is not None else '-'
        lines.append(f'seed {run.seed} {r.name}: {state}{" COLLIDED" if r.collided else ""}, '
                     f'path {r.path_length:.2f} m, time {when}, compute {r.compute_time * 1e3:.0f} ms, '
                     f'min clearance {r.min_clearance:.2f} m, activations {r.activations} ({r.status})'
                     + ('' if r.realtime is None else f'; realtime x{r.realtime.factor:g}: '
                        f'{r.realtime.stale_ticks} of {r.realtime.ticks} ticks without a fresh plan, '
                        f'longest planning latency {r.realtime.max_latency * 1e3:.0f} ms'))
    return '\n'.join(lines)


class _JsonRuns:
    """--json written as runs finish: the document's head at once, each run as it ends, the tail when the batch
    stops. The bytes are those of json.dumps of the whole document, and a stopped batch leaves a valid one."""

    def __init__(self, path: Path, scenario: str, algorithm: str) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        self.path = path
        self.file: IO[str] = path.open('w')
        head = json.dumps({'scenario': scenario, 'algorithm': algorithm, 'runs': []})
        self.file.write(head[:-len('[]}')] + '[')
        self.count = 0

    def add(self, run: Run) -> None:
        self.file.write((', ' if self.count else '') + json.dumps(run.to_json()))   # one write: whole or nothing
        self.file.flush()
        self.count += 1

    def close(self) -> None:
        """End the document (once); a write error is the caller's, the file is closed either way."""
        if self.file.closed:
            return
        try:
            self.file.write(']}\n')
        finally:
            self.file.close()


class _Stop(KeyboardInterrupt):
    """A stop asked for by a signal, raised at a safe point of the batch (a KeyboardInterrupt, so no
    `except Exception` in the simulation takes it for a fault)."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


class _StopSignals:
    """While the batch runs, Ctrl-C and SIGTERM only note the signal; the batch stops at its next simulated step
    or between runs. Python's own Ctrl-C raised KeyboardInterrupt wherever the main thread was, also inside a
    destructor or a generator's clean-up, where Python prints "Exception ignored" and runs on: a batch of a
    million runs then never stopped."""

    def __init__(self) -> None:
        self.signum: int | None = None

    def check(self, *_: object) -> None:
        """Raise the stop if one was asked for (also usable as a simulation observer)."""
        if self.signum is not None:
            raise _Stop(self.signum)

    def _note(self, signum: int, frame: FrameType | None) -> None:
        if self.signum is not None:   # asked twice (one step can take long, e.g. an exact path): stop now
            raise _Stop(signum)
        self.signum = signum

    @contextmanager
    def installed(self) -> Iterator[_StopSignals]:
        """Signal handlers exist in the main thread only; elsewhere (a caller's thread) Ctrl-C acts as usual."""
        if threading.current_thread() is not threading.main_thread():
            yield self
            return
        # A signal ignored from the start stays ignored (`fastep-sim ... &` in a script: Ctrl-C is not for it).
        previous = {sig: signal.signal(sig, self._note) for sig in (signal.SIGINT, signal.SIGTERM)
                    if signal.getsignal(sig) is not signal.SIG_IGN}
        try:
            yield self
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)


def main(argv: Sequence[str] | None = None) -> int:
    return guard(PROG, lambda: _run(argv))


def _run(argv: Sequence[str] | None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if args.list:
        print('\n'.join(builtin_names()))
        return 0
    if args.scenario is None:
        parser.error('a SCENARIO is required (a YAML file or one of: ' + ', '.join(builtin_names()) + ')')
    # A FastepError from here on (a bad scenario; RecordingError: the MCAP file cannot be written) is guard's
    # one line and exit 2.
    scenario = load_scenario(args.scenario)
    recorder = None
    if args.mcap is not None and dynamic_feature(scenario.obstacle_specs):
        return fail(PROG, f'--mcap: {dynamic_feature(scenario.obstacle_specs)}: fastep-sim does not write '
                          'recordings of moving, unknown and misplaced obstacles yet (fastep-launch --record does)')
    if args.mcap is not None:
        try:  # the ROS message packages only when a recording is asked for
            from msg_tools.sim_mcap import SimRecorder
        except ImportError as exc:
            return fail(PROG, f'--mcap needs the ROS 2 message packages: {exc}')
        recorder = SimRecorder(scenario, args.algorithm, args.seed)
    try:
        json_runs = _JsonRuns(args.json, scenario.name, args.algorithm) if args.json is not None else None
    except OSError as exc:
        return fail(PROG, f'cannot write output: {exc}')
    done, stop = 0, None
    try:
        try:
            with _StopSignals().installed() as stops:
                for run_seed in range(args.seed, args.seed + args.runs):
                    stops.check()
                    run = simulate(scenario, args.algorithm, run_seed,
                                   observer=_observing(recorder if run_seed == args.seed else None, stops),
                                   realtime=args.realtime)
                    if json_runs is not None:
                        json_runs.add(run)   # before the summary: a run printed is a run in the file
                    print(_summary(run), flush=True)
                    done += 1
                    if run_seed == args.seed:
                        _write_first_run(args, scenario, run, recorder)
                        recorder = None   # its messages too
                    del run   # no run is kept: memory does not grow with --runs
        except KeyboardInterrupt as exc:   # Ctrl-C or SIGTERM (_Stop), or Ctrl-C outside the main thread
            stop = exc
        finally:
            if json_runs is not None:
                json_runs.close()
        if json_runs is not None:
            print(f'wrote {json_runs.path}')
    except OSError as exc:
        return fail(PROG, f'cannot write output: {exc}')
    if stop is None:
        return 0
    terminated = isinstance(stop, _Stop) and stop.signum == signal.SIGTERM
    what = 'stopped by SIGTERM' if terminated else 'interrupted'
    print(f'{PROG}: {what} after {done} of {args.runs} runs; what finished is written', file=sys.stderr)
    return 128 + signal.SIGTERM if terminated else INTERRUPTED


def _observing(recorder: SimRecorder | None, stops: _StopSignals) -> Callable[[Tick], None]:
    """The simulation's observer: the stop check at every step, and the recorder for the run it records."""
    if recorder is None:
        return stops.check

    def observe(tick: Tick) -> None:
        stops.check()
        recorder.observe(tick)
    return observe


def _write_first_run(args: argparse.Namespace, scenario: Scenario, first: Run, recorder: SimRecorder | None) -> None:
    """The figure and the recording of the first run, as soon as it has finished (a bad path fails here, not
    after the whole batch; a batch stopped later keeps them)."""
    if args.plot is not None:
        from msg_tools.plots import plot_paths  # matplotlib only when a figure is asked for
        args.plot.parent.mkdir(parents=True, exist_ok=True)
        print(f'wrote {plot_paths(scenario, first, args.plot)}')
    if recorder is not None:
        recorder.finish(first)
        args.mcap.parent.mkdir(parents=True, exist_ok=True)
        count = recorder.write(args.mcap)
        print(f'wrote {args.mcap} ({count} messages of the run with seed {args.seed})')


if __name__ == '__main__':
    sys.exit(main())
