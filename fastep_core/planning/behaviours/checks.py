"""The checks that end or redirect a goal: a goal nothing reaches, a goal the robot makes no progress toward, and
a robot trapped (it starts a recovery and the tick goes on)."""

from __future__ import annotations

import numpy as np

from fastep_core.planning.behaviours.recoveries import Escaping, Manoeuvring
from fastep_core.planning.behaviours.tick import FloatArray, Steering, Tick

__all__ = ['PathCheck', 'ProgressCheck', 'TrapCheck']


class PathCheck:
    """On the goal's first tick: its exact path (the navigator's `reference`); a goal nothing reaches fails."""

    def __init__(self) -> None:
        self.checked = False   # has the goal been checked for a path

    def new_goal(self) -> None:
        self.checked = False

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if self.checked:
            return None
        self.checked = True
        nav.reference = nav.exact_path(now.position)
        if nav.reference is None:
            nav.fail_no_path(now.position)
            return np.zeros(2)
        return None


class ProgressCheck:
    """No progress for progress_timeout: the goal fails (planning/recovery/progress.py)."""

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if nav.progress.stalled(now.t, now.distance):
            nav.fail(nav.progress.reason)
            return np.zeros(2)
        return None


class TrapCheck:
    """Trapped (no progress for trap_timeout outside a recovery): a robot that cannot turn in place manoeuvres out
    if it can, any other escapes along the exact path; the tick goes on with it (a stop only when there is no way
    out)."""

    def __init__(self, manoeuvring: Manoeuvring | None, escaping: Escaping) -> None:
        self.manoeuvring, self.escaping = manoeuvring, escaping

    def trapped(self, nav: Steering, t: float, distance: float) -> bool:
        if not nav.escapes_traps or self.escaping.escape.active or \
                (self.manoeuvring is not None and self.manoeuvring.driver.active):
            return False
        return nav.trap.trapped(t, distance)

    def __call__(self, nav: Steering, now: Tick) -> FloatArray | None:
        if self.trapped(nav, now.t, now.distance):
            if self.manoeuvring is not None and nav.start_manoeuvre(now.state, now.t, now.others):
                nav.escapes += 1
            elif not nav.start_escape(now.position, now.distance, now.t, now.others):
                return np.zeros(2)
        return None
