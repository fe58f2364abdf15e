"""What the robot harness measures, as plain functions of recorded arrays (no ROS): unit-tested on synthetic data.

A real base applies each cmd_vel as it comes, so what a robot feels of its planner is in the commands' arrival
times and values: the gaps between them (a base that hears nothing for long drives on blind, or stops at its
timeout), and the velocity steps between successive commands over the time between them, also averaged over a
few successive commands (arrival jitter of a few ms makes a step over 0.048 s look 4 % steeper).
CPU: a process's utime + stime from /proc/<pid>/stat, in clock ticks.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ['Gaps', 'command_accelerations', 'command_gaps', 'cpu_percent', 'parse_control_ms', 'parse_proc_stat',
           'process_cpu_seconds']

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Gaps:
    """The gaps between successive commands longer than `threshold` (s): how many, and the longest of all."""

    threshold: float
    count: int
    longest: float


def command_gaps(times: ArrayLike, threshold: float) -> Gaps:
    """Gaps between successive arrival times (s, increasing) longer than threshold; longest 0 for < 2 times."""
    gaps = np.diff(np.asarray(times, dtype=float))
    if not len(gaps):
        return Gaps(threshold, 0, 0.0)
    return Gaps(threshold, int(np.count_nonzero(gaps > threshold)), float(gaps.max()))


def command_accelerations(times: ArrayLike, v: ArrayLike, omega: ArrayLike, span: int = 1,
                          min_dt: float = 1e-3) -> tuple[float, float]:
    """max |dv/dt| and max |domega/dt| over `span` successive command intervals (arrival times in s): span 1, the
    step between two commands over the time between them (at least min_dt: two commands taken in one callback
    are not 0 s apart at the base); a larger span averages over that many intervals, so a command that arrives a
    few ms early or late (a step over 0.048 s, not 0.05) weighs 1 / span as much. (0, 0) for <= span commands."""
    t = np.asarray(times, dtype=float)
    if len(t) <= span:
        return 0.0, 0.0
    dt = np.maximum(t[span:] - t[:-span], min_dt)
    x, w = np.asarray(v, dtype=float), np.asarray(omega, dtype=float)
    return float((np.abs(x[span:] - x[:-span]) / dt).max()), float((np.abs(w[span:] - w[:-span]) / dt).max())


def parse_proc_stat(text: str) -> int:
    """utime + stime (clock ticks) of a /proc/<pid>/stat line. The command name (field 2) is in parentheses and
    may hold spaces and parentheses itself: the fields are counted after its last ')'."""
    rest = text[text.rindex(')') + 2:].split()
    # rest[0] is field 3 (state): utime and stime are fields 14 and 15.
    return int(rest[11]) + int(rest[12])


def process_cpu_seconds(pid: int) -> float:
    """CPU seconds (user + system) a running process has used so far; OSError when it is gone."""
    with open(f'/proc/{pid}/stat') as f:
        return parse_proc_stat(f.read()) / os.sysconf('SC_CLK_TCK')


def cpu_percent(cpu_before: float, cpu_after: float, wall: float) -> float:
    """Percent of one core used between two readings of process_cpu_seconds `wall` seconds apart (NaN: wall <= 0)."""
    return 100.0 * (cpu_after - cpu_before) / wall if wall > 0.0 else float('nan')


def parse_control_ms(text: str) -> tuple[float, float, float] | None:
    """(p50, p99, max) of a planner status' control_ms value 'p50 / p99 / max'; None when empty or malformed."""
    parts = text.split('/')
    if len(parts) != 3:
        return None
    try:
        p50, p99, top = (float(p) for p in parts)
    except ValueError:
        return None
    return p50, p99, top
