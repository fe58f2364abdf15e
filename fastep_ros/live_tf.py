"""Live TF for the nodes: /tf and /tf_static (tf2_msgs/msg/TFMessage) where tf2_msgs is importable.

The registry's ROS wheels have no tf2_msgs: make builds it into .venv (interfaces/build.sh), a ROS install has
it. A node publishes TF with the QoS of tf2_ros's broadcasters; where tf2_msgs is missing it says so once in its
log and goes on (recordings carry TF anyway: fastep-record and fastep-sim --mcap write it with rosbags,
msg_tools.frames). The frame algebra itself is msg_tools.frames.
"""

from __future__ import annotations

from typing import Any, Callable, Sequence

from geometry_msgs.msg import TransformStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from fastep_ros.limits import TF_MESSAGE_TRANSFORMS, TF_POLL_TRANSFORMS, TF_STAMP_AHEAD
from msg_tools import frames, tf_cdr
from msg_tools.tf_buffer import TfBuffer

__all__ = ['LOCALIZATION_QOS', 'TfBroadcaster', 'TfListener']

_DYNAMIC = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)
_STATIC = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)

_BYTES_PER_TRANSFORM = 128   # a TransformStamped in CDR with frame names of ~20 characters each

# A localization pose (AMCL's amcl_pose is reliable and transient-local): best available matches every publisher
# without incompatible-QoS warnings, and takes the last pose of a transient-local one at once.
LOCALIZATION_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.BEST_AVAILABLE,
                              durability=DurabilityPolicy.BEST_AVAILABLE)


class TfBroadcaster:
    """Publishes transforms on /tf and /tf_static for a node, or (no tf2_msgs here) nothing, said once.

    `message_class` is for tests: frames.tf_message_class() (None when tf2_msgs is not importable) by default."""

    def __init__(self, node: Node, message_class: Callable[[], type | None] = frames.tf_message_class) -> None:
        self.node = node
        self.cls = message_class()
        self.static: list[TransformStamped] = []
        self.dynamic_pub: Any = None
        self.static_pub: Any = None
        if self.cls is None:
            node.get_logger().info('tf2_msgs is not installed: not publishing /tf or /tf_static (recordings made '
                                   'with fastep-record or fastep-sim --mcap carry them)')
            return
        self.dynamic_pub = node.create_publisher(self.cls, frames.TF, _DYNAMIC)
        self.static_pub = node.create_publisher(self.cls, frames.TF_STATIC, _STATIC)

    @property
    def available(self) -> bool:
        return self.cls is not None

    def destroy(self) -> None:
        """Destroy the publishers."""
        for publisher in (self.dynamic_pub, self.static_pub):
            if publisher is not None:
                self.node.destroy_publisher(publisher)
        self.dynamic_pub = self.static_pub = None

    def send(self, transforms: Sequence[TransformStamped]) -> None:
        if self.dynamic_pub is not None and self.cls is not None:
            self.dynamic_pub.publish(self.cls(transforms=list(transforms)))

    def send_static(self, transforms: Sequence[TransformStamped]) -> None:
        """Add static transforms: like tf2_ros's static broadcaster, one latched message holds all of them."""
        self.static.extend(transforms)
        if self.static_pub is not None and self.cls is not None:
            self.static_pub.publish(self.cls(transforms=list(self.static)))


