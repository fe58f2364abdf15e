"""Simulated time as a node lives it: is /clock arriving, and was use_sim_time switched while it ran.

A node on simulated time whose /clock stops has a clock that stands still: its timers on that clock stop (the
planner's control loop, the plant's integration) while its wall-clock timers go on. Without a look at the wall
clock, the planner's status (re-published on a wall timer) kept saying OK with its last mode while nothing moved.
SimTimeWatch is that look. It also tells when use_sim_time was switched at runtime (rclpy's TimeSource switches the
clock in its on-set-parameters callback): every time a node kept is then on the other clock (wall time is ~1.7e9 s,
simulated time starts at 0), and the node must restart what it timed.
"""

from __future__ import annotations

import time

from rclpy.clock import ROSClock
from rclpy.node import Node

from fastep_ros.common import ClockGuard

__all__ = ['SimTimeWatch']


class SimTimeWatch:
    """Watches one node's clock on the wall clock; `timeout` wall seconds without /clock is a problem."""

    def __init__(self, node: Node, guard: ClockGuard | None, timeout: float) -> None:
        self.node = node
        self.guard = guard
        self.timeout = timeout
        self.active = self.simulated()
        self.since = time.monotonic()   # when simulated time was switched on (or the node started)

    def simulated(self) -> bool:
        """Is the node's clock on simulated time now?"""
        clock = self.node.get_clock()
        return isinstance(clock, ROSClock) and clock.ros_time_is_active

    def switched(self) -> bool:
        """True once after each switch of use_sim_time."""
        active = self.simulated()
        if active == self.active:
            return False
        self.active, self.since = active, time.monotonic()
        return True

    def silence(self) -> float:
        """Wall seconds without a /clock message while on simulated time (since the switch at most); 0 on wall time
        or when the /clock handler could not be watched (no guard)."""
        if not self.active or self.guard is None:
            return 0.0
        heard = self.guard.heard
        last = self.since if heard is None or heard < self.since else heard
        return time.monotonic() - last

    def problem(self) -> str:
        """Why the node's time stands still ('' when it does not)."""
        silent = self.silence()
        if silent <= self.timeout:
            return ''
        return f'no /clock for {silent:.1f} s (use_sim_time is true, clock_timeout {self.timeout:g} s): this ' \
               f'node\'s time stands still'
