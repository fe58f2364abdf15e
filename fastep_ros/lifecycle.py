"""Managed (lifecycle) nodes that Nav2's lifecycle manager can drive, autostarting by default.

The planner and the plant are rclpy.lifecycle.LifecycleNode subclasses (rclpy 7.1.6, Jazzy), offering the lifecycle
services nav2_lifecycle_manager calls (`<node>/change_state`, `get_state`, ...) and `<node>/transition_event`. A
node builds everything in its constructor (a bad parameter is a one-line exit 2, no lifecycle involved) and ends it
with `Lifecycle.start`: `autostart` true (the default) configures and activates at once, as a plain node; false
stands unconfigured and inactive until a lifecycle manager (or `ros2 lifecycle set`) drives it.

`Lifecycle` is the member that does it (the planner's `lifecycle`; ManagedNode, the plant's base, holds one):
configure succeeds; activate calls the node's `activate`; deactivate, shutdown and an error call `deactivate` (a
zero command, timers off); cleanup calls `cleanup`. A transition the current state does not have is answered
`success: false` (and logged); the node carries on in its state.
"""

from __future__ import annotations

from typing import Any, Callable, TypeVar

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn

from fastep_ros.common import Param

__all__ = ['AUTOSTART', 'Lifecycle', 'ManagedNode', 'transitions_to_member']

AUTOSTART = Param('autostart', True, 'configure and activate at start; false: stay unconfigured (no commands) until '
                  'a lifecycle manager drives the node (change_state: configure, activate, deactivate, cleanup, '
                  'shutdown)')

TRANSITIONS = ('on_configure', 'on_activate', 'on_deactivate', 'on_cleanup', 'on_shutdown', 'on_error')
NodeClass = TypeVar('NodeClass', bound=type[LifecycleNode])


def transitions_to_member(cls: NodeClass) -> NodeClass:
    """Class decorator: rclpy's transition callbacks of a LifecycleNode (on_configure, on_activate, ...: rclpy
    calls the node's methods of those names) handed to the node's `lifecycle` member."""
    for name in TRANSITIONS:
        def transition(self: Any, state: LifecycleState, name: str = name) -> TransitionCallbackReturn:
            return getattr(self.lifecycle, name)(state)
        transition.__name__ = transition.__qualname__ = name
        setattr(cls, name, transition)
    return cls


class Lifecycle:
    """A LifecycleNode's transitions, calling `activate` / `deactivate` / `cleanup` of the node; its owner's
    on_configure, on_activate, ... are this member's (rclpy calls the node's methods of those names)."""

    def __init__(self, node: LifecycleNode, activate: Callable[[], None], deactivate: Callable[[], None],
                 cleanup: Callable[[], None]) -> None:
        self.node = node
        self.activate, self.deactivate, self.cleanup = activate, deactivate, cleanup
        self.is_active = False
        self.autostart = True
        service = getattr(node, '_service_change_state', None)
        if service is not None:
            service.callback = self._refusing_invalid(service.callback)

    def _refusing_invalid(self, handle: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
        """change_state's handler answering `success: false` to a transition the current state does not have
        (configure while active): rclpy raises it out of the service callback, which ended the process."""
        def change_state(request: Any, response: Any) -> Any:
            try:
                return handle(request, response)
            except _rclpy.RCLError as exc:
                wanted = request.transition.label or str(request.transition.id)
                self.node.get_logger().warning(f'change_state refused: transition {wanted} is not valid in state '
                                               f'{self.node._state_machine.current_state[1]} '
                                               f'({str(exc).splitlines()[0] if str(exc) else "rcl error"})')
                response.success = False
                return response
        return change_state

    def start(self, autostart: bool | None = None) -> None:
        """The constructor's last step: autostart, or stand inactive until a lifecycle manager drives the node.
        `autostart` as declared by the node (None: declared here)."""
        self.autostart = AUTOSTART.declare(self.node) if autostart is None else autostart
        if self.autostart:
            self.node.trigger_configure()
            self.node.trigger_activate()
        else:
            self.deactivate()

    # rclpy's transition callbacks (LifecycleNode's own: the lifecycle publishers and other managed entities).
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.node.get_logger().info('configured')
        return LifecycleNode.on_configure(self.node, state)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        result = LifecycleNode.on_activate(self.node, state)
        if result == TransitionCallbackReturn.SUCCESS:
            self.is_active = True
            self.activate()
            self.node.get_logger().info('active')
        return result

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.is_active = False
        self.deactivate()
        self.node.get_logger().info('inactive')
        return LifecycleNode.on_deactivate(self.node, state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.cleanup()
        self.node.get_logger().info('cleaned up: unconfigured')
        return LifecycleNode.on_cleanup(self.node, state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.is_active = False
        self.deactivate()
        self.node.get_logger().info('shut down (finalized)')
        return LifecycleNode.on_shutdown(self.node, state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.is_active = False
        self.deactivate()
        return LifecycleNode.on_error(self.node, state)


@transitions_to_member
class ManagedNode(LifecycleNode):
    """A LifecycleNode whose transitions (its `lifecycle` member) call activate / deactivate / cleanup of the
    subclass."""

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.lifecycle = Lifecycle(self, self.activate, self.deactivate, self.cleanup)

    @property
    def is_active(self) -> bool:
        return self.lifecycle.is_active

    @property
    def autostart(self) -> bool:
        return self.lifecycle.autostart

    def start_lifecycle(self) -> None:
        """The constructor's last step: autostart, or stand inactive until a lifecycle manager drives the node."""
        self.lifecycle.start()

    # What a subclass does.
    def activate(self) -> None:
        """Start commanding (timers on)."""

    def deactivate(self) -> None:
        """Stop commanding (a zero command, timers off)."""

    def cleanup(self) -> None:
        """Forget what the run built up (back to unconfigured)."""
