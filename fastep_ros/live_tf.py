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

from msg_tools import frames
from msg_tools.tf_buffer import TfBuffer

__all__ = ['LOCALIZATION_QOS', 'TfBroadcaster', 'TfListener']

_DYNAMIC = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)
_STATIC = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)

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
    the executor's thread only (a planning thread reads what they returned)."""

    def __init__(self, node: Node, message_class: Callable[[], type | None] = frames.tf_message_class,
                 dynamic: bool = True) -> None:
        """`dynamic`: follow /tf too (else /tf_static only)."""
        from fastep_ros.polled import PolledSubscription, polled
        self.tree = TfBuffer()
        self.dynamic: PolledSubscription | None = None
        cls = message_class()
        if cls is None:
            return
        static = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                            durability=DurabilityPolicy.TRANSIENT_LOCAL)
        node.create_subscription(cls, frames.TF_STATIC, self.take_static, static)
        if not dynamic:
            return
        self.dynamic = polled(node, cls, frames.TF, _DYNAMIC)
        if self.dynamic is None:
            node.create_subscription(cls, frames.TF, self.take, _DYNAMIC)

    def take(self, msg: Any) -> None:
        """A /tf TFMessage into the buffer."""
        self.tree.add(msg.transforms)

    def take_static(self, msg: Any) -> None:
        """A /tf_static TFMessage into the buffer: its transforms hold at every time."""
        self.tree.add(msg.transforms, static=True)

    def poll(self) -> None:
        """Take what /tf brought since the last lookup."""
        if self.dynamic is not None:
            for msg in self.dynamic.take_all():
                self.take(msg)

    def lookup(self, target: str, source: str) -> frames.Pose2D | None:
        """The newest pose of frame `source` in frame `target` (after taking what /tf brought), or None."""
        self.poll()
        return self.tree.lookup(target, source)

    def lookup_at(self, target: str, source: str, stamp: float | None) -> frames.Pose2D:
        """The pose of frame `source` in frame `target` at `stamp` (s; None: the newest), after taking what /tf
        brought; TfUnavailable (one line) when there is none."""
        self.poll()
        return self.tree.lookup_at(target, source, stamp)

    def destroy(self) -> None:
        if self.dynamic is not None:
            self.dynamic.destroy()
