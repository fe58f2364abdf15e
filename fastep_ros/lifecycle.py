"""Managed (lifecycle) nodes that Nav2's lifecycle manager can drive, autostarting by default.

The planner and the plant are rclpy.lifecycle.LifecycleNode subclasses (rclpy 7.1.6, Jazzy), offering the lifecycle
services nav2_lifecycle_manager calls (`<node>/change_state`, `get_state`, ...) and `<node>/transition_event`. They
keep Nav2's order (nav2_controller's controller_server, ros2/demos' lifecycle talker):

- the constructor declares the parameters (a bad one is a one-line exit 2 at once) and nothing else that talks to
  the graph, then calls `Lifecycle.start`: `autostart` true (the default) configures and activates at once, as a
  plain node; false stands unconfigured, with nothing made, until a lifecycle manager (or `ros2 lifecycle set`)
  drives it;
- configure makes everything from the parameters' values then (subscriptions, publishers, timers, servers,
  threads); a value found bad there is a FAILURE with one log line (with autostart: the one-line exit 2);
- activate switches the lifecycle publishers on (LifecycleNode.on_activate), then the node's timers;
- deactivate sends what stops the robot while the publishers are still on, then switches them and the timers off;
- cleanup releases everything configure made, so the next configure builds afresh; shutdown and an error release
  it too, from any state. Every callback configure made does nothing from the moment cleanup begins (`mute`): an
  executor may deliver a message it took before the subscription was destroyed.

`Lifecycle` is the member that does it (the planner's `lifecycle`; ManagedNode, the plant's base, holds one): its
owner's on_configure, on_activate, ... are this member's, calling the node's `configure`, `activate`,
`deactivate` and `cleanup`. It knows the node's state from the transitions the node went through, and answers a
transition the current state does not have `success: false` (logged): rclpy 7.1.6 raises it out of the
change_state service callback, which ends the process.
"""

from __future__ import annotations

import traceback
from typing import Any, Callable, TypeVar

from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.lifecycle.publisher import LifecyclePublisher
from rclpy.node import Node

from fastep_ros.common import Param, StartupError

__all__ = ['AUTOSTART', 'Lifecycle', 'ManagedNode', 'destroy_publisher', 'transitions_to_member']

AUTOSTART = Param('autostart', True, 'configure and activate at start; false: stay unconfigured (nothing subscribed, '
                  'published or timed) until a lifecycle manager drives the node (change_state: configure, activate, '
                  'deactivate, cleanup, shutdown)', component='node')

TRANSITIONS = ('on_configure', 'on_activate', 'on_deactivate', 'on_cleanup', 'on_shutdown', 'on_error')
NodeClass = TypeVar('NodeClass', bound=type[LifecycleNode])

# The primary state a transition callback leaves the node in when it returns SUCCESS, and when it returns FAILURE
# (rcl_lifecycle's default state machine); ERROR goes to errorprocessing, on_error's SUCCESS to unconfigured.
OUTCOMES = {
    'on_configure': ('inactive', 'unconfigured'),
    'on_activate': ('active', 'inactive'),
    'on_deactivate': ('inactive', 'active'),
    'on_cleanup': ('unconfigured', 'inactive'),
    'on_shutdown': ('finalized', 'finalized'),
    'on_error': ('unconfigured', 'finalized'),
}
# The transitions each primary state has, by id (a request by label is resolved by rclpy among these).
VALID = {
    'unconfigured': (Transition.TRANSITION_CONFIGURE, Transition.TRANSITION_UNCONFIGURED_SHUTDOWN),
    'inactive': (Transition.TRANSITION_CLEANUP, Transition.TRANSITION_ACTIVATE,
                 Transition.TRANSITION_INACTIVE_SHUTDOWN),
    'active': (Transition.TRANSITION_DEACTIVATE, Transition.TRANSITION_ACTIVE_SHUTDOWN),
}


def transitions_to_member(cls: NodeClass) -> NodeClass:
    """Class decorator: rclpy's transition callbacks of a LifecycleNode (on_configure, on_activate, ...: rclpy
    calls the node's methods of those names) handed to the node's `lifecycle` member, which learns where each
    left the node. One that raises is logged with its traceback and is an ERROR (rclpy made it one silently)."""
    for name in TRANSITIONS:
        def transition(self: Any, state: LifecycleState, name: str = name) -> TransitionCallbackReturn:
            try:
                result = getattr(self.lifecycle, name)(state)
            except Exception as exc:  # noqa: BLE001  the lifecycle goes on to errorprocessing, the node runs on
                self.get_logger().error(f'{name} failed: {exc}\n{traceback.format_exc()}')
                result = TransitionCallbackReturn.ERROR
            self.lifecycle.went(name, result)
            return result
        transition.__name__ = transition.__qualname__ = name
        setattr(cls, name, transition)
    return cls


