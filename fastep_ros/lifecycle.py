"""Managed (lifecycle) nodes that Nav2's lifecycle manager can drive, autostarting by default.

The planner and the plant are rclpy.lifecycle.LifecycleNode subclasses (rclpy 7.1.6, Jazzy): they offer the
lifecycle services `<node>/change_state`, `get_state`, `get_available_states`, `get_available_transitions` and
`get_transition_graph`, and publish `<node>/transition_event`, which is what nav2_lifecycle_manager calls.

A node builds everything in its constructor, as before (parameters are then checked at once, and a bad one is a
one-line exit 2 with no lifecycle involved), and ends it with `start_lifecycle()`:

- `autostart` true (the default): configure and activate at once, so fastep-launch, `make demo` and a node
  started by hand behave as plain nodes did;
- `autostart` false: unconfigured and inactive (no commands, no integration) until a lifecycle manager (or
  `ros2 lifecycle set`) drives it: configure, activate, deactivate, cleanup, shutdown.

Transitions: configure checks nothing more (done at construction) and succeeds; activate calls `activate()`;
deactivate, shutdown and an error call `deactivate()` (a planner sends a zero cmd_vel and stops its control timer;
a plant stops integrating and drops its command); cleanup calls `cleanup()` (a planner forgets its goal). A node
that is not active says so on its status (`inactive`). A transition the current state does not have is answered
`success: false` (and logged); the node carries on in its state.
"""

from __future__ import annotations

from typing import Any, Callable

from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn

from fastep_ros.common import declare

__all__ = ['ManagedNode']


class ManagedNode(LifecycleNode):
    """A LifecycleNode whose transitions call activate / deactivate / cleanup of the subclass."""

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.is_active = False
        self.autostart = True
        service = getattr(self, '_service_change_state', None)
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
                self.get_logger().warning(f'change_state refused: transition {wanted} is not valid in state '
                                          f'{self._state_machine.current_state[1]} '
                                          f'({str(exc).splitlines()[0] if str(exc) else "rcl error"})')
                response.success = False
                return response
        return change_state

    def start_lifecycle(self) -> None:
        """The constructor's last step: autostart, or stand inactive until a lifecycle manager drives the node."""
        self.autostart = declare(self, 'autostart', True, 'configure and activate at start; false: stay '
                                 'unconfigured (no commands) until a lifecycle manager drives the node '
                                 '(change_state: configure, activate, deactivate, cleanup, shutdown)')
        if self.autostart:
            self.trigger_configure()
            self.trigger_activate()
        else:
            self.deactivate()

    # What a subclass does.
    def activate(self) -> None:
        """Start commanding (timers on)."""

    def deactivate(self) -> None:
        """Stop commanding (a zero command, timers off)."""

    def cleanup(self) -> None:
        """Forget what the run built up (back to unconfigured)."""

    # rclpy's transition callbacks.
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.get_logger().info('configured')
        return super().on_configure(state)

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        result = super().on_activate(state)
        if result == TransitionCallbackReturn.SUCCESS:
            self.is_active = True
            self.activate()
            self.get_logger().info('active')
        return result

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.is_active = False
        self.deactivate()
        self.get_logger().info('inactive')
        return super().on_deactivate(state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.cleanup()
        self.get_logger().info('cleaned up: unconfigured')
        return super().on_cleanup(state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.is_active = False
        self.deactivate()
        self.get_logger().info('shut down (finalized)')
        return super().on_shutdown(state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.is_active = False
        self.deactivate()
        return super().on_error(state)
