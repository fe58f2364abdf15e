"""fastep-replay: publish a recording on the live graph with its original timing (a `ros2 bag play` stand-in).

    fastep-replay FILE.mcap [--rate R] [--loop] [--topics T [T ...]] [--clock [HZ]] [--delay S]
                  [--wait-subscribers N] [--ros-args ...]

Why: to look at a recorded or simulated run again in RViz/Foxglove, or to feed it to nodes, without rosbag2
(not on PyPI). Messages are published as recorded (raw CDR bytes, never deserialised) in log-time order, with
each topic's recorded QoS (`offered_qos_profiles`), so /map and /obstacles are latched again. --clock publishes
/clock from the log times for nodes with use_sim_time (a recorded /clock is then not replayed).
A truncated file is replayed up to its last complete chunk and a corrupt chunk is skipped, each with a warning;
topics that cannot be published (a refused name, a non-CDR encoding, a type not installed) are left out with a
warning. Exit codes and options: docs/reference/commands.md.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from typing import Any, Sequence

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy
from rosgraph_msgs.msg import Clock

from fastep_core.cli import Parser, guard
from fastep_core.errors import FastepError
from msg_tools import interface
from msg_tools.mcap_io import ChannelInfo, Recording, open_recording
from msg_tools.mcap_writer import MESSAGE_ENCODING
from msg_tools.ros2_profile import message_class, qos_from_dicts

__all__ = ['ReplayNode', 'main']

LINGER = 0.5          # wall seconds the publishers stay after the last message (reliable delivery)
WAIT_TIMEOUT = 30.0   # wall seconds --wait-subscribers waits at most
SLICE = 0.1           # wall seconds slept at most at once: a stop (Ctrl-C, SIGTERM) is noticed within it
MAX_DELAY = 3600.0    # s, --delay
MAX_CLOCK_HZ = 10_000.0
MAX_CLOCK_NS = (2**31 - 1) * 1_000_000_000   # builtin_interfaces/Time.sec is an int32


def pause(seconds: float) -> None:
    """Sleep `seconds` of wall time, or less if ROS shuts down meanwhile (rclpy's SIGINT/SIGTERM handler
    does not interrupt a sleep)."""
    deadline = time.monotonic() + seconds
    while rclpy.ok():
        left = deadline - time.monotonic()
        if left <= 0.0:
            return
        time.sleep(min(left, SLICE))


def init_ros(ros_args: Sequence[str]) -> None:
    """rclpy.init with the --ros-args; FastepError (one line) if ROS refuses them. rcl also logs its own
    complaint on stderr ("Failed to parse global arguments"): what it writes there during init is held back
    and shown only if init succeeds, so that a refusal stays one line."""
    sys.stderr.flush()
    saved = os.dup(2)
    error: Exception | None = None
    with tempfile.TemporaryFile() as held:
        os.dup2(held.fileno(), 2)
        try:
            rclpy.init(args=[PROG, *ros_args])
        except Exception as exc:   # UnknownROSArgsError, RCLError for a remap rule it cannot parse, ...
            error = exc
        finally:
            os.dup2(saved, 2)
            os.close(saved)
        if error is None:
            held.seek(0)
            text = held.read()
            if text:
                os.write(2, text)
            return
    raise FastepError(f'cannot start ROS: {type(error).__name__}: {" ".join(str(error).split())}')


def unplayable(info: ChannelInfo) -> str:
    """Why a recorded topic cannot be published on ROS 2 ('' if it can)."""
    from rclpy.exceptions import NameValidationException
    from rclpy.validate_full_topic_name import validate_full_topic_name

    try:
        validate_full_topic_name(info.topic)
    except NameValidationException:
        return 'its name is not a valid ROS topic name'
    if info.message_encoding != MESSAGE_ENCODING:
        return f'its messages are {info.message_encoding or "not"}-encoded, not cdr'
    try:
        message_class(info.type)
    except FastepError as exc:
        return str(exc)
    return ''


def _stamp(ns: int) -> Any:
    from builtin_interfaces.msg import Time
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


class ReplayNode(Node):
    """Publishers for the recorded topics; play() sends the messages with the recorded timing."""

    def __init__(self, recording: Recording, topics: Sequence[str] | None = None, rate: float = 1.0,
                 clock_hz: float | None = None, node_name: str = 'replay', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.recording = recording
        self.rate = rate
        self.clock_hz = clock_hz
        chosen = set(topics) if topics else set(recording.topics)
        if clock_hz is not None:
            chosen.discard(interface.CLOCK)
        self.topics = sorted(chosen)
        self.publishers_by_topic: dict[str, Any] = {}
        for topic in self.topics:
            info = recording.topics[topic]
            self.publishers_by_topic[topic] = self.create_publisher(message_class(info.type), topic,
                                                                    qos_from_dicts(info.qos))
        self.clock_pub = (self.create_publisher(Clock, interface.CLOCK, interface.offered_qos(interface.CLOCK))
                          if clock_hz is not None else None)
        self.last_clock = -1
        self.played = 0

    # ------------------------------------------------------------------------------------------- clock
    def publish_clock(self, ns: int) -> None:
        if self.clock_pub is not None and ns > self.last_clock:
            self.last_clock = ns
            self.clock_pub.publish(Clock(clock=_stamp(ns)))

    def wait_until(self, target: float, origin_ns: int, origin_wall: float) -> None:
        """Sleep until the wall time `target`; with --clock, tick the clock meanwhile."""
        period = 1.0 / self.clock_hz if self.clock_hz else math.inf
        while rclpy.ok():
            now = time.monotonic()
            if now >= target:
                return
            if self.clock_pub is not None:
                self.publish_clock(min(origin_ns + int((now - origin_wall) * self.rate * 1e9), MAX_CLOCK_NS))
            time.sleep(min(target - now, period, SLICE))

    # ------------------------------------------------------------------------------------------- playing
    def wait_for_subscribers(self, count: int) -> bool:
        """Wait until every volatile topic has `count` subscribers (latched ones reach late joiners anyway)."""
        volatile = [pub for pub in self.publishers_by_topic.values()
                    if pub.qos_profile.durability != DurabilityPolicy.TRANSIENT_LOCAL]
        deadline = time.monotonic() + WAIT_TIMEOUT
        while rclpy.ok() and time.monotonic() < deadline:
            if all(pub.get_subscription_count() >= count for pub in volatile):
                return True
            time.sleep(0.05)
        return False

    def play_once(self) -> int:
        """Publish the recording once; return how many messages were sent."""
        sent = 0
        origin_ns: int | None = None
        origin_wall = time.monotonic()
        for raw in self.recording.raw_messages(self.topics):
            if not rclpy.ok():
                return sent
            if origin_ns is None:
                origin_ns, origin_wall = raw.log_time, time.monotonic()
            self.wait_until(origin_wall + (raw.log_time - origin_ns) * 1e-9 / self.rate, origin_ns, origin_wall)
            if not rclpy.ok():
                return sent
            self.publish_clock(raw.log_time)
            self.publishers_by_topic[raw.topic].publish(raw.data)
            self.played += 1
            sent += 1
        return sent


PROG = 'fastep-replay'


def _parser() -> argparse.ArgumentParser:
    p = Parser(prog=PROG, description='Publish an MCAP recording with its original timing.')
    p.add_argument('file', help='MCAP recording')
    p.add_argument('--rate', type=float, default=1.0, help='playback speed factor (default 1; 2 = twice as fast)')
    p.add_argument('--loop', action='store_true', help='start again at the end, until stopped')
    p.add_argument('--topics', nargs='+', metavar='TOPIC', help='replay only these topics')
    p.add_argument('--clock', nargs='?', type=float, const=100.0, metavar='HZ',
                   help='publish /clock from the log times (HZ ticks per wall second between messages, default 100)')
    p.add_argument('--delay', type=float, default=0.5, help='wall seconds between creating the publishers and '
                   'the first message (default 0.5, for DDS discovery)')
    p.add_argument('--wait-subscribers', type=int, default=0, metavar='N',
                   help='before playing, wait until every volatile topic has N subscribers (at most 30 s)')
    return p


def main(argv: Sequence[str] | None = None) -> int:
    return guard(PROG, lambda: _run(list(sys.argv[1:] if argv is None else argv)))


def _run(argv: list[str]) -> int:
    ros_args: list[str] = []
    if '--ros-args' in argv:
        cut = argv.index('--ros-args')
        argv, ros_args = argv[:cut], argv[cut:]
    parser = _parser()
    args = parser.parse_args(argv)
    if not (math.isfinite(args.rate) and args.rate > 0.0):
        parser.error(f'--rate must be > 0, got {args.rate}')
    if args.clock is not None and not (math.isfinite(args.clock) and 0.0 < args.clock <= MAX_CLOCK_HZ):
        parser.error(f'--clock rate must be > 0 and <= {MAX_CLOCK_HZ:g} Hz, got {args.clock}')
    if not (math.isfinite(args.delay) and 0.0 <= args.delay <= MAX_DELAY):
        parser.error(f'--delay must be >= 0 and <= {MAX_DELAY:g} s, got {args.delay}')
    # A FastepError before ROS starts (unreadable file, unknown or unplayable topic) is guard's one line.
    recording = open_recording(args.file)
    for topic in args.topics or []:
        if topic not in recording.topics:
            raise FastepError(f'topic {topic} is not in {args.file} (it has {", ".join(sorted(recording.topics))})')
        why = unplayable(recording.topics[topic])
        if why:
            raise FastepError(f'topic {topic} cannot be replayed: {why}')
    topics = list(args.topics or [])
    if not topics:
        for topic, info in sorted(recording.topics.items()):
            why = unplayable(info)
            if why:
                print(f'{PROG}: warning: not replaying {topic}: {why}', file=sys.stderr)
            else:
                topics.append(topic)
        if not topics:
            raise FastepError(f'{args.file} holds no topic that can be replayed')
    if args.clock is not None and recording.end_time > MAX_CLOCK_NS:
        raise FastepError(f'--clock: {args.file} has log times past 2^31 s ({recording.end_time * 1e-9:.6g} s), '
                          f'which /clock cannot carry (builtin_interfaces/Time.sec is an int32)')
    if recording.warning():
        print(f'{PROG}: warning: {recording.warning()}', file=sys.stderr)
    recording.on_skip = lambda line: print(f'{PROG}: warning: {line}', file=sys.stderr)

    init_ros(ros_args)
    node = None
    try:
        try:
            node = ReplayNode(recording, topics, args.rate, args.clock)
        except (KeyboardInterrupt, ExternalShutdownException):
            raise
        except Exception as exc:   # e.g. a remap (-r) to a name ROS refuses, found when a publisher is made
            raise FastepError(f'cannot create the publishers: {type(exc).__name__}: '
                              f'{" ".join(str(exc).split())}') from None
        if args.wait_subscribers > 0 and not node.wait_for_subscribers(args.wait_subscribers):
            node.get_logger().warning(f'not every topic has {args.wait_subscribers} subscribers after '
                                      f'{WAIT_TIMEOUT:g} s; playing anyway')
        pause(args.delay)
        while rclpy.ok():
            if node.play_once() == 0 or not args.loop:
                break
        pause(LINGER)
        print(f'{PROG}: played {node.played} messages on {len(node.topics)} topics', file=sys.stderr)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