def destroy_publisher(node: Node, publisher: Any) -> None:
    """Destroy a publisher; a lifecycle publisher also leaves its node's managed entities (Node.destroy_publisher
    would leave it there, activated with the node, for ever)."""
    if isinstance(publisher, LifecyclePublisher) and isinstance(node, LifecycleNode):
        node.destroy_lifecycle_publisher(publisher)
    else:
        node.destroy_publisher(publisher)


def forget_destroyed(node: Node) -> None:
    """Drop the dead references the node's default callback group keeps: rclpy's CallbackGroup.add_entity adds a
    weak reference for every entity made in it and nothing takes one out when the entity is destroyed, so every
    configure and cleanup would leave ~50 of them behind."""
    group = node.default_callback_group
    group.entities = {ref for ref in group.entities if ref() is not None}


def _ignored(*_: Any) -> None:
    """What a subscription's or timer's callback becomes once its node is cleaned up."""


def _answered_empty(request: Any, response: Any) -> Any:
    """What a service's callback becomes once its node is cleaned up: the empty response."""
    return response


def callback_entities(node: Node) -> set[Any]:
    """The node's subscriptions, timers and services: what an executor calls back into."""
    return {*node.subscriptions, *node.timers, *node.services}


def mute(node: Node, kept: set[Any]) -> None:
    """Make every callback of the node's subscriptions, timers and services not in `kept` do nothing (a service:
    answer empty), rclpy's /clock subscription (its TimeSource's, made again when use_sim_time is switched on)
    excepted. An executor may still deliver what it took before an entity was destroyed: at load the EventsExecutor
    called the planner's odometry callback after its cleanup had dropped what the callback reads (an
    AttributeError out of the spin, which ends a node process). Executors read `callback` when they call it."""
    clock, services = getattr(getattr(node, '_time_source', None), '_clock_sub', None), set(node.services)
    for entity in callback_entities(node) - kept:
        if entity is not clock:
            entity.callback = _answered_empty if entity in services else _ignored