class TfListener:
    """What /tf and /tf_static say, in a msg_tools.tf_buffer.TfBuffer, for lookups (the planner's goals in other
    frames, map -> odom, where its scans were taken); nothing where tf2_msgs is missing. /tf_static is subscribed
    to (latched, rare); /tf is polled, taken when a lookup needs it: every robot's odometry transform at 50 Hz, N
    times N on a graph, costs no executor wake-up. Lookups take what /tf brought into the buffer: call them on
    the executor's thread only (a planning thread reads what they returned).

    Both are taken as bytes and read without building messages (msg_tools.tf_cdr), with this node's clock
    when they came (the buffer honours stamps: msg_tools.tf_buffer). The executor's work is bounded: a message of
    more than TF_MESSAGE_TRANSFORMS transforms, or any beyond TF_POLL_TRANSFORMS read whole since the last lookup,
    is cut to the transforms of the frames lookups asked for (the buffer's `needed`) and their parents, with a
    throttled warning; a transform stamped more than TF_STAMP_AHEAD ahead of the clock is refused, and frames
    dropped for newer ones (the buffer keeps FRAMES_MAX) are said, likewise."""

    WARN_PERIOD = 10.0   # s between two warnings of one kind (a flood would say one a message)

    def __init__(self, node: Node, message_class: Callable[[], type | None] = frames.tf_message_class,
                 dynamic: bool = True) -> None:
        """`dynamic`: follow /tf too (else /tf_static only)."""
        from fastep_ros.polled import PolledSubscription, polled
        self.node = node
        self.tree = TfBuffer()
        self.dynamic: PolledSubscription | None = None
        self.subscriptions: list[Any] = []   # the callback ones
        self.cls = message_class()
        self.cut = 0        # messages cut to the needed frames
        self._said = (0, 0)   # the buffer's refused_ahead and dropped when they were last said
        if self.cls is None:
            return
        static = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                            durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.subscriptions.append(node.create_subscription(self.cls, frames.TF_STATIC, self.take_static, static,
                                                           raw=True))
        if not dynamic:
            return
        self.dynamic = polled(node, self.cls, frames.TF, _DYNAMIC, raw=True)
        if self.dynamic is None:
            self.subscriptions.append(node.create_subscription(self.cls, frames.TF, self.take, _DYNAMIC, raw=True))

    def now(self) -> float:
        return self.node.get_clock().now().nanoseconds * 1e-9

    def take(self, msg: Any) -> None:
        """A /tf TFMessage (or its bytes) into the buffer, read whole if it holds at most TF_MESSAGE_TRANSFORMS
        transforms, else cut."""
        self._take(msg, False, TF_MESSAGE_TRANSFORMS)

    def take_static(self, msg: Any) -> None:
        """A /tf_static TFMessage (or its bytes) into the buffer: its transforms hold at every time."""
        self._take(msg, True, TF_MESSAGE_TRANSFORMS)

    def _take(self, msg: Any, static: bool, budget: int) -> int:
        """A message (or its bytes) into the buffer, read whole if it holds at most `budget` transforms (and
        TF_MESSAGE_TRANSFORMS), else cut; returns the transforms read whole."""
        topic = frames.TF_STATIC if static else frames.TF
        now, budget = self.now(), min(budget, TF_MESSAGE_TRANSFORMS)
        logger = self.node.get_logger()
        if isinstance(msg, bytes):
            count = tf_cdr.transform_count(msg)
            try:
                taken = self.tree.add_cdr(msg, static, now, TF_STAMP_AHEAD,
                                          whole=count is not None and count <= budget)
            except ValueError as exc:
                logger.warning(f'ignoring a {topic} message: {exc}', throttle_duration_sec=self.WARN_PERIOD)
                return 0
            if taken is None:   # not little-endian CDR: rclpy deserialises it, unless it is too big
                if len(msg) > TF_MESSAGE_TRANSFORMS * _BYTES_PER_TRANSFORM:
                    logger.warning(f'ignoring a {topic} message of {len(msg)} bytes in big-endian CDR (more than '
                                   f'{TF_MESSAGE_TRANSFORMS} transforms are not read whole)',
                                   throttle_duration_sec=self.WARN_PERIOD)
                    return 0
                from rclpy.serialization import deserialize_message
                msg = deserialize_message(msg, self.cls)
            else:
                if not taken.whole:
                    self._said_cut(topic, taken.count, taken.read, taken.searched)
                self._say_refused(topic)
                return taken.read if taken.whole else 0
        transforms = msg.transforms
        if len(transforms) > budget:   # a message built already (a test, a stand-in class): cut by name
            needed = self.tree.needed
            cut = [t for t in transforms if t.child_frame_id.lstrip('/') in needed]
            self._said_cut(topic, len(transforms), len(cut), tuple(needed))
            transforms, read = cut, 0
        else:
            read = len(transforms)
        self.tree.add(transforms, static, now, TF_STAMP_AHEAD)
        self._say_refused(topic)
        return read

    def _said_cut(self, topic: str, count: int, read: int, searched: tuple[str, ...]) -> None:
        self.cut += 1
        why = f'more than the {TF_MESSAGE_TRANSFORMS} read whole' if count > TF_MESSAGE_TRANSFORMS else \
            f'past the {TF_POLL_TRANSFORMS} read whole per lookup'
        names = ', '.join(searched[:8]) + (', ...' if len(searched) > 8 else '') if searched else 'none yet'
        self.node.get_logger().warning(
            f'{topic}: a message of {count} transforms ({why}): took only the {read} of the frames this node '
            f'looks up ({names}); {self.cut} messages cut so far', throttle_duration_sec=self.WARN_PERIOD)

    def _say_refused(self, topic: str) -> None:
        ahead, dropped = self.tree.refused_ahead, self.tree.dropped
        if (ahead, dropped) == self._said:
            return
        if ahead != self._said[0]:
            self.node.get_logger().warning(
                f'{topic}: {ahead} transforms stamped more than {TF_STAMP_AHEAD:g} s ahead of this node\'s clock '
                f'refused so far', throttle_duration_sec=self.WARN_PERIOD)
        if dropped != self._said[1]:
            self.node.get_logger().warning(
                f'TF: more than {self.tree.max_frames} frames: {dropped} dropped so far, the least recently '
                f'updated first (never one this node looks up)', throttle_duration_sec=self.WARN_PERIOD)
        self._said = (ahead, dropped)

    def poll(self) -> None:
        """Take what /tf brought since the last lookup: the first TF_POLL_TRANSFORMS transforms read whole, the
        messages beyond cut to the frames lookups ask for. Each message is read as it is taken (the queue holds
        up to 100)."""
        if self.dynamic is None:
            return
        handle, cls, budget = self.dynamic.handle, self.dynamic.msg_type, TF_POLL_TRANSFORMS
        while (taken := handle.take_message(cls, True)) is not None:
            budget -= self._take(taken[0], False, budget)

    def lookup(self, target: str, source: str) -> frames.Pose2D | None:
        """The newest pose of frame `source` in frame `target` (after taking what /tf brought), or None."""
        self.tree.need(target, source)   # before the poll: what it takes is searched for them
        self.poll()
        return self.tree.lookup(target, source)

    def lookup_stamped(self, target: str, source: str) -> tuple[frames.Pose2D, float] | None:
        """lookup, with the stamp it holds at (s; inf when every edge between the frames is static), or None."""
        self.tree.need(target, source)   # before the poll: what it takes is searched for them
        self.poll()
        return self.tree.lookup_stamped(target, source)

    def lookup_at(self, target: str, source: str, stamp: float | None) -> frames.Pose2D:
        """The pose of frame `source` in frame `target` at `stamp` (s; None: the newest), after taking what /tf
        brought; TfUnavailable (one line) when there is none."""
        self.tree.need(target, source)   # before the poll: what it takes is searched for them
        self.poll()
        return self.tree.lookup_at(target, source, stamp)

    def destroy(self) -> None:
        """Destroy the subscriptions (the polled one too, which the node does not know)."""
        if self.dynamic is not None:
            self.dynamic.destroy()
            self.dynamic = None
        for subscription in self.subscriptions:
            self.node.destroy_subscription(subscription)
        self.subscriptions.clear()
