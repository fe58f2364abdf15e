"""Tests of the planner node's planning thread: waiting for it, and holding its passes where a test wants them.

A pass runs on a thread of its own (fastep_ros/planning_thread.py); a test that checks what the executor does
meanwhile holds the pass at a `Gate` and waits on conditions, never on a fixed sleep (green on a busy machine).
"""

from __future__ import annotations

import threading
import time
from typing import Any, Callable

import numpy as np

__all__ = ['WAIT', 'Gate', 'wait_for']

WAIT = 30.0   # s: what a test waits at most for the planning thread (only a machine under heavy load comes near)


def wait_for(condition: Callable[[], bool], what: str) -> None:
    """Until `condition` holds (AssertionError naming `what` after WAIT seconds)."""
    deadline = time.monotonic() + WAIT
    while not condition():
        assert time.monotonic() < deadline, f'{what}: not within {WAIT:g} s'
        time.sleep(0.002)


class Gate:
    """Something on the planning thread that waits until the test opens it (and says when it was reached)."""

    def __init__(self) -> None:
        self.open, self.entered = threading.Event(), threading.Event()

    def wait(self) -> None:
        self.entered.set()
        assert self.open.wait(WAIT), 'the gate was never opened'

    @classmethod
    def holding(cls, nav: Any) -> Gate:
        """A gate every pass of `nav` waits at, before its update: a pass that takes as long as the test wants."""
        gate, update = cls(), nav.update

        def stuck(*args: Any) -> np.ndarray:
            gate.wait()
            return update(*args)
        nav.update = stuck
        return gate
