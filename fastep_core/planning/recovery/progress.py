"""Has the robot come closer to its goal lately? The progress checker and the trap detector.

Both watch the distance to the goal over time, as Nav2's progress checker watches the pose:
- ProgressChecker fails a run when the robot has not come `progress_distance` closer to the goal within
  `progress_timeout` seconds (0 disables it). Progress of another kind (a shorter way left on an escape path,
  a manoeuvre started or finished) restarts its clock through `made_progress`.
- TrapDetector calls the robot trapped when it has not come `progress_distance` closer within `trap_timeout`
  seconds (0 disables it). Near the goal half the distance counts: the kinematic approach slows down in
  proportion to the distance, and a robot driving straight to its goal must never be taken for trapped.
"""

from __future__ import annotations

import math

__all__ = ['ProgressChecker', 'TrapDetector']


class ProgressChecker:
    """Fails a run that does not come `distance` closer to the goal within `timeout` seconds."""

    def __init__(self, distance: float, timeout: float) -> None:
        self.distance, self.timeout = distance, timeout
        self.best = math.inf   # the best distance to the goal so far ...
        self.since = 0.0       # ... and when the clock last restarted

    def reset(self, t: float) -> None:
        self.best, self.since = math.inf, t

    def made_progress(self, t: float) -> None:
        self.since = t

    def stalled(self, t: float, distance: float) -> bool:
        """Note the distance at time t; True when the run has failed to make progress."""
        if distance < self.best - self.distance or self.best == math.inf:
            self.best, self.since = distance, t
            return False
        return self.timeout > 0 and t - self.since > self.timeout

    @property
    def reason(self) -> str:
        return f'failed to make progress: not {self.distance:g} m closer to the goal in {self.timeout:g} s'


class TrapDetector:
    """A robot is trapped when it has not come `distance` closer (near the goal: half the distance) in `timeout` s."""

    def __init__(self, distance: float, timeout: float) -> None:
        self.distance, self.timeout = distance, timeout
        self.best = math.inf   # the best distance to the goal since the last reset ...
        self.since = 0.0       # ... and when it was reached
        self.tripped = False   # trapped at the next check, whatever the clock says (trip)

    def reset(self, t: float, distance: float = math.inf) -> None:
        self.best, self.since = distance, t
        self.tripped = False

    def trip(self) -> None:
        """Call the robot trapped at the next check (the planner knows it is stuck without waiting)."""
        self.tripped = True

    def trapped(self, t: float, distance: float) -> bool:
        if self.timeout <= 0:
            return False
        if self.tripped:
            self.tripped = False
            return True
        needed = min(self.distance, 0.5 * self.best)
        if distance < self.best - needed or self.best == math.inf:
            self.best, self.since = distance, t
            return False
        return t - self.since > self.timeout
