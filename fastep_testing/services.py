"""A client of a node's services in the same process: the parameter services (what `ros2 param` calls) and
the lifecycle services (what Nav2's lifecycle manager calls), spinning the node beside it."""

from __future__ import annotations

import time
from typing import Any, Callable

from rcl_interfaces.srv import DescribeParameters, GetParameters, ListParameters, SetParameters, SetParametersAtomically
from rclpy.parameter import Parameter

from fastep_ros.executors import make_executor

__all__ = ['Services']


class Services:
    """A client of one node's parameter services (what `ros2 param` calls), spinning the node beside it on the
    executor `executor` (fastep_ros.executors names them)."""

    def __init__(self, context: Any, node: Any, executor: str = 'single') -> None:
        import rclpy
        self.node = node
        self.client = rclpy.create_node('param_client', context=context)
        self.executor = make_executor(executor, context=context)
        self.executor.add_node(node)
        self.executor.add_node(self.client)
        self.prefix = node.get_fully_qualified_name()
        self.clients: dict[str, Any] = {}   # one per service, made at its first call

    def call(self, kind: type, service: str, request: Any) -> Any:
        if service not in self.clients:
            self.clients[service] = self.client.create_client(kind, f'{self.prefix}/{service}')
        client = self.clients[service]
        assert client.wait_for_service(timeout_sec=10.0), service
        future = client.call_async(request)
        self.executor.spin_until_future_complete(future, timeout_sec=10.0)
        assert future.done(), service
        return future.result()

    def set(self, **values: Any) -> list[Any]:
        request = SetParameters.Request(
            parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()])
        return list(self.call(SetParameters, 'set_parameters', request).results)

    def set_atomically(self, **values: Any) -> Any:
        request = SetParametersAtomically.Request(
            parameters=[Parameter(k, value=v).to_parameter_msg() for k, v in values.items()])
        return self.call(SetParametersAtomically, 'set_parameters_atomically', request).result

    def get(self, *names: str) -> list[Any]:
        return list(self.call(GetParameters, 'get_parameters', GetParameters.Request(names=list(names))).values)

    def describe(self, *names: str) -> list[Any]:
        request = DescribeParameters.Request(names=list(names))
        return list(self.call(DescribeParameters, 'describe_parameters', request).descriptors)

    def names(self) -> list[str]:
        return list(self.call(ListParameters, 'list_parameters', ListParameters.Request()).result.names)

    def spin_until(self, done: Callable[[], bool], seconds: float = 10.0) -> bool:
        end = time.monotonic() + seconds
        while not done() and time.monotonic() < end:
            self.executor.spin_once(timeout_sec=0.02)
        return done()

    def close(self) -> None:
        self.executor.shutdown()
        self.client.destroy_node()
        self.node.destroy_node()

    def change_state(self, transition: str) -> bool:
        """A lifecycle transition by label (configure, activate, deactivate, cleanup, shutdown), as Nav2's
        lifecycle manager asks for it; True if it succeeded."""
        from lifecycle_msgs.msg import Transition
        from lifecycle_msgs.srv import ChangeState
        ids = {'configure': Transition.TRANSITION_CONFIGURE, 'activate': Transition.TRANSITION_ACTIVATE,
               'deactivate': Transition.TRANSITION_DEACTIVATE, 'cleanup': Transition.TRANSITION_CLEANUP,
               'shutdown': Transition.TRANSITION_UNCONFIGURED_SHUTDOWN}
        request = ChangeState.Request()
        request.transition.id = ids[transition]
        if transition == 'shutdown':
            request.transition.id = {'inactive': Transition.TRANSITION_INACTIVE_SHUTDOWN,
                                     'active': Transition.TRANSITION_ACTIVE_SHUTDOWN}.get(
                                         self.state(), Transition.TRANSITION_UNCONFIGURED_SHUTDOWN)
        return bool(self.call(ChangeState, 'change_state', request).success)

    def state(self) -> str:
        """The lifecycle state's label (unconfigured, inactive, active, finalized)."""
        from lifecycle_msgs.srv import GetState
        return str(self.call(GetState, 'get_state', GetState.Request()).current_state.label)
