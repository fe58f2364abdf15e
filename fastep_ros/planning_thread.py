"""The planner node's planning thread: passes of the navigator off the control timer's path.

A pass (perception of the newest scan, then Navigator.update: routes, exact paths, escapes, manoeuvres, the
swarm) may take seconds; the control timer must not wait for it (fastep_core/planning/control.py drives on the
newest plan meanwhile). Why a thread and not a process or callback groups: the navigator's state (its world, its
route, its swarm) is large and changes every pass, and a thread shares it without copying; the executor stays
the node's own (the EventsExecutor by default), so one code path serves every layout of fastep-launch. The GIL
lets the control callback in within the interpreter's switch interval, which the node sets to SWITCH_INTERVAL.

Everything that changes the navigator (a goal, a new world, new parameters, a restart of its clock) goes through
`call`: at once on the caller's thread when no pass is under way, else between passes on the planning thread, in
the order given; no pass sees a half-made change, and the caller never waits for a pass.
"""

from __future__ import annotations

import collections
import functools
import sys
import threading
import time
import traceback
from typing import Any, Callable, Generic, TypeVar

__all__ = ['PlanningThread', 'SWITCH_INTERVAL']

SWITCH_INTERVAL = 0.0005   # s: how long a thread holding the GIL keeps another waiting for it, at most (default 5 ms)
PASS_TIMES = 200           # passes whose wall times the diagnostics sum up

Snapshot = TypeVar('Snapshot')
PlanT = TypeVar('PlanT')


class PlanningThread(Generic[Snapshot, PlanT]):
    """One thread running `plan_pass` on the newest snapshot submitted, and the changes `call`ed between passes."""

    def __init__(self, plan_pass: Callable[[Snapshot], PlanT | None], log_error: Callable[[str], Any]) -> None:
        self._plan_pass, self._log_error = plan_pass, log_error
        self._wake = threading.Condition()
        self._working = threading.Lock()   # held while a pass or a change runs
        self._calls: collections.deque[Callable[[], Any]] = collections.deque()
        self._snapshot: Snapshot | None = None
        self._stopping = False
        self.plan: PlanT | None = None          # the newest plan (replaced whole: the control timer reads it)
        self.passes = 0
        self.pass_started: float | None = None  # perf_counter() when the pass under way began
        self.pass_times: collections.deque[float] = collections.deque(maxlen=PASS_TIMES)   # wall seconds
        if sys.getswitchinterval() > SWITCH_INTERVAL:
            sys.setswitchinterval(SWITCH_INTERVAL)
        self._thread = threading.Thread(target=self._run, name='planning', daemon=True)
        self._thread.start()

    def submit(self, snapshot: Snapshot) -> None:
        """Plan from this snapshot next (a snapshot still waiting is replaced: only the newest counts)."""
        with self._wake:
            self._snapshot = snapshot
            self._wake.notify()

    def call(self, change: Callable[[], Any]) -> None:
        """Run `change` now if no pass is under way, else on the planning thread before the next pass."""
        if self._working.acquire(blocking=False):
            try:
                with self._wake:
                    calls, self._calls = [*self._calls, change], collections.deque()
                for work in calls:
                    self._guarded(work)
            finally:
                self._working.release()
            return
        with self._wake:
            self._calls.append(change)
            self._wake.notify()

    def drop_plan(self) -> None:
        """Forget the plan (a new navigator: its predecessor's plan is not its own); call from a `call`."""
        self.plan = None

    def on_thread(self) -> bool:
        """Is the caller the planning thread (a change it runs)?"""
        return threading.current_thread() is self._thread

    @property
    def alive(self) -> bool:
        """Is the thread still running (a pass under way past stop's timeout)?"""
        return self._thread.is_alive()

    @property
    def busy_for(self) -> float:
        """Wall seconds the pass under way has run (0 when none is)."""
        started = self.pass_started
        return 0.0 if started is None else time.perf_counter() - started

    def stop(self, timeout: float = 5.0) -> None:
        """End the thread after the pass under way (waits at most `timeout` seconds for it)."""
        with self._wake:
            self._stopping = True
            self._wake.notify()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)

    def _run(self) -> None:
        while True:
            with self._wake:
                while not (self._stopping or self._calls or self._snapshot is not None):
                    self._wake.wait()
                if self._stopping:
                    return
            with self._working:
                with self._wake:
                    calls, self._calls = list(self._calls), collections.deque()
                    snapshot, self._snapshot = self._snapshot, None
                for change in calls:
                    self._guarded(change)
                if snapshot is not None:
                    self.pass_started = began = time.perf_counter()
                    plan = self._guarded(functools.partial(self._plan_pass, snapshot))
                    self.pass_times.append(time.perf_counter() - began)
                    self.passes += 1
                    if plan is not None:
                        self.plan = plan
                    self.pass_started = None

    def _guarded(self, work: Callable[[], Any]) -> Any:
        """A fault in a change or a pass is logged, never the end of the thread (the node fails the goal)."""
        try:
            return work()
        except Exception as exc:  # noqa: BLE001  the thread must outlive any fault of the planner
            self._log_error(f'planning thread: {exc}\n{traceback.format_exc()}')
            return None
