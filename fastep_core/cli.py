"""What every fastep command line shares: one-line errors with exit code 2, the main() guard, argparse types.

The contract of every console script (fastep-sim, fastep-bench, fastep-tune, fastep-report, fastep-recover,
fastep-replay, fastep-launch) and of the ROS nodes: bad input gives ONE line `PROG: error: ...` on stderr and
exit code 2, never a traceback or a usage block; Ctrl-C gives one line and 130; a reader that goes away
(`| head`) ends the command quietly. `Parser` does it for the flags, `guard` for everything after them.
Long batches show a `progress_bar` (tqdm) on stderr, so stdout stays the result.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from typing import TYPE_CHECKING, Any, Callable, NoReturn

from fastep_core.errors import FastepError

if TYPE_CHECKING:
    from tqdm import tqdm

__all__ = ['MAX_ITERATIONS', 'MAX_POPSIZE', 'MAX_RUNS', 'MAX_WORKERS', 'Parser', 'count', 'guard', 'fail', 'seed',
           'positive_int', 'progress_bar', 'tcp_port', 'tcp_port_problem']

INTERRUPTED = 130
"""Exit code after Ctrl-C: 128 + SIGINT, as a shell reports it."""


class Parser(argparse.ArgumentParser):
    """argparse, but bad flags give one line on stderr (and exit 2) instead of usage + error."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f'{self.prog}: error: {message} (see --help)\n')


def fail(prog: str, message: object) -> int:
    """Print `PROG: error: MESSAGE` on stderr; return 2, the exit code of bad input."""
    print(f'{prog}: error: {message}', file=sys.stderr)
    return 2


def guard(prog: str, body: Callable[[], int]) -> int:
    """Run a command's body and return its exit code, turning what a user can cause into one line.

    FastepError: its message, exit 2. Ctrl-C: `PROG: interrupted`, exit 130. BrokenPipeError (the reader of
    stdout went away): exit 1 without a word, and without Python's second complaint when it flushes stdout
    at exit.
    """
    try:
        return body()
    except FastepError as exc:
        return fail(prog, exc)
    except KeyboardInterrupt:
        print(f'{prog}: interrupted', file=sys.stderr)
        return INTERRUPTED
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def seed(text: str) -> int:
    """argparse type of a seed: a whole number >= 0 (numpy's SeedSequence takes no negative seeds)."""
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f'a seed must be >= 0, got {value}')
    return value


def positive_int(text: str) -> int:
    """argparse type of a count (runs, workers, seeds, population): a whole number >= 1."""
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f'must be at least 1, got {value}')
    return value


MAX_RUNS = 100_000
"""Runs (or worlds) one command line may ask for: more is a typo, or an attack, that fills the memory with tasks
before a first result (fastep-bench --runs 3000000: 1.8 GB in a minute)."""
MAX_WORKERS = 256
MAX_POPSIZE = 1_000   # DE population multiplier (x 4 x the dimensions: 99999999999 wanted 11.6 TiB)
MAX_ITERATIONS = 10_000


def count(limit: int) -> Callable[[str], int]:
    """argparse type of a count from 1 to `limit` (runs, worlds, workers, seeds, a population): one line otherwise."""
    def parse(text: str) -> int:
        value = positive_int(text)
        if value > limit:
            raise argparse.ArgumentTypeError(f'must be at most {limit}, got {text}')
        return value
    parse.__name__ = 'count'
    return parse


def realtime_factor(text: str) -> float:
    """argparse type of --realtime's FACTOR: how many times slower than this machine the robot's computer plans
    (a finite number >= 0; 0 counts no planning time, yet every plan still reaches the control loop a tick late)."""
    value = float(text)
    if not (math.isfinite(value) and 0.0 <= value <= 1000.0):
        raise argparse.ArgumentTypeError(f'a realtime factor must be in [0, 1000], got {text}')
    return value


REALTIME_HELP = ('planning takes time: a plan reaches the control loop only after the wall time it took x FACTOR '
                 '(default 1), the robot driving on its last plan meanwhile, as on a robot; not deterministic')


def tcp_port(text: str) -> int:
    """argparse type of a TCP port to listen on: a whole number in [1, 65535]."""
    value = int(text)
    if not 1 <= value <= 65535:
        raise argparse.ArgumentTypeError(f'a port must be in [1, 65535], got {value}')
    return value


def tcp_port_problem(port: int, host: str = '127.0.0.1') -> str:
    """Why a server could not listen on host:port ('' if it can): tried, then released at once."""
    import socket
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((host, port))
        except OSError as exc:
            return f'cannot listen on {host}:{port}: {exc.strerror or exc}'
    return ''


def progress_bar(total: int, label: str, show: bool | None = None, unit: str = 'run') -> tqdm[Any]:
    """A tqdm progress bar on stderr; update(n) it as work ends, close() it (or use it as a context manager).

    show: None draws it only when stderr is a terminal (a log file gets no carriage-return clutter), True
    always (asked for, e.g. to follow a long batch in a log), False never.
    """
    from tqdm import tqdm  # here, not at the top: 0.1 s of import that no node and no short command needs
    return tqdm(total=total, desc=label, unit=unit, file=sys.stderr, disable=None if show is None else not show,
                dynamic_ncols=True)
