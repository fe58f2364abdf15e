"""What a node publishes, as messages, for tests that take a publisher's place."""

from __future__ import annotations

from typing import Any, Callable

from rclpy.serialization import deserialize_message


def keep_published(publisher: Any, keep: Callable[[Any], Any]) -> None:
    """Replace `publisher.publish` by `keep` (e.g. a list's append), handed messages: nodes send their high-rate
    messages as bytes (msg_tools.cdr), decoded here into the publisher's type."""
    msg_type = publisher.msg_type

    def publish(msg: Any) -> None:
        keep(deserialize_message(msg, msg_type) if isinstance(msg, bytes) else msg)

    publisher.publish = publish
