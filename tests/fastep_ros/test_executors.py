"""fastep_ros.executors: the nodes on rclpy's EventsExecutor as on the SingleThreadedExecutor (message-info
callbacks, timers on simulated time, the /clock guard), and the choice of executor."""

from __future__ import annotations

import time
from typing import Any, Callable

import pytest
from geometry_msgs.msg import Twist
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock

from fastep_ros.errors import StartupError
from fastep_ros.executors import EXECUTOR_ENV, EXECUTORS, MessageInfoCallback, executor_kind, make_executor
from fastep_ros.plant import PlantNode
from msg_tools import convert
from msg_tools.interface import LATEST


def _spin_until(executor: Any, done: Callable[[], bool], seconds: float = 10.0) -> None:
    end = time.monotonic() + seconds
    while not done() and time.monotonic() < end:
        executor.spin_once(timeout_sec=0.05)


@pytest.mark.parametrize('kind', EXECUTORS)
def test_the_plant_takes_commands_with_their_message_info_on_either_executor(context: Any, kind: str) -> None:
    """rclpy 7.1.6's EventsExecutor hands a two-parameter callback one (message, info) tuple: the plant's cmd_vel
    callback raised inside spin_once ("SystemError: null argument to internal routine") and the node ended."""
    executor = make_executor(kind, context)
    plant = PlantNode(context=context, parameter_overrides=[Parameter('start', value=[1.0, 2.0])])
    sender = plant.create_publisher(Twist, 'cmd_vel', LATEST)
    try:
        executor.add_node(plant)
        twist = Twist()
        twist.linear.x = 0.5

        def taken() -> bool:
            sender.publish(twist)
            return bool(plant.command[0] == 0.5)
        _spin_until(executor, taken)
        assert plant.command.tolist() == [0.5, 0.0]
        assert plant.command_time is not None   # sent time: the DDS source timestamp of the Twist (wall time)
    finally:
        executor.shutdown()
        plant.destroy_node()


def test_a_message_info_callback_takes_both_calling_conventions() -> None:
    seen: list[tuple[Any, Any]] = []
    callback = MessageInfoCallback(lambda msg, info: seen.append((msg, info)))
    callback('m', {'source_timestamp': 1})
    callback(('m', {'source_timestamp': 2}))
    assert seen == [('m', {'source_timestamp': 1}), ('m', {'source_timestamp': 2})]


@pytest.mark.parametrize('kind', EXECUTORS)
def test_timers_run_on_simulated_time_and_the_clock_guard_holds_on_either_executor(context: Any, kind: str) -> None:
    """A plant on use_sim_time integrates only as /clock advances; a lone /clock message far ahead is ignored
    (common.guard_clock replaces the callback of rclpy's /clock subscription: the EventsExecutor reads it at
    each message)."""
    executor = make_executor(kind, context)
    plant = PlantNode(context=context, parameter_overrides=[Parameter('start', value=[0.0, 0.0]),
                                                            Parameter('use_sim_time', value=True)])
    clock = plant.create_publisher(Clock, '/clock', 10)
    try:
        executor.add_node(plant)

        def at(t: float) -> Callable[[], bool]:
            def reached() -> bool:
                clock.publish(convert.seconds_to_clock(t))
                return plant.tick is not None and plant.tick * plant.step >= t - 1e-9
            return reached
        for t in (0.1, 0.2, 0.3):
            _spin_until(executor, at(t))
            assert plant.tick is not None and plant.tick * plant.step == pytest.approx(t)
        clock.publish(convert.seconds_to_clock(1e6))   # alone, far ahead: ignored
        end = time.monotonic() + 0.5
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        assert plant.now() == pytest.approx(0.3)
    finally:
        executor.shutdown()
        plant.destroy_node()


def test_the_executor_is_chosen_by_argument_environment_or_default(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(EXECUTOR_ENV, raising=False)
    assert executor_kind() in EXECUTORS
    monkeypatch.setenv(EXECUTOR_ENV, 'single')
    assert executor_kind() == 'single' and executor_kind('events') == 'events'
    monkeypatch.setenv(EXECUTOR_ENV, 'threads')
    with pytest.raises(StartupError, match="FASTEP_EXECUTOR must be one of events, single, got 'threads'"):
        executor_kind()
