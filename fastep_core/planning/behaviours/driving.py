"""Driving on: the algorithm's target (`Algorithm`, the last behaviour), driving to a target or on through a
deferred step (`drive_on`), and standing clear of a mover (`stand_clear`)."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from fastep_core.planning.behaviours.tick import FloatArray, Steering, Tick
from fastep_core.planning.others import OtherRobot

__all__ = ['Algorithm', 'drive_on', 'stand_clear']


class Algorithm:
    """The algorithm's target (`choose_target`)."""

    def __call__(self, nav: Steering, now: Tick) -> FloatArray:
        return drive_on(nav, now, nav.choose_target(now.position, now.others))


def drive_on(nav: Steering, now: Tick, target: FloatArray | None, drive_on_deferred: bool = True) -> FloatArray:
    """Drive to target; without one, while the step is deferred to the next tick, on to the last target as before
    (rather than stopping for one tick in the middle of a crowd), else stop."""
    if target is None:
        last = nav.target
        if nav.step_deferred and last is not None and drive_on_deferred:
            return nav.drive_to(now.state, last, now.t, now.dt, now.others)
        nav.clear_target()
        return np.zeros(2)
    return nav.drive_to(now.state, target, now.t, now.dt, now.others)


def stand_clear(nav: Steering, state: FloatArray, others: Sequence[OtherRobot]) -> FloatArray:
    """A robot standing still (no valid step, held, waiting) that a mover would run into gets out of its
    way (planning/safety/yielding.py); zeros otherwise."""
    stop = np.zeros(2)
    state = np.asarray(state, dtype=float)
    if not np.isfinite(state).all():
        return stop
    yielded = nav.yield_to_movers(state, stop, nav.params.dt, others)
    if yielded.kind != 'evading':
        return stop
    nav.yield_kind, nav.reason = yielded.kind, yielded.reason
    return yielded.command
