"""fastep-launch's progress on a terminal: robots arrived of all, simulated time, achieved real-time factor.

On a terminal (the stream is a TTY) one tqdm bar is redrawn in place at most every `refresh` wall seconds:

    arrived 3/16 |█████     |, simulated 42.0 s, 6.3x real time, 1 failed

Anywhere else (a log file, a pipe, CI) a plain line every `every` wall seconds and one at the end, so a log
shows that the run goes on without carriage-return clutter:

    fastep-launch: 3/16 arrived, simulated 42.0 s, 6.3x real time, 1 failed

The real-time factor is simulated seconds over wall seconds since the clock started (Progress.start); with
--no-clock the simulated time is wall time and the factor 1. fastep-launch --no-progress turns both off.
No ROS here: the launcher calls update() from its monitoring loop.
"""

from __future__ import annotations

import sys
import time
from typing import IO, Any, Callable

__all__ = ['LINE_PERIOD', 'Progress', 'REFRESH_PERIOD']

LINE_PERIOD = 10.0      # wall seconds between plain lines when the stream is not a terminal
REFRESH_PERIOD = 0.25   # wall seconds between redraws of the bar on a terminal


class Progress:
    """Shows a run's progress on `stream` (stderr by default): a tqdm bar on a TTY, plain lines otherwise."""

    def __init__(self, prog: str, total: int, stream: IO[str] | None = None, *, enabled: bool = True,
                 every: float = LINE_PERIOD, refresh: float = REFRESH_PERIOD,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.prog = prog
        self.total = total
        self.stream = sys.stderr if stream is None else stream
        self.every = every
        self.clock = clock
        self.enabled = enabled
        isatty = getattr(self.stream, 'isatty', None)
        self.tty = bool(enabled and isatty is not None and isatty())
        self.bar: Any = None
        if self.tty:
            from tqdm import tqdm  # here: 0.1 s of import a run without a terminal does not need
            # (tqdm puts ', ' before the postfix itself)
            self.bar = tqdm(total=total, desc='arrived', unit='robot', file=self.stream, dynamic_ncols=True,
                            mininterval=refresh, bar_format='{desc} {n_fmt}/{total_fmt} |{bar}|{postfix}')
        self.started: float | None = None   # wall time the clock started
        self.last_line = -float('inf')
        self.state = (0, 0, 0.0)              # arrived, failed, simulated seconds
        self.closed = False

    def start(self) -> None:
        """The clock starts now: the real-time factor counts from here."""
        self.started = self.clock()
        self.last_line = self.started

    def text(self) -> str:
        """'3/16 arrived, simulated 42.0 s, 6.3x real time[, 1 failed]' of the newest update."""
        return f'{self.state[0]}/{self.total} arrived, {self._details()}'

    def _details(self) -> str:
        _, failed, sim = self.state
        wall = self.clock() - self.started if self.started is not None else 0.0
        rtf = f'{sim / wall:.1f}x real time' if wall > 0.0 else 'real time factor -'
        return f'simulated {sim:.1f} s, {rtf}' + (f', {failed} failed' if failed else '')

    def update(self, arrived: int, failed: int, sim_time: float) -> None:
        """The newest counts (robots arrived, robots failed or timed out) and simulated seconds since the start."""
        if not self.enabled or self.closed:
            return
        self.state = (arrived, failed, sim_time)
        if self.bar is not None:
            self.bar.n = arrived
            self.bar.set_postfix_str(self._details(), refresh=False)
            self.bar.update(0)   # redraws when mininterval has passed
        elif self.clock() - self.last_line >= self.every:
            self._line()

    def _line(self) -> None:
        self.last_line = self.clock()
        print(f'{self.prog}: {self.text()}', file=self.stream, flush=True)

    def close(self) -> None:
        """The final state: the bar drawn once more and left on its line, or one last plain line."""
        if not self.enabled or self.closed:
            return
        self.closed = True
        if self.bar is not None:
            self.bar.set_postfix_str(self._details(), refresh=False)
            self.bar.refresh()
            self.bar.close()
        else:
            self._line()
