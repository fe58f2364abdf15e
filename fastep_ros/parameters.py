"""Parameters that change while a node runs, and the check for `-p` overrides no parameter takes.

A node declares its parameters with fastep_ros.common.declare (ranges in the descriptor, which rclpy enforces on
every set), the tunable ones with read_only=False, and then hands their names to DynamicParameters with a function
that validates and applies a batch of changes. A set through the parameter services (`ros2 param set`, rqt, a
SetParameters client) then:

- of a read-only parameter: refused by rclpy ("Trying to set a read-only parameter: ...");
- out of the descriptor's range or of the wrong type: refused by rclpy with the range or type; an integer for a
  double parameter is taken as that double (`ros2 param set /r1/planner a 1` means 1.0);
- not finite, or refused by the node's check (e.g. dwa needs max_speed > 0): refused with the node's reason,
  nothing changed (a SetParametersAtomically batch is all or nothing);
- otherwise applied to the running node at once, without a restart.
"""

from __future__ import annotations

import difflib
import math
import weakref
from typing import Any, Callable, Iterable

from rcl_interfaces.msg import ParameterType, SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter

__all__ = ['DynamicParameters', 'runtime_names', 'unknown_overrides', 'warn_unknown_overrides']

Apply = Callable[[dict[str, Any]], str]
"""Validates and applies {name: new value}; returns '' when applied, else why not (then nothing changed)."""

_RUNTIME: weakref.WeakKeyDictionary[Node, frozenset[str]] = weakref.WeakKeyDictionary()


def runtime_names(node: Node) -> frozenset[str]:
    """The parameters the node applies while it runs: those of its DynamicParameters (none without one)."""
    return _RUNTIME.get(node, frozenset())


class DynamicParameters:
    """The set-parameters callbacks of a node whose `names` change at runtime through `apply`.

    Register it after the node has declared everything: rclpy calls the on-set callbacks while declaring too.
    """

    def __init__(self, node: Node, names: Iterable[str], apply: Apply) -> None:
        self.node = node
        self.names = frozenset(names)
        self.apply = apply
        node.add_pre_set_parameters_callback(self._widen)
        node.add_on_set_parameters_callback(self._on_set)
        _RUNTIME[node] = self.names

    def destroy(self) -> None:
        """Take the callbacks off the node: sets are then only rclpy's checks (its descriptors' ranges)."""
        self.node.remove_pre_set_parameters_callback(self._widen)
        self.node.remove_on_set_parameters_callback(self._on_set)
        _RUNTIME.pop(self.node, None)

    def _declared_type(self, name: str) -> int | None:
        if not self.node.has_parameter(name):
            return None
        return int(self.node.describe_parameter(name).type)

    def _widen(self, parameters: list[Parameter]) -> list[Parameter]:
        """An integer for a double parameter (an integer array for a double array) is taken as that double."""
        out = []
        for parameter in parameters:
            declared = self._declared_type(parameter.name)
            if parameter.type_ == Parameter.Type.INTEGER and declared == ParameterType.PARAMETER_DOUBLE:
                parameter = Parameter(parameter.name, Parameter.Type.DOUBLE, float(parameter.value))
            elif parameter.type_ == Parameter.Type.INTEGER_ARRAY and declared == ParameterType.PARAMETER_DOUBLE_ARRAY:
                parameter = Parameter(parameter.name, Parameter.Type.DOUBLE_ARRAY, [float(v) for v in parameter.value])
            out.append(parameter)
        return out

    def _on_set(self, parameters: list[Parameter]) -> SetParametersResult:
        changes = {p.name: p.value for p in parameters if p.name in self.names}
        if not changes:
            return SetParametersResult(successful=True)
        for name, value in changes.items():
            if isinstance(value, float) and not math.isfinite(value):
                return SetParametersResult(successful=False, reason=f'parameter {name} must be finite, got {value}')
        try:
            reason = self.apply(changes)
        except Exception as exc:   # a bug in an apply function refuses the set; it never ends the node
            reason = f'{type(exc).__name__}: {exc}'
        if reason:
            self.node.get_logger().warning(f'parameters refused: {reason}')
        else:
            self.node.get_logger().info('parameters set: ' + ', '.join(f'{k}={v}' for k, v in changes.items()))
        return SetParametersResult(successful=not reason, reason=reason)


def unknown_overrides(node: Node) -> list[str]:
    """Names given to the node (`-p name:=value`, a parameter file) that it has not declared, sorted."""
    overrides = getattr(node, '_parameter_overrides', None)   # rclpy keeps them there (a private attribute)
    if not isinstance(overrides, dict):
        return []
    return sorted(name for name in overrides if not node.has_parameter(name))


def warn_unknown_overrides(node: Node) -> list[str]:
    """Warn about every override no parameter takes (a misspelled `-p` was ignored silently); returns them."""
    unknown = unknown_overrides(node)
    if unknown:
        declared = list(node.list_parameters([], 0).names)
        hints = []
        for name in unknown:
            close = difflib.get_close_matches(name, declared, n=1)
            hints.append(f'{name} (did you mean {close[0]}?)' if close else name)
        node.get_logger().warning(f'ignoring unknown parameter(s): {", ".join(hints)} (`ros2 param list` or '
                                  f'`ros2 param describe` tell what this node takes)')
    return unknown