class Lifecycle:
    """A LifecycleNode's transitions, calling `configure` / `activate` / `deactivate` / `cleanup` of the node; its
    owner's on_configure, on_activate, ... are this member's (rclpy calls the node's methods of those names).

    `configure` raises StartupError (one line) for a value it cannot start with; `cleanup(forget)` releases whatever
    configure made, also after a configure that failed half-way, and with `forget` drops what the run left (a
    configure follows); shutdown and destroy_node keep it to be read."""

    def __init__(self, node: LifecycleNode, configure: Callable[[], None], activate: Callable[[], None],
                 deactivate: Callable[[], None], cleanup: Callable[[bool], None]) -> None:
        self.node = node
        self.configure, self.activate, self.deactivate, self.cleanup = configure, activate, deactivate, cleanup
        self.state = 'unconfigured'   # the primary state the node's transitions left it in
        self.is_active = False        # commanding: false from the moment deactivation begins
        self.built = False            # configure has run (or begun) since the last release
        self.autostart = True
        self._kept: set[Any] = set()   # the entities the node had before configure (cleanup mutes the others)
        self._starting = False                       # the constructor's configure (autostart)
        self._failure: BaseException | None = None   # why it failed: raised by start
        self._refuse_invalid()

    def _refuse_invalid(self) -> None:
        """Put the check in front of the node's change_state service (found among its services by type and name)."""
        name = f'{self.node.get_fully_qualified_name().rstrip("/")}/change_state'
        for service in self.node.services:
            if service.srv_type is ChangeState and service.service_name == name:
                service.callback = self._refusing_invalid(service.callback)

    def _refusing_invalid(self, handle: Callable[[Any, Any], Any]) -> Callable[[Any, Any], Any]:
        """change_state's handler answering `success: false` to a transition the current state does not have
        (configure while active), and to whatever else rclpy would raise out of the service callback."""
        def change_state(request: Any, response: Any) -> Any:
            transition = request.transition
            wanted = transition.label or str(transition.id)
            if transition.label or transition.id in VALID.get(self.state, ()):
                try:
                    return handle(request, response)
                except Exception as exc:  # noqa: BLE001  raised out of the callback, it ended the process
                    self.node.get_logger().error(f'change_state {wanted} failed in state {self.state}: '
                                                 f'{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}')
            else:
                self.node.get_logger().warning(f'change_state refused: transition {wanted} is not valid in state '
                                               f'{self.state}')
            response.success = False
            return response
        return change_state

    def went(self, transition: str, result: TransitionCallbackReturn) -> None:
        """Where a transition callback's result leaves the node (rcl_lifecycle's state machine)."""
        success, failure = OUTCOMES[transition]
        if result == TransitionCallbackReturn.SUCCESS:
            self.state = success
        elif result == TransitionCallbackReturn.FAILURE or transition == 'on_error':
            self.state = failure
        else:
            self.state = 'errorprocessing'

    def start(self, autostart: bool | None = None) -> None:
        """The constructor's last step: autostart (configure, then activate; a configure that fails raises its
        error, a StartupError for a bad value), or stand unconfigured until a lifecycle manager drives the node.
        `autostart` as declared by the node (None: declared here)."""
        self.autostart = AUTOSTART.declare(self.node) if autostart is None else autostart
        if not self.autostart:
            return
        self._starting = True
        try:
            configured = self.node.trigger_configure()
        finally:
            self._starting = False
        failure, self._failure = self._failure, None
        if failure is not None:
            raise failure
        if configured == TransitionCallbackReturn.SUCCESS:
            self.node.trigger_activate()

    def release(self, forget: bool = True) -> None:
        """The node's cleanup, once, if configure has made anything since the last."""
        if self.built:
            self.built = False
            mute(self.node, self._kept)   # first: nothing configure made acts on what cleanup takes apart
            self.cleanup(forget)
            forget_destroyed(self.node)


    def stop(self) -> None:
        """Stop commanding (deactivate) if the node is active."""
        if self.is_active:
            self.is_active = False
            self.deactivate()

    # rclpy's transition callbacks (LifecycleNode's own: the lifecycle publishers and other managed entities).
    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.built, self._kept = True, callback_entities(self.node)
        try:
            self.configure()
        except Exception as exc:  # noqa: BLE001  a node that cannot configure stays unconfigured, never ends
            self.release()
            if self._starting:
                self._failure = exc   # raised by start: a StartupError is the one-line exit 2
            elif isinstance(exc, StartupError):
                self.node.get_logger().error(f'configure failed: {exc}')
            else:
                self.node.get_logger().error(f'configure failed: {exc}\n{traceback.format_exc()}')
            return TransitionCallbackReturn.FAILURE if isinstance(exc, StartupError) else \
                TransitionCallbackReturn.ERROR
        result = LifecycleNode.on_configure(self.node, state)
        if result == TransitionCallbackReturn.SUCCESS:
            self.node.get_logger().info('configured')
        else:
            self.release()
        return result

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        result = LifecycleNode.on_activate(self.node, state)
        if result == TransitionCallbackReturn.SUCCESS:
            self.is_active = True
            self.activate()
            self.node.get_logger().info('active')
        return result

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.stop()   # the zero command while the publishers are on: LifecycleNode's switches them off
        self.node.get_logger().info('inactive')
        return LifecycleNode.on_deactivate(self.node, state)

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.release()
        self.node.get_logger().info('cleaned up: unconfigured')
        return LifecycleNode.on_cleanup(self.node, state)

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.stop()
        self.release(forget=False)   # finalized: nothing is configured again
        self.node.get_logger().info('shut down (finalized)')
        return LifecycleNode.on_shutdown(self.node, state)

    def on_error(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.stop()
        self.release()
        return LifecycleNode.on_error(self.node, state)


@transitions_to_member
class ManagedNode(LifecycleNode):
    """A LifecycleNode whose transitions (its `lifecycle` member) call configure / activate / deactivate /
    cleanup of the subclass."""

    def __init__(self, node_name: str, **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        self.lifecycle = Lifecycle(self, self.configure, self.activate, self.deactivate, self.cleanup)

    @property
    def is_active(self) -> bool:
        return self.lifecycle.is_active

    @property
    def autostart(self) -> bool:
        return self.lifecycle.autostart

    def start_lifecycle(self) -> None:
        """The constructor's last step: autostart, or stand unconfigured until a lifecycle manager drives the
        node."""
        self.lifecycle.start()

    def destroy_node(self) -> None:
        self.lifecycle.release(forget=False)
        super().destroy_node()

    # What a subclass does.
    def configure(self) -> None:
        """Make the subscriptions, publishers and timers (StartupError for a value it cannot start with)."""

    def activate(self) -> None:
        """Start commanding (timers on)."""

    def deactivate(self) -> None:
        """Stop commanding (a zero command, timers off)."""

    def cleanup(self, forget: bool = True) -> None:
        """Release what configure made (back to unconfigured); `forget`: drop it too (a configure follows)."""
