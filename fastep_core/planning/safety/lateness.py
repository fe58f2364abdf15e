"""How late the control loop acts, measured, and the speed that stays safe at that lateness.

Every stop the guard and the approach plan assumes the next command comes a control period later and the pose
acted on is the robot's now. On a busy computer neither holds: a tick can come late (the executor or the GIL held
elsewhere), odometry can be old when it is used, and the scan the guard checks can be older than the laser's
newest. Lateness is the time the robot may drive on beyond what those plans assume:

    late = (worst tick gap - period) + (odometry age - period) + (scan age - scan allowance),

each the worst over the last LATENESS_WINDOW seconds; a tick gap or an odometry age within 1.5 periods is on time
(ON_TIME: a timer's jitter; the graph benchmarks count a period late from 1.5). A gap after a stop counts only when
shorter than the window: a longer one is a loop that was off (a lifecycle inactive), not late, and standing risked
nothing meanwhile. The control tick (planning/control.py) then
- looks `late` seconds further ahead with the guard, and
- allows itself no more speed than stops within the distance it would stop in on time: from top speed v at braking
  a, v*late + s^2/2a <= v^2/2a gives s = a(sqrt(late^2 + v^2/a^2) - late); and, toward the goal d ahead, no more
  than stops there: s = a(sqrt(late^2 + 2d/a) - late).
On time (late 0) both caps are above anything the plan asks, so nothing changes.
"""

from __future__ import annotations

import math
from collections import deque

__all__ = ['LATENESS_WINDOW', 'ON_TIME', 'Lateness', 'stopping_speed']

LATENESS_WINDOW = 5.0   # s of the robot's clock: how long one late tick keeps the robot slower (a loop
#                         starved once is starved again: another process's bursts, a collector)
ON_TIME = 0.5           # periods: a tick or odometry later than due by no more than this is on time (timer jitter)


def stopping_speed(room: float, late: float, braking: float) -> float:
    """The highest speed that, driven on for `late` seconds and then braked at `braking`, stops within `room`."""
    if braking <= 0.0 or not math.isfinite(braking):
        return math.inf if late <= 0.0 else max(room, 0.0) / late
    room = max(room, 0.0)
    return braking * (math.sqrt(late * late + 2.0 * room / braking) - late)


class Lateness:
    """The control loop's measured lateness (module docstring), fed once per control tick."""

    def __init__(self, window: float = LATENESS_WINDOW) -> None:
        self.window = window
        self._samples: deque[tuple[float, float, float, float]] = deque()   # (t, gap, odometry, scan) beyond due
        self._last: tuple[float, bool] | None = None   # the previous tick's time, and whether it told the robot to move
        self.gap = self.odometry = self.scan = 0.0     # the worst of each over the window, beyond what is due (s)

    @property
    def late(self) -> float:
        """Seconds the robot may drive on beyond what its stops plan for (0: on time)."""
        return self.gap + self.odometry + self.scan

    def tick(self, t: float, period: float, odometry_age: float = 0.0, scan_late: float = 0.0) -> None:
        """A control tick at t (period: the one due); odometry_age: how old the odometry acted on is; scan_late:
        how much older than allowed the scan the guard checks is."""
        gap = 0.0
        if self._last is not None:
            before, moving = self._last
            if t < before:
                self.reset()   # the clock went back (a restarted simulation): nothing before counts
            elif moving or t - before <= self.window:
                gap = t - before - period
        slack = ON_TIME * period
        sample = (t, gap if gap > slack else 0.0, odometry_age - period if odometry_age - period > slack else 0.0,
                  max(scan_late, 0.0))
        samples = self._samples
        if any(sample[1:]) or samples:
            samples.append(sample)
            while samples and samples[0][0] < t - self.window:
                samples.popleft()
            self.gap = max(s[1] for s in samples)
            self.odometry = max(s[2] for s in samples)
            self.scan = max(s[3] for s in samples)
            if not (self.gap or self.odometry or self.scan):
                samples.clear()   # on time for a whole window: the per-tick cost goes back to nothing
        self._last = (t, False)

    def moving(self, t: float, moving: bool) -> None:
        """Whether the command sent at tick t tells the robot to move (a gap after it counts)."""
        if self._last is not None and self._last[0] == t:
            self._last = (t, moving)

    def reset(self) -> None:
        self._samples.clear()
        self._last = None
        self.gap = self.odometry = self.scan = 0.0

    def describe(self) -> str:
        """Which parts make the lateness, in words ('' when on time)."""
        parts = [f'{name} {value:.2f} s' for name, value in (('ticks', self.gap), ('odometry', self.odometry),
                                                             ('scan', self.scan)) if value > 0.0]
        return f'{self.late:.2f} s late ({", ".join(parts)})' if parts else ''
