"""One set of limits in the planner node: max_speed set at runtime reaches the model, the control tick's guard and
smoother and the latency compensation by the next control tick; dt follows control_rate_hz."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest
from rclpy.parameter import Parameter

from fastep_core.scenario import load_scenario
from fastep_ros import launch
from fastep_ros.common import StartupError
from fastep_ros.planner import PlannerNode
from fastep_testing.in_process import DT, ObedientBase, planner_node

LAG = 0.04    # s: how old the odometry of a latency-compensation probe is


def make(context: Any, **params: Any) -> PlannerNode:
    return planner_node(context, **{'workspace': [0.0, 0.0, 100.0, 20.0], **params})


class Base(ObedientBase):
    """The obedient base, asked how far the latency compensation puts it."""

    def compensated(self) -> float:
        """How far the latency compensation predicts the robot from odometry LAG s old: the command it was sent,
        over LAG, as the model has it."""
        before = self.state - LAG * np.array([self.v * np.cos(self.state[2]), self.v * np.sin(self.state[2]), 0.0])
        self.odometry(self.now - LAG, before)
        state, problem = self.node.inputs.state(self.now)
        assert state is not None, problem
        return float(np.hypot(*(state[:2] - before[:2])))


def set_speed(node: PlannerNode, value: float) -> None:
    assert node.set_parameters([Parameter('max_speed', value=value)])[0].successful


def test_max_speed_raised_and_lowered_at_runtime_reaches_model_guard_smoother_and_latency_compensation(
        context: Any) -> None:
    node = make(context, model='diff_drive', robot_radius=0.3)
    try:
        base = Base(node)
        speeds = [base.tick() for _ in range(30)]
        assert speeds[-1] == pytest.approx(1.0)
        set_speed(node, 1.5)
        base.tick()   # the next control tick: every reader has the new limit
        nav, control = node.navigator, node.control_tick
        assert nav is not None and control is not None
        fast = np.array([1.5, 0.0])
        assert nav.model.integrate(base.state, fast, DT)[0] == pytest.approx(base.state[0] + 1.5 * DT)
        assert control.guard.model is nav.model and nav.guard_check.model is nav.model
        assert control.smoother.max_speed == nav.limits.max_speed == control.limits.max_speed == 1.5
        speeds = [base.tick() for _ in range(10)]
        assert speeds[-1] == pytest.approx(1.5)
        assert base.compensated() == pytest.approx(1.5 * LAG)   # at the old limit's saturation: 1.0 x LAG

        set_speed(node, 0.5)
        speeds = [base.tick()]   # the next tick brakes toward it, at max_acceleration
        control = node.control_tick
        assert control is not None and control.smoother.max_speed == control.limits.max_speed == 0.5
        assert speeds[0] == pytest.approx(1.5 - 2.5 * DT)
        # The ramp down is what the base does: predicted as such (a model saturating at 0.5 would say 0.5 x LAG).
        assert base.compensated() == pytest.approx(speeds[0] * LAG)
        assert control.guard.model is node.navigator.model   # type: ignore[union-attr]  # made by now
        speeds += [base.tick() for _ in range(12)]
        assert np.abs(np.diff([1.5, *speeds])).max() <= 2.5 * DT + 1e-9 and speeds[-1] == pytest.approx(0.5)
        assert base.compensated() == pytest.approx(0.5 * LAG)
    finally:
        node.destroy_node()


def test_a_dt_that_disagrees_with_control_rate_hz_is_refused_in_one_line(context: Any) -> None:
    with pytest.raises(StartupError) as refused:
        make(context, dt=0.1)   # control_rate_hz 20: a period of 0.05 s
    message = str(refused.value)
    assert 'dt=0.1' in message and 'control_rate_hz=20' in message and '\n' not in message
    node = make(context, control_rate_hz=10.0, dt=0.1)   # the same period twice: taken
    try:
        assert node.params.dt == 0.1
        (result,) = node.set_parameters([Parameter('dt', value=0.05)])
        assert not result.successful and '\n' not in result.reason
        assert 'dt=0.05' in result.reason and 'control_rate_hz=10' in result.reason
        assert node.params.dt == 0.1 and node.get_parameter('dt').value == 0.1   # nothing changed
        assert node.set_parameters_atomically([Parameter('control_rate_hz', value=25.0),
                                               Parameter('dt', value=0.04)]).successful   # both at once, agreeing
        assert node.params.dt == 0.04
    finally:
        node.destroy_node()
    # fastep-launch gives a scenario's dt and 1 / dt as the rate: taken, the scenario's step to the bit, as
    # fastep-sim steps (1 / (1 / 0.03) is not 0.03).
    scenario = load_scenario('open_field')
    scenario = dataclasses.replace(scenario, planner=scenario.planner.with_overrides({'dt': 0.03}))
    given = launch.planner_params(scenario, 0, 'fastep', 0, False)
    assert given['dt'] == 0.03 and given['control_rate_hz'] == 1.0 / 0.03
    node = make(context, control_rate_hz=given['control_rate_hz'], dt=given['dt'])
    try:
        assert node.params.dt == 0.03
    finally:
        node.destroy_node()


def test_control_rate_hz_changed_at_runtime_changes_the_planner_s_dt(context: Any) -> None:
    node = make(context, model='diff_drive', robot_radius=0.3)
    try:
        base = Base(node)
        for _ in range(5):
            base.tick()
        assert node.params.dt == DT
        assert node.set_parameters([Parameter('control_rate_hz', value=10.0)])[0].successful
        base.tick()
        nav, control = node.navigator, node.control_tick
        assert nav is not None and control is not None
        assert node.params.dt == 0.1
        assert nav.params.dt == nav.limits.dt == control.limits.dt == 0.1   # DWA's, the smoother's period
        assert node.get_parameter('dt').value == 0.1   # the dt parameter says the period it follows
        assert node.control_timer.timer_period_ns == 100_000_000
    finally:
        node.destroy_node()


def test_the_dt_parameter_reads_the_control_period_when_only_control_rate_hz_is_given(context: Any) -> None:
    node = PlannerNode(context=context, parameter_overrides=[Parameter('control_rate_hz', value=10.0),
                                                             Parameter('workspace', value=[0.0, 0.0, 20.0, 20.0])])
    try:
        assert node.params.dt == pytest.approx(0.1) and node.get_parameter('dt').value == pytest.approx(0.1)
    finally:
        node.destroy_node()
