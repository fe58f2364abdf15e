"""A subscription that no executor wakes up for: its newest message is taken when the node needs it.

A planner follows every other robot's odometry, published at the plants' integration rate (50 Hz), but uses it
only on its control tick (20 Hz). With a callback subscription each message costs an executor wake-up, a
deserialisation and a Python call in every planner, N (N - 1) times per period for N robots: the cost of a graph
grew like N^2 (docs/benchmarks.md). A PolledSubscription is an rcl subscription on the node that is not handed
to the node's executor (it is not in Node.subscriptions): the middleware keeps the newest message (keep-last 1)
and take_latest() deserialises only that one, when asked. The topic, type and QoS on the graph are those of an
ordinary subscription.

rclpy has no public API for it: this builds the subscription object as Node.create_subscription does
(rclpy's _rclpy.Subscription). Should that change, polled() returns None and the caller subscribes as before.
"""

from __future__ import annotations

from typing import Any

from rclpy.node import Node
from rclpy.qos import QoSProfile

__all__ = ['PolledSubscription', 'polled']


class PolledSubscription:
    """The newest message of a topic, taken on demand (take_latest); destroy() before the node is destroyed."""

    def __init__(self, node: Node, msg_type: Any, topic: str, qos: QoSProfile, raw: bool = False) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation
        from rclpy.type_support import check_is_valid_msg_type

        check_is_valid_msg_type(msg_type)
        self.msg_type = msg_type
        self.topic = topic
        self.raw = raw   # take the serialised bytes (msg_tools.cdr reads them), not a message
        with node.handle:
            self.handle: Any = rclpy_implementation.Subscription(node.handle, msg_type, topic,
                                                                 qos.get_c_qos_profile())

    def take_latest(self) -> Any:
        """The newest message received since the last call (its bytes if raw), or None."""
        latest = None
        while True:
            taken = self.handle.take_message(self.msg_type, self.raw)
            if taken is None:
                return latest
            latest = taken[0]

    def take_all(self) -> list[Any]:
        """Every message received since the last call, oldest first (their bytes if raw)."""
        out = []
        while (taken := self.handle.take_message(self.msg_type, self.raw)) is not None:
            out.append(taken[0])
        return out

    def destroy(self) -> None:
        self.handle.destroy_when_not_in_use()


def polled(node: Node, msg_type: Any, topic: str, qos: QoSProfile, raw: bool = False) -> PolledSubscription | None:
    """A PolledSubscription, or None if rclpy cannot make one (the caller then subscribes with a callback)."""
    try:
        return PolledSubscription(node, msg_type, topic, qos, raw)
    except (ImportError, AttributeError, TypeError):
        return None
