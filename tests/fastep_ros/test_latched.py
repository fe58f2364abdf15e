"""fastep_ros.latched: a latched topic's subscription made anew when a new publisher delivers nothing."""

from __future__ import annotations

import time
from typing import Any

from fastep_ros.latched import Arrivals, LatchedSubscription


def test_a_publisher_heard_from_in_time_changes_nothing() -> None:
    a = Arrivals(wait=3.0)
    assert not a.look(1, 0.0)          # the map server appeared ...
    a.heard(0.1)                       # ... and its latched message came
    assert not any(a.look(1, t) for t in (1.0, 5.0, 60.0))


def test_a_publisher_that_delivers_nothing_gets_one_new_subscription() -> None:
    a = Arrivals(wait=3.0)
    assert not a.look(1, 0.0) and not a.look(1, 2.9)
    assert a.look(1, 3.0)              # subscribe again
    # The new subscription matches the same publisher again: not a new one, so no second renewal.
    assert not any(a.look(n, t) for n, t in ((0, 3.1), (1, 3.5), (1, 10.0), (1, 100.0)))


def test_a_message_taken_before_the_looks_that_see_its_publisher_counts() -> None:
    """The matched count is updated on a DDS thread: the message can be taken first, a look or two before."""
    a = Arrivals(wait=3.0)
    a.heard(0.0)
    assert not a.look(0, 0.25) and not a.look(1, 0.5) and not a.look(1, 10.0)


def test_a_message_heard_long_before_a_publisher_appeared_is_not_its_message() -> None:
    a = Arrivals(wait=3.0)
    a.heard(0.0)
    assert not a.look(1, 5.0)
    assert a.look(1, 8.0)


def test_a_restarted_publisher_is_waited_for_again() -> None:
    a = Arrivals(wait=3.0)
    a.look(1, 0.0)
    a.heard(0.1)
    assert not a.look(0, 10.0)         # killed
    assert not a.look(1, 11.0)         # started again: appeared
    assert a.look(1, 14.0)             # its message did not come


def test_a_publisher_gone_while_rematching_does_not_stop_the_watch() -> None:
    a = Arrivals(wait=3.0)
    a.look(2, 0.0)
    assert a.look(2, 3.0)
    assert not a.look(1, 3.5)          # one of the two did not come back
    assert not a.look(1, 6.0)          # rematching given up after `wait`
    assert not a.look(2, 7.0)          # a new publisher ...
    assert a.look(2, 10.0)             # ... that delivers nothing


def test_a_latched_publisher_that_published_nothing_is_subscribed_to_once_more(context: Any) -> None:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import String

    from msg_tools.interface import OBSTACLES, offered_qos

    node = rclpy.create_node('latched_test', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        got: list[Any] = []
        sub = LatchedSubscription(node, String, 'world', got.append, offered_qos(OBSTACLES), wait=0.3)
        first = sub.subscription
        node.create_publisher(String, 'world', offered_qos(OBSTACLES))   # latched, publishes nothing (yet)
        deadline = time.monotonic() + 10.0
        while sub.renewed == 0 and time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
            sub.look()
        assert sub.renewed == 1 and sub.subscription is not first
        assert node.count_subscribers('world') == 1   # the old subscription is gone
        for _ in range(40):                            # matched again: not a new publisher, no more renewals
            executor.spin_once(timeout_sec=0.05)
            sub.look()
        assert sub.renewed == 1
    finally:
        executor.shutdown()
        node.destroy_node()


def test_a_latched_message_that_arrives_is_taken_once_without_renewal(context: Any) -> None:
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from std_msgs.msg import String

    from msg_tools.interface import OBSTACLES, offered_qos

    node = rclpy.create_node('latched_test', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        node.create_publisher(String, 'world', offered_qos(OBSTACLES)).publish(String(data='two circles'))
        got: list[Any] = []
        sub = LatchedSubscription(node, String, 'world', got.append, offered_qos(OBSTACLES), wait=0.5)
        deadline = time.monotonic() + 1.5
        while time.monotonic() < deadline:
            executor.spin_once(timeout_sec=0.05)
            sub.look()
        assert sub.renewed == 0, got
        assert [m.data for m in got] == ['two circles']
    finally:
        executor.shutdown()
        node.destroy_node()
