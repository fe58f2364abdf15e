"""fastep-record: records the fastep topics of the live graph into an MCAP file (a `ros2 bag record` stand-in).

    fastep-record --ros-args -p output:=run.mcap [-p topics:="['/r1/odom', '/map']"] [-p scenario:=table2_s2]
                  [-p use_sim_time:=true]
    python -m fastep_ros.recorder --ros-args -p output:=run.mcap ...     (the same, e.g. from fastep-launch)

Why our own recorder: rosbag2 is not on PyPI. It writes what `ros2 bag record -s mcap` would (msg_tools.mcap_io):
the ROS 2 profile, schemas from the installed .msg files and each topic's offered QoS, so /map and /obstacles
replay latched. Subscriptions are generic (CDR bytes written as received) and take the QoS the publishers offer.
TF (`tf`): `derive` writes /tf and /tf_static from the recorded odometry (msg_tools.frames.TfFromOdometry), `graph`
records the graph's own, `none` none. Crash safety: chunks are flushed every `flush_period`; SIGINT or SIGTERM finish
the file, after a SIGKILL or a full disk (one line, exit 1) `fastep-recover` rewrites what was written.
Which topics, QoS, time stamps, the `~/recording` status: docs/guide.md, "The recorder node"; TF: docs/frames.md.
"""

from __future__ import annotations

import functools
import struct
import sys
import time
from pathlib import Path
from typing import Any, Sequence

from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.clock import Clock, ClockType
from rclpy.logging import LoggingSeverity
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock as ClockMsg

from fastep_core.cli import fail
from fastep_core.errors import FastepError
from fastep_ros.common import (
    PERIOD_RANGE,
    StartupError,
    check_range,
    declare,
    declare_strings,
    guard_clock,
    node_main,
    quiet_at_stop,
)
from fastep_ros.limits import ACK_PERIOD_RANGE
from fastep_ros.lock_step import AckPacer
from msg_tools import cdr, convert, frames, interface
from msg_tools.mcap_writer import COMPRESSIONS, McapWriter, WriteFailedError
from msg_tools.ros2_profile import message_class, qos_profile_to_dict

__all__ = ['RecorderNode', 'RecordingStopped', 'main']


class RecordingStopped(FastepError):
    """The output could not be written (disk full, ...): the node stops, main() exits with code 1."""


_write_failures: list[str] = []   # what stopped a recorder of this process: main() exits 1 instead of 0 or 2
_stopped: list[str] = []          # ... of which the ones not printed yet (stop_writing): exit_code() prints them

FAST_DISCOVERY_PERIOD = 0.05  # wall seconds between the first looks at the graph for topics ...
FAST_LOOKS = 60               # ... so many (3 s), then every discovery_period

# What an empty `topics` parameter records.
_DEFAULT_TOPICS = (', '.join(interface.SHARED_TOPICS) + ' and /<robot>/{' + ', '.join(interface.ROBOT_TOPICS) +
                   '}')


