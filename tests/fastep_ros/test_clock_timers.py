"""Timers on simulated time fire in every period on either executor, also when the next /clock time is taken while
a timer's call is still queued (fastep_ros.common.ClockGuard.repair_timers).

rclpy's EventsExecutor (rclpy/src/rclpy/events_executor/timers_manager.cpp, ClockManager) queues a timer's call
at each look that finds it due, without looking whether one is queued already, and rcl_timer_call moves the timer
a period on at each call. A look is queued after each timer call (before its callback runs) and at each /clock jump.
So when a timer's call for time t comes late, behind the node's other work, and the /clock of t + period is taken
right after it, both looks find the timer due at t + period: it is called twice there and skips t + 2 period. In
lock step a plant's odometry of t often comes from its cmd_vel callback before its timer's call, the graph answers
with t + period at once, and the period skipped never comes on its own (the clock waits for that plant's odometry):
the whole graph waited LOCK_WAIT (5 s) and went on without it, "lock step: nothing stamped ... acting without".

The graph here is tasks of the node's executor (no DDS, no other process): the executor takes the same events
in the same order on every run, and a stall is seen when the executor has nothing left to do, not after a wall-clock
deadline (a busy machine only makes these tests slower).
"""

from __future__ import annotations

from typing import Any, Callable

import pytest
from builtin_interfaces.msg import Time
from rclpy.node import Node
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from fastep_ros.common import ClockGuard, guard_clock
from fastep_ros.executors import EXECUTORS, make_executor
from fastep_ros.plant import PlantNode

PERIOD_NS = 50_000_000   # the control period of a lock-step run (0.05 s)
TICKS = 30


def _clock(ns: int) -> Clock:
    return Clock(clock=Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000))


def _busy(tick: int) -> bool:
    """Ticks whose answer comes before the timer's call (every third): the rest wait for the timer."""
    return tick % 3 == 1


class _Graph:
    """The rest of a lock-step graph, as tasks of the node's executor (its queue of events, first in first out; the
    EventsExecutor of rclpy 7.1 takes no guard conditions): on_advance takes the next /clock time through the node's
    guard; a tick is answered (the next on_advance queued) by the node's odometry or its timer (answer), and at a
    busy tick `elsewhere` is queued first: the callback that makes the tick's odometry before the timer's call."""

    def __init__(self, executor: Any, guard: ClockGuard, elsewhere: Callable[[], None]) -> None:
        self.executor, self.guard = executor, guard
        self.tick = 0            # the time taken last, in periods
        self.answered = 0        # the last tick answered
        self.events = 0          # the test's callbacks run so far (spin's measure of an idle executor)
        self.elsewhere = elsewhere

    def on_advance(self) -> None:
        self.events += 1
        self.tick += 1
        self.guard(_clock(self.tick * PERIOD_NS))
        if _busy(self.tick):
            self.executor.create_task(self.on_other)

    def on_other(self) -> None:
        self.events += 1
        self.elsewhere()

    def answer(self, tick: int) -> None:
        """Tick `tick` is answered (once): the next /clock time is queued."""
        self.events += 1
        if tick == self.tick and self.answered < tick < TICKS:
            self.answered = tick
            self.executor.create_task(self.on_advance)

    def spin(self, executor: Any, done: Callable[[], bool], idle: int = 50, most: int = 100_000) -> None:
        """Spin until done(), or until the executor has run none of the test's callbacks `idle` times in a row
        (nothing here comes from outside the node: a graph that stands stays standing)."""
        quiet = 0
        for _ in range(most):
            if quiet >= idle or done():
                return
            before = self.events
            executor.spin_once(timeout_sec=0.001)
            quiet = quiet + 1 if self.events == before else 0


@pytest.mark.parametrize('kind', EXECUTORS)
def test_a_timer_on_simulated_time_fires_in_every_period_when_the_next_time_comes_behind_its_late_call(
        context: Any, kind: str) -> None:
    """The tick order of a loaded lock-step process, on a timer: at a busy tick the graph's answer is queued
    before the timer's call (another callback published the odometry), so the next /clock comes right behind that
    call. On rclpy's EventsExecutor, unrepaired, the timer was called twice at tick 2 and never at tick 3: the
    graph stood at tick 3."""
    executor = make_executor(kind, context)
    node = Node('timed', context=context, parameter_overrides=[Parameter('use_sim_time', value=True)])
    guard = guard_clock(node)
    assert isinstance(guard, ClockGuard)
    fired: list[int] = []
    graph = _Graph(executor, guard, lambda: graph.answer(graph.tick))   # a busy tick's odometry, before the timer

    def on_timer() -> None:
        tick = round(node.get_clock().now().nanoseconds / PERIOD_NS)
        fired.append(tick)
        graph.answer(tick)

    try:
        guard(_clock(0))
        node.create_timer(PERIOD_NS * 1e-9, on_timer)
        executor.add_node(node)
        executor.create_task(graph.on_advance)
        graph.spin(executor, lambda: graph.tick == TICKS and TICKS in fired)
        assert (graph.tick, graph.answered) == (TICKS, TICKS - 1), f'the graph stood at tick {graph.tick}'
        assert set(range(1, TICKS + 1)) - {k for k in range(1, TICKS + 1) if _busy(k)} <= set(fired)
    finally:
        executor.shutdown()
        node.destroy_node()


@pytest.mark.parametrize('kind', EXECUTORS)
def test_a_lock_step_plant_integrates_every_step_when_its_odometry_is_answered_at_once(
        context: Any, kind: str) -> None:
    """A lock-step plant (no planner: it needs no command), each odometry answered at once with the next /clock
    time; at a busy tick its step is made by its command's callback before its timer's call (on_cmd_vel calls
    on_timer). Odometry of every step comes, in order, each once. Unrepaired, the EventsExecutor called the plant's
    timer twice at step 1 and not at step 2: the plant published step 1 and stood, as in a launch for LOCK_WAIT
    ("nothing stamped 0.1 s from r1")."""
    executor = make_executor(kind, context)
    plant = PlantNode(context=context, parameter_overrides=[
        Parameter('start', value=[0.0, 0.0]), Parameter('use_sim_time', value=True),
        Parameter('lock_step', value=True), Parameter('rate_hz', value=1e9 / PERIOD_NS)])
    guard = plant.clock_guard
    assert isinstance(guard, ClockGuard)
    graph = _Graph(executor, guard, plant.on_timer)   # a busy tick's command: on_cmd_vel calls on_timer
    published: list[int] = []
    publish: Callable[[], None] = plant.publish

    def answered() -> None:   # the graph's answer to each odometry
        publish()
        tick = -1 if plant.tick is None else plant.tick
        published.append(tick)
        graph.answer(tick)

    plant.publish = answered   # type: ignore[method-assign]  # the test answers what the plant publishes
    try:
        guard(_clock(0))
        executor.add_node(plant)
        executor.create_task(graph.on_advance)
        graph.spin(executor, lambda: bool(published) and published[-1] >= TICKS)
        assert [k for k in published if k > 0] == list(range(1, TICKS + 1)), f'the plant stood at tick {graph.tick}'
    finally:
        executor.shutdown()
        plant.destroy_node()
