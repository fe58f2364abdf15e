"""`/diagnostics` (diagnostic_msgs/DiagnosticArray), as Nav2 nodes publish it through diagnostic_updater.

One DiagnosticStatus per task of the node, named `<node>: <task>` with the node's fully qualified name (without
the leading slash, e.g. `r1/planner: odometry`, so that the robots of a graph stay apart), hardware_id the robot
(the namespace; the node name in the root namespace), published once a wall second. Levels are
DiagnosticStatus's: OK, WARN, ERROR, and STALE for data that stopped coming (stale odometry). This is besides
the planner's `<ns>/status`, which the launcher follows.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.lifecycle import LifecycleNode
from rclpy.node import Node

from fastep_ros.lifecycle import destroy_publisher
from msg_tools.interface import RELIABLE

__all__ = ['DIAGNOSTICS', 'Diagnostics', 'Task', 'level_name']

DIAGNOSTICS = '/diagnostics'
PERIOD = 1.0   # wall seconds between arrays (diagnostic_updater's default period)

_LEVEL_NAMES = {DiagnosticStatus.OK: 'OK', DiagnosticStatus.WARN: 'WARN', DiagnosticStatus.ERROR: 'ERROR',
                DiagnosticStatus.STALE: 'STALE'}


def level_name(level: bytes) -> str:
    return _LEVEL_NAMES.get(level, repr(level))


@dataclass
class Task:
    """One status of the array: the task's name, level, message and values."""

    task: str
    level: bytes
    message: str
    values: dict[str, Any] = field(default_factory=dict)


def _text(value: Any) -> str:
    if isinstance(value, float):
        return f'{value:.6g}'
    if isinstance(value, (tuple, list)):
        return ' '.join(_text(v) for v in value)
    return '' if value is None else str(value)


class Diagnostics:
    """The node's /diagnostics publisher (`managed`: a lifecycle publisher, on only while its node is active)."""

    def __init__(self, node: Node, managed: bool = False) -> None:
        self.node = node
        self.publisher = node.create_lifecycle_publisher(DiagnosticArray, DIAGNOSTICS, RELIABLE) \
            if managed and isinstance(node, LifecycleNode) else node.create_publisher(DiagnosticArray, DIAGNOSTICS,
                                                                                      RELIABLE)
        self.prefix = node.get_fully_qualified_name().lstrip('/')
        namespace = node.get_namespace().strip('/')
        self.hardware_id = namespace or node.get_name()

    def publish(self, tasks: list[Task]) -> None:
        array = DiagnosticArray()
        array.header.stamp = self.node.get_clock().now().to_msg()
        for task in tasks:
            status = DiagnosticStatus(level=task.level, name=f'{self.prefix}: {task.task}', message=task.message,
                                      hardware_id=self.hardware_id)
            status.values = [KeyValue(key=str(k), value=_text(v)) for k, v in task.values.items()]
            array.status.append(status)
        self.publisher.publish(array)

    def destroy(self) -> None:
        """Destroy the publisher."""
        destroy_publisher(self.node, self.publisher)
