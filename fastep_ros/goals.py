"""The planner's one goal subscription: volatile publishers (RViz's 2D Goal Pose, `ros2 topic pub`) and latched
ones (fastep-launch) alike, without an incompatible-QoS warning on either side.

DDS matches a transient-local subscription only with transient-local publishers, while a volatile one receives
no history: a planner started after a latched goal was sent would never get it (fastep-launch relies on it to
resume a restarted planner). QoSDurabilityPolicy.BEST_AVAILABLE resolves only once, at creation, so a volatile
publisher discovered later is still incompatible.

So the durability is chosen here at every look at the graph (the planner's 0.25 s wall tick) by the rule
`wanted`: volatile, except while catching up with the history of latched publishers and while no volatile
publisher is known. A catch-up ends when those publishers have each sent their goal, or after CATCH_UP wall
seconds. When the rule changes the durability the subscription is replaced, the new one first so no goal falls
between. Details: docs/robots_and_goals.md.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Iterable

from geometry_msgs.msg import PoseStamped
from rclpy import qos
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSPolicyKind, QoSProfile, ReliabilityPolicy

from msg_tools import interface

if TYPE_CHECKING:
    from rclpy.node import Node

__all__ = ['CATCH_UP', 'DEPTH', 'CatchUp', 'GoalSubscription', 'goal_qos']

CATCH_UP = 5.0   # wall seconds a transient-local subscription waits at most for a latched publisher's history
DEPTH = 10

Gid = tuple[int, ...]


def goal_qos(durability: DurabilityPolicy) -> QoSProfile:
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=DEPTH, reliability=ReliabilityPolicy.RELIABLE,
                      durability=durability)


@dataclass
class CatchUp:
    """Which latched publishers' histories are still to be received; what durability that asks for. No ROS."""

    timeout: float = CATCH_UP
    pending: dict[Gid, float | None] = field(default_factory=dict)   # publisher -> when catching up began
    done: set[Gid] = field(default_factory=set)
    heard: int = 0               # goals received while catching up
    durability: DurabilityPolicy = DurabilityPolicy.VOLATILE

    def look(self, publishers: Iterable[tuple[Gid, bool]], now: float) -> DurabilityPolicy:
        """The publishers now on the graph ((gid, latched) pairs): the durability the subscription should have."""
        latched: set[Gid] = set()
        volatile = False
        for gid, is_latched in publishers:
            if is_latched:
                latched.add(gid)
            else:
                volatile = True
        self.done &= latched
        self.pending = {gid: since for gid, since in self.pending.items() if gid in latched}
        for gid in latched - self.done - set(self.pending):
            self.pending[gid] = now if self.durability == DurabilityPolicy.TRANSIENT_LOCAL else None
        if self.durability == DurabilityPolicy.TRANSIENT_LOCAL:
            caught_up = self.heard >= len(self.pending)
            for gid, since in list(self.pending.items()):
                if caught_up or (since is not None and now - since >= self.timeout):
                    del self.pending[gid]
                    self.done.add(gid)
        wanted = DurabilityPolicy.TRANSIENT_LOCAL if self.pending and not volatile else DurabilityPolicy.VOLATILE
        self.switch(wanted, now)
        return wanted

    def switch(self, durability: DurabilityPolicy, now: float) -> None:
        if durability == self.durability:
            return
        self.durability = durability
        self.heard = 0
        if durability == DurabilityPolicy.TRANSIENT_LOCAL:   # the clock of every pending publisher starts now
            self.pending = dict.fromkeys(self.pending, now)

    def heard_goal(self) -> None:
        if self.durability == DurabilityPolicy.TRANSIENT_LOCAL:
            self.heard += 1


class GoalSubscription:
    """The node's subscription on `goal_pose`, re-made with the durability CatchUp asks for."""

    def __init__(self, node: Node, callback: Callable[[PoseStamped], None], topic: str = interface.GOAL_POSE,
                 timeout: float = CATCH_UP) -> None:
        self.node = node
        self.callback = callback
        self.catch_up = CatchUp(timeout)
        self.subscription = self._subscribe(DurabilityPolicy.VOLATILE, topic)
        self.topic = self.subscription.topic_name

    def _subscribe(self, durability: DurabilityPolicy, topic: str) -> Any:
        events = SubscriptionEventCallbacks(incompatible_qos=self.on_incompatible)
        return self.node.create_subscription(PoseStamped, topic, self.on_goal, goal_qos(durability),
                                             event_callbacks=events)

    @property
    def durability(self) -> DurabilityPolicy:
        return self.catch_up.durability

    def look(self) -> None:
        """Look at the goal's publishers on the graph; re-subscribe if the durability wanted changed."""
        before = self.catch_up.durability
        try:
            infos = self.node.get_publishers_info_by_topic(self.topic)
        except Exception as exc:   # the graph can change under us: look again next time
            self.node.get_logger().debug(f'graph look at {self.topic} failed: {exc}')
            return
        publishers = [(tuple(i.endpoint_gid), i.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL)
                      for i in infos]
        wanted = self.catch_up.look(publishers, time.monotonic())
        if wanted != before:
            self._replace(wanted)

    def _replace(self, durability: DurabilityPolicy) -> None:
        old, self.subscription = self.subscription, self._subscribe(durability, self.topic)
        self.node.destroy_subscription(old)
        self.node.get_logger().debug(f'{self.topic}: subscription now {durability.name.lower()}')

    def on_goal(self, msg: PoseStamped) -> None:
        self.catch_up.heard_goal()
        self.callback(msg)

    def destroy(self) -> None:
        """Destroy the subscription (the one made last)."""
        self.node.destroy_subscription(self.subscription)

    def on_incompatible(self, info: Any) -> None:
        """A volatile publisher met the transient-local subscription (between two looks): become volatile now.
        Any other incompatibility (a best-effort publisher: goals are taken reliably) is warned about."""
        if self.catch_up.durability != DurabilityPolicy.TRANSIENT_LOCAL or \
                int(info.last_policy_kind) != QoSPolicyKind.DURABILITY:
            policy = qos.qos_policy_name_from_kind(info.last_policy_kind)
            self.node.get_logger().warning(f'{self.topic}: a publisher offers an incompatible QoS ({policy}); its '
                                           'goals are not received (goals are taken reliably)',
                                           throttle_duration_sec=5.0)
            return
        self.node.get_logger().info(f'{self.topic}: a volatile publisher appeared while catching up with latched '
                                    'goals; the subscription is volatile again')
        self.catch_up.switch(DurabilityPolicy.VOLATILE, time.monotonic())
        self._replace(DurabilityPolicy.VOLATILE)
