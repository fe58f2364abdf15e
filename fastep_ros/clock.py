"""fastep-clock: simulated time for the graph, published on /clock.

    fastep-clock --ros-args -p rtf:=10.0 [-p step:=0.05] [-p max_rate_hz:=400.0]

Every tick of a steady wall timer, period step / rtf but at least 1 / max_rate_hz, time advances by rtf x the period
(in lock step always by one step); a machine that cannot keep up makes time run slower, never jump. A finer step only
costs CPU: plants integrate in their own steps and planners act once per control period. wait_for_subscribers holds
the start until that many /clock subscriptions match, so no node misses the beginning. Lock step (sync_topics, step =
the control period): each tick waits, up to sync_timeout, until every listed topic (fastep-launch: each planner's
cmd_vel, stamped with its tick) has answered since the tick before (a stamped message stamped after it, an unstamped
one at all); observer_topics (clock_ack of the launcher's monitor and fastep-record) may lag observer_lag ticks. The
timeout is 5 s because a loaded machine starves a node for a second or two; a topic that timed out is not waited for
until it publishes again, and one never heard waits up to wait_timeout. /clock is best effort, so while waiting the
clock repeats the current time every HOLD_PERIOD. Parameters: docs/reference/parameters.md; docs/guide.md.
"""

from __future__ import annotations

import importlib
import math
import struct
from dataclasses import dataclass
from typing import Any, Sequence

from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rclpy.serialization import deserialize_message
from rosgraph_msgs.msg import Clock as ClockMsg

from fastep_ros.common import (
    CLOCK_JUMP_LIMIT,
    RATE_RANGE,
    StartupError,
    check_range,
    declare,
    declare_strings,
    node_main,
    quiet_at_stop,
)
from fastep_ros.limits import OBSERVER_LAG_MAX, RTF_RANGE, STEP_RANGE
from fastep_ros.lock_step import STAMP_EPS
from msg_tools import cdr, convert, interface

__all__ = ['ClockNode', 'main', 'tick_plan']

SETTLE = 0.05       # wall seconds the start time is held after the expected subscribers matched (a subscriber
                    # whose end matched later misses the first tick: it gets it again after HOLD_PERIOD)
HOLD_PERIOD = 0.1   # wall seconds between repeated /clock messages while the time is held
LOOKUP_PERIOD = 0.05   # wall seconds between looks at the graph for the sync topics, while the start time is held
                       # (every 0.2 s, make demo's start waited up to 0.45 s for the clock's cmd_vel subscriptions)
START_MAX = 1e9     # simulated seconds: far from the int32 seconds of a /clock message (2^31 - 1)
GRAPH_LOOK_PERIOD = 0.05   # lock step: wall seconds a tick waits before the graph is asked which late topics still
                           # have a publisher, and between two such looks (asked at every timer event, 16 topics
                           # at 1 kHz, the look cost the clock's process, which runs robots too, 8 % of its core)


@dataclass
class _Sync:
    sub: Any = None
    lag: int = 0            # ticks it may answer late (an observer's clock_ack: observer_lag; a node's: 0)
    heard: float = -math.inf   # the latest time it answered (a message without a stamp: the tick it came in)
    absent: bool = False   # timed out once: not waited for until it publishes again
    answered: bool = False  # has published since the clock started


def _message_type(type_name: str) -> Any:
    """The Python class of 'pkg/msg/Name', or None."""
    try:
        package, kind, name = type_name.split('/')
        return getattr(importlib.import_module(f'{package}.{kind}'), name)
    except (ValueError, ImportError, AttributeError):
        return None


def _stamp(msg: Any) -> float | None:
    """The time a sync message answers: its header's stamp, a rosgraph_msgs/Clock's time (an observer's
    acknowledgement of a tick: fastep-record's and fastep-launch's `clock_ack`); None if it carries none."""
    header = getattr(msg, 'header', None)
    if header is not None:
        return convert.stamp_to_seconds(header.stamp)
    if isinstance(msg, ClockMsg):
        return convert.stamp_to_seconds(msg.clock)
    return None


