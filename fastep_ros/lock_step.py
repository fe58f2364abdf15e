"""Exact lock step: when a planner acts, so that a live graph steps exactly like fastep-sim.

fastep-sim's tick at time t: every planner decides from every robot's state at t, then every robot moves for
one control period. On the graph the same three hops make a tick, whatever order DDS delivers messages in:

1. the clock says t (fastep-clock waits for every planner's cmd_vel stamped t - dt first);
2. each plant integrates from t - dt to t with the command stamped t - dt and publishes its odometry stamped t;
3. each planner acts once, when its own odometry stamped t and that of every robot it follows (and its scan)
   are in, and stamps its cmd_vel t.

The first tick starts at time 0 once time runs. An input that does not come within `wait` wall seconds is given
up on until a newer stamp of it comes, so a dead robot costs the wait once, not every tick.

LockStep is the bookkeeping, without ROS (unit-tested alone); the planner node feeds it. AckPacer paces an
observer's acknowledgements.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

__all__ = ['LOCK_WAIT', 'STAMP_EPS', 'AckPacer', 'LockStep']

LOCK_WAIT = 5.0     # wall seconds an input is waited for (the clock's sync_timeout: a loaded machine starves a node)
STAMP_EPS = 1e-6    # seconds: stamps this close are the same time (float times through nanosecond stamps)


@dataclass
class LockStep:
    """Which odometry stamp a planner acts on next, and whether every input of that time is in."""

    wait: float = LOCK_WAIT
    acted: float = -math.inf              # the stamp last acted on
    waiting_since: float | None = None    # wall seconds the stamp due began waiting for an input
    gone: dict[str, float] = field(default_factory=dict)   # input given up on -> its stamp then
    abandoned: list[str] = field(default_factory=list)     # the inputs the last call of late() gave up on
    blocker: Any = None    # the caller's handle on the first input late() waits for (held() looks at it alone)

    def due(self, stamp: float, now: float) -> bool:
        """Odometry stamped `stamp` is to be acted on at node time `now`: newer than the last acted on, not ahead
        of the clock, and time runs (before the run the clock holds 0 while goals come)."""
        return now > 0.0 and self.acted + STAMP_EPS < stamp <= now + STAMP_EPS

    def late(self, stamp: float, inputs: Mapping[str, float], wall: float) -> list[str]:
        """The inputs (name -> newest stamp) still to wait for before acting on `stamp`; [] to act now. Those
        waited for longer than `wait` wall seconds are given up on (until a newer stamp of theirs comes)."""
        self.abandoned = []
        for name, heard in list(self.gone.items()):
            if inputs.get(name, heard) > heard + STAMP_EPS:
                del self.gone[name]   # it came back
        late = [name for name, heard in inputs.items() if heard < stamp - STAMP_EPS and name not in self.gone]
        self.blocker = None
        if not late:
            self.waiting_since = None
            return []
        if self.waiting_since is None:
            self.waiting_since = wall
        if wall - self.waiting_since <= self.wait:
            return late
        for name in late:
            self.gone[name] = inputs[name]
        self.abandoned, self.waiting_since = late, None
        return []

    def held(self, heard: float | None, stamp: float, wall: float) -> bool:
        """Whether `stamp` still waits, from the input late() waited for first alone (its newest stamp `heard`;
        None when it is no longer an input): still behind and the wait not over, late() would say wait too. A
        lock-step planner hears N - 1 other robots' odometry a tick, each a call: this spares it building the
        inputs for all of them each time."""
        return heard is not None and heard < stamp - STAMP_EPS and self.waiting_since is not None and \
            wall - self.waiting_since <= self.wait


@dataclass
class AckPacer:
    """When an observer of the lock step (fastep-launch's monitor, fastep-record) acknowledges a /clock time it has
    taken: once every `period` simulated seconds (the clock lets it lag its observer_lag ticks behind), and a time
    said again each time it is said again (the clock holds it, waiting for an observer: its repeats come every
    HOLD_PERIOD of wall time). Said only once, an acknowledgement sent before the clock's end of the reliable
    connection had matched was lost, and the clock waited 30 s for one that never came again."""

    period: float = 0.0
    acked: float = -math.inf   # the time acknowledged last
    seen: float = -math.inf    # the time taken last

    def due(self, t: float) -> bool:
        """Take /clock time `t`; True if it is to be acknowledged now."""
        again, self.seen = t == self.seen, t
        if t >= self.acked + self.period - STAMP_EPS or (again and t >= self.acked - STAMP_EPS):
            self.acked = t
            return True
        return False