class RecorderNode(Node):
    """Subscribes (raw) to the wanted topics as they appear and writes every message to one MCAP file."""

    def __init__(self, node_name: str = 'recorder', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        guard_clock(self)   # a bad /clock message is ignored, never the end of the node
        output = declare(self, 'output', '', 'MCAP file to write (replaced if it exists; folders are created); '
                         'empty: fastep_<date>_<time>.mcap in the current folder')
        self.wanted = self._declare_topics()
        scenario = declare(self, 'scenario', '', 'optional scenario (YAML file or built-in name): its robots\' '
                           'models, radii, starts and goals go into the `fastep` metadata record for fastep-report')
        chunk_size = declare(self, 'chunk_size', 256 * 1024, 'bytes of messages per chunk (a chunk is the unit a '
                             'crash loses at most)', constraints='>= 1024')
        flush_period = declare(self, 'flush_period', 1.0, 'wall seconds between flushes of the chunk in progress '
                               'to the file (bounds what a SIGKILL loses)',
                               constraints=f'range [{PERIOD_RANGE[0]:g}, {PERIOD_RANGE[1]:g}]')
        compression = declare(self, 'compression', 'zstd', 'chunk compression: zstd | lz4 | none',
                              constraints='zstd | lz4 | none')
        discovery_period = declare(self, 'discovery_period', 0.5, 'wall seconds between looks at the graph for '
                                   'new topics', constraints=f'range [{PERIOD_RANGE[0]:g}, {PERIOD_RANGE[1]:g}]')
        tf_mode = declare(self, 'tf', 'derive', 'TF in the recording: derive (from the recorded odometry; map -> '
                          'odom the identity) | graph (the graph\'s /tf and /tf_static) | none',
                          constraints='derive | graph | none')
        self.depth = declare(self, 'queue_depth', 1000, 'subscription queue depth (messages kept while the '
                             'recorder is busy)', constraints='>= 1')
        clock_ack = declare(self, 'clock_ack', False, 'lock step: say on ~/clock_ack each /clock time recorded, so '
                            'that the clock (its observer_topics) never runs further ahead of the recording than its '
                            'observer_lag (fastep-launch sets it; at a high rtf the recorder fell behind and messages '
                            'were lost)')
        ack_period = declare(self, 'clock_ack_period', 0.0, 'lock step: simulated seconds from one clock_ack to '
                                  'the next, at least (0: every /clock time; fastep-launch: a quarter of the clock\'s '
                                  'observer_lag, so that the clock hears from the recorder a few times per tick it '
                                  'waits for, rather than every tick)', value_range=ACK_PERIOD_RANGE, unit=' s')
        self.acks = AckPacer(ack_period)
        if chunk_size < 1024:
            raise StartupError(f'parameter chunk_size must be >= 1024, got {chunk_size}')
        for name, value in (('flush_period', flush_period), ('discovery_period', discovery_period)):
            check_range(name, value, *PERIOD_RANGE, ' s')
        if compression not in COMPRESSIONS:
            raise StartupError(f'parameter compression must be one of {", ".join(COMPRESSIONS)}, got {compression!r}')
        if tf_mode not in ('derive', 'graph', 'none'):
            raise StartupError(f'parameter tf must be derive, graph or none, got {tf_mode!r}')
        self.tf_from_odometry = frames.TfFromOdometry() if tf_mode == 'derive' else None
        self.record_graph_tf = tf_mode == 'graph'
        if self.depth < 1:
            raise StartupError(f'parameter queue_depth must be >= 1, got {self.depth}')
        metadata = self._scenario_metadata(scenario)

        self.path = Path(output or time.strftime('fastep_%Y%m%d_%H%M%S.mcap'))
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self.writer: McapWriter | None = McapWriter(self.path, chunk_size=chunk_size, compression=compression,
                                                        library='fastep-record')
        except OSError as exc:
            raise StartupError(f'cannot write {self.path}: {exc.strerror or exc}') from None
        except FastepError as exc:   # already names the file
            raise StartupError(str(exc)) from None
        self.writer.add_metadata(interface.METADATA_NAME, metadata)
        self.subscriptions_by_topic: dict[str, Any] = {}
        self.types: dict[str, str] = {}
        self.channels: dict[str, int] = {}
        self.counts: dict[str, int] = {}
        self.status_pub = self.create_publisher(DiagnosticStatus, interface.RECORDING, interface.STATUS_QOS)
        self.ack_pub = self.create_publisher(ClockMsg, interface.CLOCK_ACK, interface.RELIABLE) if clock_ack else None
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        # A launch starts its nodes and the recorder at once, and waits for the recording to hold odometry before
        # the run begins: the first FAST_LOOKS looks come every FAST_DISCOVERY_PERIOD, then every discovery_period.
        self.discovery_period, self.looks = discovery_period, 0
        self.discovery_timer = self.create_timer(min(discovery_period, FAST_DISCOVERY_PERIOD), self.discover,
                                                 clock=steady)
        self.flush_timer = self.create_timer(flush_period, self.flush, clock=steady)
        self.discover()
        what = ', '.join(sorted(self.wanted)) if self.wanted else 'the fastep topics'
        self.get_logger().info(f'recording {what} to {self.path}')

    # ------------------------------------------------------------------------------------------- setup
    def _declare_topics(self) -> set[str]:
        value = declare_strings(self, 'topics', f'topics to record; empty: {_DEFAULT_TOPICS} as they appear')
        out = set()
        for name in value:
            try:
                out.add(self.resolve_topic_name(str(name)))
            except Exception as exc:  # rclpy raises its own validation errors
                raise StartupError(f'parameter topics: {name!r} is not a valid topic name ({exc})') from None
        return out

    @staticmethod
    def _scenario_metadata(source: str) -> dict[str, str]:
        meta = {'source': 'fastep-record', 'time_base': 'receive time on the recorder\'s ROS clock'}
        if not source:
            return meta
        from fastep_core.scenario import load_scenario
        try:
            meta.update(interface.scenario_metadata(load_scenario(source)))
        except FastepError as exc:
            raise StartupError(f'parameter scenario: {exc}') from None
        return meta

    # ------------------------------------------------------------------------------------------- graph
    def wants(self, topic: str) -> bool:
        if self.record_graph_tf and topic in (frames.TF, frames.TF_STATIC):
            return True
        return topic in self.wanted if self.wanted else interface.is_interface_topic(topic)

    @quiet_at_stop
    def discover(self) -> None:
        """Subscribe to every wanted topic now on the graph that is not recorded yet."""
        if self.writer is None:
            return
        self.looks += 1
        if self.looks == FAST_LOOKS:
            self.discovery_timer.timer_period_ns = round(self.discovery_period * 1e9)
        for topic, types in self.get_topic_names_and_types():
            if topic in self.subscriptions_by_topic or not self.wants(topic) or not types:
                continue
            type_name = types[0]
            if len(types) > 1:
                self.get_logger().warning(f'{topic} has several types {types}; recording {type_name}')
            try:
                msg_type = message_class(type_name)
            except FastepError as exc:
                self.get_logger().warning(f'not recording {topic}: {exc}')
                self.subscriptions_by_topic[topic] = None
                continue
            self.types[topic] = type_name
            self.counts[topic] = 0
            self.subscriptions_by_topic[topic] = self.create_subscription(
                msg_type, topic, functools.partial(self.on_message, topic), self.request_qos(topic),
                raw=True)
            self.get_logger().info(f'recording {topic} ({type_name})')

    def offered(self, topic: str) -> list[dict[str, Any]]:
        """The QoS profiles the topic's publishers offer, or what the fastep nodes offer on it."""
        try:
            infos = self.get_publishers_info_by_topic(topic)
        except Exception:  # the graph can change under us; fall back to the interface's defaults
            infos = []
        if infos:
            return [qos_profile_to_dict(info.qos_profile) for info in infos]
        # Nobody publishes it yet (e.g. goal_pose, known from the planner's subscription): what the fastep nodes
        # offer on it, or for a topic outside the interface ROS's usual offer (reliable, volatile, 10 deep).
        if interface.is_interface_topic(topic):
            return interface.offered_qos_profiles(topic)
        return [qos_profile_to_dict(interface.RELIABLE)]

    def request_qos(self, topic: str) -> QoSProfile:
        """Like rosbag2: reliable / transient-local only if every offer is; deep keep-last queue."""
        offers = self.offered(topic)
        reliable = all(o['reliability'] == 'reliable' for o in offers)
        latched = all(o['durability'] == 'transient_local' for o in offers)
        return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=self.depth,
                          reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)

    # ------------------------------------------------------------------------------------------- writing
    @quiet_at_stop   # (a launch stopped at its start: a first message's status publish met the shut-down context)
    def on_message(self, topic: str, data: bytes) -> None:
        writer = self.writer
        if writer is None:
            return
        now = self.get_clock().now().nanoseconds
        try:
            channel = self.channels.get(topic)
            if channel is None:  # registered at the first message, when the publishers' QoS is known
                channel = self.channels[topic] = writer.add_channel(topic, self.types[topic], self.offered(topic))
            writer.write_raw(channel, data, now, now)
            if topic == interface.CLOCK and self.ack_pub is not None and len(data) >= 12:
                # A CDR Clock: 4 bytes of encapsulation, then int32 sec, uint32 nanosec.
                sec, nanosec = struct.unpack_from('<iI' if data[1] == 1 else '>iI', data, 4)
                self.acknowledge(sec, nanosec)
            if self.tf_from_odometry is not None:
                for tf_topic, tf_data in self.tf_from_odometry.take(topic, data):
                    writer.write(tf_topic, tf_data, now, now, type_name=frames.TF_TYPE,
                                 qos=frames.TF_QOS if tf_topic == frames.TF else frames.TF_STATIC_QOS)
        except WriteFailedError as exc:
            self.stop_writing(exc)
            return   # stopping: nothing more to publish
        self.counts[topic] += 1
        if self.counts[topic] == 1:
            self.publish_status()

    def acknowledge(self, sec: int, nanosec: int) -> None:
        """Say on clock_ack that the /clock time (sec, nanosec) is recorded, as AckPacer says (once every
        clock_ack_period; a time said again at once)."""
        if self.acks.due(sec + nanosec * 1e-9):
            assert self.ack_pub is not None
            self.ack_pub.publish(cdr.clock_cdr((sec, nanosec)))

    @quiet_at_stop
    def flush(self) -> None:
        if self.writer is not None:
            try:
                self.writer.flush()
            except WriteFailedError as exc:
                self.stop_writing(exc)
                return
            self.publish_status()

    def stop_writing(self, exc: WriteFailedError) -> None:
        """The file cannot be written (disk full, ...): close it as it is and end the node with one line."""
        writer, self.writer = self.writer, None
        if writer is not None:
            try:
                writer.finish()   # only closes the file: the writer is broken
            except WriteFailedError:
                pass
        kept = sum(self.counts.values())
        message = (f'{exc}; recording stopped after {kept} messages: {self.path} keeps the chunks written before '
                   f'(fastep-recover rewrites them as a complete file)')
        _write_failures.append(message)
        _stopped.append(message)
        # The process stops (node_main's spin ends with the context) and exit_code() says why in one line. Raised
        # from this callback, the EventsExecutor logged it as FATAL with where it was raised, besides the line.
        self.context.try_shutdown()

    def publish_status(self) -> None:
        """What was received so far: the file, and the message count of every topic that delivered."""
        values: dict[str, Any] = {'file': str(self.path)}
        values.update((topic, count) for topic, count in sorted(self.counts.items()) if count)
        self.status_pub.publish(convert.make_status(self.get_fully_qualified_name(), 'recording', 'ok', values))

    def close(self) -> None:
        """Finish the file (summary, footer). Safe to call twice."""
        writer, self.writer = self.writer, None
        if writer is None:
            return
        try:
            writer.finish()
        except WriteFailedError as exc:   # the summary did not fit on the disk: one line, exit 1
            message = (f'{exc}; {self.path} has no summary: the chunks written before are readable (fastep-recover '
                       f'rewrites them as a complete file)')
            _write_failures.append(message)
            print(f'fastep-record: error: {message}', file=sys.stderr)
            return
        text = f'wrote {sum(self.counts.values())} messages on {len(self.channels)} topics to {self.path}'
        logger = self.get_logger()
        if self.context.ok():
            logger.info(text)
        elif logger.get_effective_level() <= LoggingSeverity.INFO:  # after Ctrl-C /rosout is gone
            print(f'[INFO] [{self.get_name()}]: {text}', file=sys.stderr)

    def destroy_node(self) -> None:
        self.close()
        super().destroy_node()


def exit_code(code: int, prog: str = 'fastep-record') -> int:
    """The exit code of a process that ran recorders, after node_main returned `code`: a write failure (printed here
    once, or by close()) is not bad input: exit 1, not 2 (or 0)."""
    while _stopped:
        fail(prog, _stopped.pop(0))
    return 1 if _write_failures else code


def main(args: Sequence[str] | None = None) -> int:
    return exit_code(node_main('fastep-record', RecorderNode, args))


if __name__ == '__main__':
    raise SystemExit(main())
