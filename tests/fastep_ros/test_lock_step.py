"""fastep_ros.lock_step: which odometry stamp a planner acts on, and when every input of its time is in."""

from __future__ import annotations

import pytest

from fastep_ros.lock_step import LockStep


def test_a_stamp_is_due_once_time_runs_and_only_once() -> None:
    lock = LockStep()
    assert not lock.due(0.0, 0.0)          # the clock holds 0 before the run: goals may still be coming
    assert lock.due(0.0, 0.05)             # time runs: the start state is acted on, at 0
    lock.acted = 0.0
    assert not lock.due(0.0, 0.05)         # not twice
    assert not lock.due(0.1, 0.05)         # not ahead of the node's clock
    assert lock.due(0.05, 0.05)
    assert lock.due(0.05 + 1e-9, 0.05)     # stamps through nanoseconds are the same time


def test_act_only_when_every_input_of_that_time_is_in() -> None:
    lock = LockStep(wait=5.0)
    assert lock.late(1.0, {'r2': 0.95, 'r3': 1.0, 'scan': 1.0}, wall=100.0) == ['r2']
    assert lock.late(1.0, {'r2': 1.0, 'r3': 1.0, 'scan': 1.0}, wall=100.1) == []
    assert lock.waiting_since is None and lock.abandoned == []
    assert lock.late(1.05, {'r2': 1.1}, wall=101.0) == []   # a newer stamp answers too


def test_an_input_that_does_not_come_is_given_up_on_once_until_it_comes_again() -> None:
    lock = LockStep(wait=5.0)
    assert lock.late(1.0, {'r2': 0.5}, wall=10.0) == ['r2']
    assert lock.late(1.0, {'r2': 0.5}, wall=15.0) == ['r2']          # not yet: 5 s exactly
    assert lock.late(1.0, {'r2': 0.5}, wall=15.1) == []              # given up on
    assert lock.abandoned == ['r2'] and lock.gone == {'r2': 0.5}
    assert lock.late(1.05, {'r2': 0.5}, wall=15.2) == []             # the next tick does not wait for it again
    assert lock.abandoned == []
    assert lock.late(1.1, {'r2': 0.7}, wall=16.0) == ['r2']          # it published again: waited for again
    assert lock.gone == {}


def test_the_clock_reads_an_answers_stamp_from_its_bytes() -> None:
    """The clock takes every planner's cmd_vel and every observer's acknowledgement as bytes: a TwistStamped's
    header stamp, a Clock's time, none for a Twist (it answers whatever tick is current)."""
    from geometry_msgs.msg import Twist, TwistStamped
    from rosgraph_msgs.msg import Clock

    from fastep_ros.clock import _raw_stamp, _stamped_first
    from msg_tools import cdr
    assert _stamped_first(TwistStamped) and _stamped_first(Clock) and not _stamped_first(Twist)
    assert _raw_stamp(cdr.twist_stamped_cdr(cdr.stamp_parts(16.45), 'r1/base_link', (1.0, 0.0), 0.0),
                      TwistStamped, True) == 16.45
    assert _raw_stamp(cdr.clock_cdr(cdr.stamp_parts(0.05)), Clock, True) == 0.05
    assert _raw_stamp(cdr.twist_cdr((1.0, 0.0), 0.0), Twist, False) is None


def test_an_observer_acknowledges_a_period_apart_and_a_held_time_each_time_it_is_said_again() -> None:
    from fastep_ros.lock_step import AckPacer
    pacer = AckPacer(0.25)
    due = [t for t in (0.05 * k for k in range(1, 21)) if pacer.due(t)]
    assert due == pytest.approx([0.05, 0.3, 0.55, 0.8])
    assert pacer.due(1.0)           # said again (the clock holds 1.0): at once
    assert pacer.due(1.0)           # and again: the first acknowledgement may have been lost (not yet matched)
    assert pacer.due(1.0)
    assert not pacer.due(1.05)      # time runs again: a period apart
    assert not pacer.due(0.9)       # an old time said late is no answer to a hold
    assert not pacer.due(0.9)
    every = AckPacer()              # period 0: every time
    assert all(every.due(0.05 * k) for k in range(1, 6))

