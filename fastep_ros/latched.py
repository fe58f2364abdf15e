"""A subscription to a latched (transient-local) topic that subscribes again when a new publisher's history does
not arrive.

A latched publisher (fastep-map's /obstacles and /map, Nav2's map_server) publishes once: a later subscription
gets the message from the writer's history. Fast DDS sometimes never delivers that history to a reader
(eProsima/Fast-DDS#3822); a planner would then drive without a restarted map server's obstacles. A new reader
is matched afresh and is sent the history again.

So when the subscription's matched publishers grow and no message comes within RESEND_AFTER wall seconds, the
subscription is made anew (the new one first; a message taken twice does not matter to a latched world's
handler), once per appearance of a publisher. Looking costs one matched count, no graph query.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.qos import QoSProfile

__all__ = ['RESEND_AFTER', 'Arrivals', 'LatchedSubscription']

RESEND_AFTER = 6.0
"""Wall seconds a newly matched latched publisher has to deliver its history: two of Fast DDS's heartbeat periods
(3 s). A first delivery lost in the race of the two ends' matching is repaired at the writer's next heartbeat
(a map restart reached the planner after 1.4 or 3.4 s, nothing between); with 3 s here, 2 of 29 restarts
renewed the subscription just before that repair."""


@dataclass
class Arrivals:
    """Whether a subscription should be made anew, from its matched publisher count over time. No ROS."""

    wait: float = RESEND_AFTER
    matched: int = 0                     # publishers matched at the last look
    waiting_since: float | None = None   # when a publisher appeared that has not been heard from since
    rematching: tuple[int, float] | None = None   # after subscribing again: the old one's count, until when
    last_heard: float | None = None      # when a message last came (it may come before the look that sees its
                                         # publisher matched: the matched count is updated on another thread)

    def look(self, matched: int, now: float) -> bool:
        """The matched count now; True when the subscription is to be made anew (then assumed done)."""
        if self.rematching is not None:   # the new subscription matching the old one's publishers again
            count, until = self.rematching
            if matched >= count or now >= until:   # all of them, or one is gone
                self.rematching = None
            self.matched = matched
            return False
        heard_lately = self.last_heard is not None and now - self.last_heard < self.wait
        if matched > self.matched and self.waiting_since is None and not heard_lately:
            self.waiting_since = now
        self.matched = matched
        if self.waiting_since is None or now - self.waiting_since < self.wait:
            return False
        self.waiting_since, self.rematching = None, (matched, now + self.wait)
        return True

    def heard(self, now: float) -> None:
        """A message arrived: the publishers that appeared (up to `wait` seconds ago) have been heard from."""
        self.waiting_since, self.last_heard = None, now


class LatchedSubscription:
    """node.create_subscription(msg_type, topic, callback, qos), made anew when Arrivals says so; call look()
    periodically (the planner: every wall tick)."""

    def __init__(self, node: Node, msg_type: Any, topic: str, callback: Callable[[Any], None], qos: QoSProfile,
                 wait: float = RESEND_AFTER) -> None:
        self.node, self.msg_type, self.callback, self.qos = node, msg_type, callback, qos
        self.arrivals = Arrivals(wait)
        self.subscription = node.create_subscription(msg_type, topic, self.on_message, qos)
        self.topic = self.subscription.topic_name
        self.renewed = 0   # subscriptions made anew

    def look(self) -> None:
        if not self.arrivals.look(self.subscription.get_publisher_count(), time.monotonic()):
            return
        old, self.subscription = self.subscription, self.node.create_subscription(
            self.msg_type, self.topic, self.on_message, self.qos)
        self.node.destroy_subscription(old)
        self.renewed += 1
        self.node.get_logger().warning(f'{self.topic}: a publisher matched {self.arrivals.wait:g} s ago has '
                                       'delivered nothing; subscribing again to be sent its latched message')

    def on_message(self, msg: Any) -> None:
        self.arrivals.heard(time.monotonic())
        self.callback(msg)

    def destroy(self) -> None:
        """Destroy the subscription (the one made last)."""
        self.node.destroy_subscription(self.subscription)