def _stamped_first(msg_type: Any) -> bool:
    """Does a message of this type start with its stamp (a std_msgs/Header, or a rosgraph_msgs/Clock's time)?
    Then a sync message's stamp is read from its first CDR bytes (msg_tools.cdr.header_stamp)."""
    fields = list(msg_type.get_fields_and_field_types().items())
    return bool(fields) and fields[0][1] in ('std_msgs/Header', 'builtin_interfaces/Time')


def _raw_stamp(data: bytes, msg_type: Any, stamped: bool) -> float | None:
    """_stamp of a sync message's bytes: read with struct where they are little-endian CDR, else by rclpy."""
    if data[:2] != b'\x00\x01':
        return _stamp(deserialize_message(data, msg_type))
    if not stamped:
        return None
    try:
        sec, nanosec = cdr.header_stamp(data)
    except struct.error:
        return None   # cut off: answers whatever tick is current, as a message without a stamp does
    return sec + nanosec * 1e-9


def tick_plan(rtf: float, step: float, max_rate_hz: float) -> tuple[float, float]:
    """(wall period, simulated increment) of one tick."""
    period = max(step / rtf, 1.0 / max_rate_hz)
    return period, rtf * period


class ClockNode(Node):
    """Publishes simulated time on /clock, rtf times faster than wall time."""

    def __init__(self, node_name: str = 'clock', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        if self.get_parameter('use_sim_time').value:
            raise StartupError('the clock cannot itself run on simulated time (use_sim_time must be false)')
        self.rtf = declare(self, 'rtf', 1.0, 'real-time factor: simulated seconds per wall second',
                           constraints=f'range [{RTF_RANGE[0]:g}, {RTF_RANGE[1]:g}]')
        self.step = declare(self, 'step', 0.05, 'simulated seconds per tick, at most (it grows when the tick '
                            'rate would exceed max_rate_hz); the default is the planners\' control period',
                            constraints=f'range [{STEP_RANGE[0]:g}, {STEP_RANGE[1]:g}]')
        self.max_rate_hz = declare(self, 'max_rate_hz', 400.0, 'most ticks per wall second',
                                   constraints=f'range [{RATE_RANGE[0]:g}, {RATE_RANGE[1]:g}]')
        self.start = declare(self, 'start', 0.0, 'simulated time of the first tick minus one increment (s)',
                             constraints=f'range [0, {START_MAX:g}]')
        self.wait_for = declare(self, 'wait_for_subscribers', 0, 'hold the time at start until this many '
                                '/clock subscriptions are matched (so no node misses the beginning)')
        self.wait_timeout = declare(self, 'wait_timeout', 30.0, 'start anyway after this many wall seconds of '
                                    'waiting for subscribers (s)')
        topics = declare_strings(self, 'sync_topics', 'lock step: before each tick, wait until every one of these '
                         'topics (e.g. the planners\' cmd_vel, published once per control period) has delivered a '
                         'message since the previous tick; empty: free-running')
        observers = declare_strings(self, 'observer_topics', 'lock step: like sync_topics, but each of these may '
                            'answer up to observer_lag ticks late (the clock_ack of a node that watches the graph and '
                            'is not part of it: fastep-launch\'s monitor, fastep-record)')
        self.observer_lag = declare(self, 'observer_lag', 0, 'lock step: ticks an observer_topics answer may lag '
                                    'behind (0: each tick waits for every observer, as for sync_topics)',
                                    value_range=(0, OBSERVER_LAG_MAX), unit=' ticks')
        self.sync_timeout = declare(self, 'sync_timeout', 5.0, 'lock step: tick anyway after waiting this many '
                                    'wall seconds, and stop waiting for a topic that did not answer until it '
                                    'publishes again (a node that stopped does not freeze time)')
        check_range('rtf', self.rtf, *RTF_RANGE)
        check_range('step', self.step, *STEP_RANGE, ' s')
        check_range('max_rate_hz', self.max_rate_hz, *RATE_RANGE, ' Hz')
        check_range('start', self.start, 0.0, START_MAX, ' s')
        self.period, self.increment = tick_plan(self.rtf, self.step, self.max_rate_hz)
        if self.increment > CLOCK_JUMP_LIMIT:
            raise StartupError(f'a tick of {self.increment:g} s (rtf {self.rtf:g} at max_rate_hz '
                               f'{self.max_rate_hz:g}) is more than the nodes take from one /clock message '
                               f'({CLOCK_JUMP_LIMIT:g} s): lower rtf or raise max_rate_hz')
        if topics or observers:
            # Lock step: every tick is one control period, as in the in-process simulator. A bigger increment
            # would make rcl timers skip periods (planners at 8 Hz instead of 20 Hz of simulated time), so
            # beyond max_rate_hz the clock runs slower than rtf instead (rtf is an upper bound here anyway).
            self.increment = self.step
        self.ticks = 0
        self.steady = Clock(clock_type=ClockType.STEADY_TIME)
        self.created = self.steady.now()
        self.matched_at: float | None = None  # steady seconds when the subscribers were all there
        self.held_at = -math.inf
        self.sync: dict[str, _Sync] = {t: _Sync() for t in topics}
        self.sync.update((t, _Sync(lag=self.observer_lag)) for t in observers if t not in self.sync)
        self.last_tick = -math.inf      # steady seconds of the last advancing tick
        self.last_lookup = -math.inf    # steady seconds of the last graph look-up for sync topics
        self.graph_looked = -math.inf   # steady seconds of the last look at the late topics' publishers (this tick)
        self.publishing: set[str] = set()   # the late topics that had a publisher then
        self.pub = self.create_publisher(ClockMsg, interface.CLOCK, interface.offered_qos(interface.CLOCK))
        self.timer = self.create_timer(self.period, self.on_tick, clock=self.steady)
        self.get_logger().info(f'simulated time at rtf {self.rtf:g}: {self.increment:g} s every '
                               f'{self.period * 1e3:.3g} ms of wall time')

    @property
    def time(self) -> float:
        return self.start + self.ticks * self.increment

    def seconds(self) -> float:
        return self.steady.now().nanoseconds * 1e-9

    def subscribe_sync_topics(self) -> bool:
        """Subscribe to the sync topics that are on the graph (their type is read from it); True when all
        are subscribed and published."""
        missing = [t for t, s in self.sync.items() if s.sub is None]
        if missing and self.seconds() - self.last_lookup > LOOKUP_PERIOD:
            self.last_lookup = self.seconds()
            types = dict(self.get_topic_names_and_types())
            for topic in missing:
                for type_name in types.get(topic, []):
                    msg_type = _message_type(type_name)
                    if msg_type is not None:
                        # Taken as bytes: every planner's cmd_vel and every observer's acknowledgement, each tick.
                        def on_message(data: bytes, t: str = topic, kind: Any = msg_type,
                                       stamped: bool = _stamped_first(msg_type)) -> None:   # a def: mypy types it
                            self.on_sync(t, _raw_stamp(data, kind, stamped))
                        self.sync[topic].sub = self.create_subscription(msg_type, topic, on_message, 10, raw=True)
                        break
        return all(s.sub is not None and self.count_publishers(t) > 0 for t, s in self.sync.items())

    @quiet_at_stop
    def on_sync(self, topic: str, stamp: float | None = None) -> None:
        """A message on a sync topic. One with a stamp answers the current tick if it is stamped after the tick
        before (a planner's cmd_vel decided for the current time; a 50 Hz plant's odometry of its last step), one
        without answers whatever tick is current."""
        sync = self.sync[topic]
        sync.heard = max(sync.heard, self.time if stamp is None else stamp)
        if not self.answers(sync):
            return   # an answer to an earlier tick (in lock step a planner's first command is stamped 0)
        sync.absent = False
        sync.answered = self.ticks > 0
        # The last answer came after the tick period: tick now rather than at the next timer event.
        if self.matched_at is not None and self.seconds() - self.last_tick >= self.period \
                and all(self.answers(s) for s in self.sync.values()) and not self.waiting():
            self.advance()

    def answers(self, sync: _Sync) -> bool:
        """Has `sync` answered the current tick, or (an observer that has answered since the run started) the tick
        `lag` ticks before: said a time later than the tick before that one? (An observer's first answer is waited
        for at once: it also says that its /clock reader has matched, so the run's first ticks reach it. A
        recording lost its first 18 /clock messages, in 1 launch of 6, while the clock ran ahead without it.)"""
        before = self.ticks - 1 - (sync.lag if sync.answered else 0)   # the tick an answer must be later than
        return before < 0 or sync.heard > self.start + before * self.increment + STAMP_EPS

    def synced(self) -> bool:
        """Every node we lock step with has answered the last tick (or stopped publishing). Which late topics still
        have a publisher is asked of the graph only once the tick has waited GRAPH_LOOK_PERIOD, and then every
        GRAPH_LOOK_PERIOD (a tick's answers come within milliseconds; a node that stopped is let go that much later)."""
        pending = [t for t, s in self.sync.items() if not (s.absent or self.answers(s))]
        if not pending:
            return True
        now = self.seconds()
        waited = now - self.last_tick
        if waited < GRAPH_LOOK_PERIOD:
            return False
        if now - self.graph_looked >= GRAPH_LOOK_PERIOD:
            self.graph_looked = now
            self.publishing = {t for t in pending if self.count_publishers(t) > 0}
        late = [t for t in pending if t in self.publishing]
        if not late:
            return True
        # A node that died (SIGKILL) stays on the graph until its DDS lease ends: stop waiting for it. One that
        # has not answered yet is more likely still being matched.
        overdue = [t for t in late if waited > (self.sync_timeout if self.sync[t].answered else self.wait_timeout)]
        for topic in overdue:
            self.sync[topic].absent = True
        if overdue:
            self.get_logger().warning(f'no answer on {", ".join(overdue)} for {waited:.3g} s of wall time; not '
                                      f'waiting for it until it publishes again')
        return len(overdue) == len(late)

    def waiting(self) -> bool:
        """Hold the start time until the expected subscribers are matched, plus a short settling time."""
        if self.sync and self.matched_at is None and not self.subscribe_sync_topics():   # (not asked once running)
            if (self.steady.now() - self.created).nanoseconds * 1e-9 <= self.wait_timeout:
                return True
        if self.matched_at is not None:
            return (self.steady.now() - self.created).nanoseconds * 1e-9 < self.matched_at + SETTLE
        elapsed = (self.steady.now() - self.created).nanoseconds * 1e-9
        if self.pub.get_subscription_count() >= self.wait_for:
            self.matched_at = elapsed
            return self.wait_for > 0
        if elapsed > self.wait_timeout:
            self.get_logger().warning(f'only {self.pub.get_subscription_count()} of {self.wait_for} /clock '
                                      f'subscribers matched after {self.wait_timeout:g} s; starting anyway')
            self.matched_at = elapsed - SETTLE
            return False
        return True

    @quiet_at_stop
    def on_tick(self) -> None:
        if self.waiting():
            self.repeat()   # holding the start time
        elif not self.sync or self.ticks == 0:  # nothing answers the hold
            self.advance()
        elif self.seconds() - self.last_tick >= 0.5 * self.period and self.synced():
            self.advance()
        else:
            self.repeat()   # lock step, waiting for a node that may have lost this tick's (best-effort) message

    def repeat(self) -> None:
        """Say the current time again, once per HOLD_PERIOD of waiting, without keeping the nodes busy."""
        now = self.seconds()
        if now - max(self.held_at, self.last_tick) < HOLD_PERIOD:
            return
        self.held_at = now
        self.pub.publish(cdr.clock_cdr(cdr.stamp_parts(self.time)))

    def advance(self) -> None:
        self.last_tick = self.seconds()
        self.graph_looked = -math.inf   # the next tick's late topics are looked at anew
        self.ticks += 1
        self.pub.publish(cdr.clock_cdr(cdr.stamp_parts(self.time)))


def main(args: Sequence[str] | None = None) -> int:
    return node_main('fastep-clock', ClockNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
