"""What a neighbour's /tf cannot do to a planner that takes map -> odom from TF (fastep_ros.live_tf.TfListener,
PlannerInputs.map_to_odom): starve it or grow it with huge messages, have it drive on a map -> odom its localizer
stopped sending, make it take an older or far-future transform for the newest. A planner built in this process on
its own simulated clock, its control tick called directly; /tf through DDS where the test is about what it
takes of the wire."""

from __future__ import annotations

import functools
import time
from typing import Any, Callable

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticStatus
from rclpy.parameter import Parameter
from rclpy.serialization import deserialize_message
from rclpy.time import Time
from tf2_msgs.msg import TFMessage

from fastep_ros.limits import TF_LOCALIZER_INTERVAL, TF_MESSAGE_TRANSFORMS, TF_POLL_TRANSFORMS
from fastep_ros.planner import PlannerNode
from msg_tools import cdr, convert, frames
from msg_tools.tf_buffer import FRAMES_MAX

DT = 0.05
CLUTTER = 20_000
DRIVING = ('kinematic', 'avoiding')


def make(context: Any) -> PlannerNode:
    node = PlannerNode(context=context, namespace='/r1', parameter_overrides=[
        Parameter('workspace', value=[0.0, 0.0, 20.0, 20.0]), Parameter('use_sim_time', value=True),
        Parameter('planning_thread', value=False), Parameter('map_to_odom_from_tf', value=True)])
    node.inputs.on_obstacles(convert.obstacles_to_marker_array([]))
    node.on_goal(convert.point_to_pose_stamped((3.0, 12.0)))
    return node


def at(node: PlannerNode, t: float) -> None:
    clock: Any = node.get_clock()
    clock.set_ros_time_override(Time(nanoseconds=int(round(t * 1e9)), clock_type=clock.clock_type))


def odometry(node: PlannerNode, t: float) -> None:
    """At t, odometry at (1, 1) in r1/odom stamped t."""
    at(node, t)
    node.inputs.on_odom(convert.state_to_odometry([1.0, 1.0], convert.seconds_to_stamp(t), frame_id='r1/odom',
                                                  child_frame_id='r1/base_link'))


def tick(node: PlannerNode, t: float) -> tuple[bytes, str, str]:
    """The control tick at t, on odometry at (1, 1) stamped t; the status it leaves."""
    odometry(node, t)
    node.on_control()
    return node.reports.status()


def drives(node: PlannerNode, t: float) -> bool:
    """Whether the tick at t drives: a command, and a status that says so (the odometry, standing, makes the
    base track worse than configured: WARN)."""
    _, mode, reason = tick(node, t)
    assert mode in DRIVING, reason
    return bool(np.any(node.last_command != 0.0))


def message(*transforms: tuple[str, str, frames.Pose2D, float]) -> TFMessage:
    return TFMessage(transforms=[frames.transform_stamped(parent, child, pose, convert.seconds_to_stamp(stamp))
                                 for parent, child, pose, stamp in transforms])


def raw(parent: str, child: str, pose: frames.Pose2D, stamp: float) -> cdr.Transform:
    q = convert.yaw_to_quaternion(pose[2])
    return (cdr.stamp_parts(stamp), parent, child, (pose[0], pose[1], 0.0), (q.x, q.y, q.z, q.w))


def holds(node: PlannerNode, pose: frames.Pose2D) -> bool:
    """Whether the planner's TF has map -> r1/odom at `pose` (after taking what /tf brought)."""
    return node.tf.lookup('map', 'r1/odom') == pytest.approx(pose)


def wait(condition: Callable[[], bool], timeout: float, what: str) -> None:
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, f'timed out after {timeout:g} s waiting for {what}'
        time.sleep(0.01)


def test_a_flood_of_20000_frame_messages_keeps_no_clutter_and_the_robot_commands_at_every_tick(context: Any) -> None:
    """A neighbour's /tf messages of 20,000 frames, map -> odom among them: each read for the frames the planner
    looks up only (rclpy took ~1 s to build one), none of the clutter kept, a command at every tick."""
    import rclpy
    node = make(context)
    neighbour = rclpy.create_node('neighbour', context=context)
    try:
        pub = neighbour.create_publisher(TFMessage, frames.TF, 100)
        wait(lambda: pub.get_subscription_count() > 0, 60.0, "the planner's /tf subscription")
        clutter = [raw('clutter', f'clutter_{k}', (float(k), 0.0, 0.0), 0.0) for k in range(CLUTTER - 1)]
        commanded = []
        for k in range(1, 11):
            t = 1.0 + k * DT
            pose = (2.0 + 0.01 * k, 0.5, 0.0)   # each message's own: the wait knows it came
            pub.publish(cdr.tf_message_cdr([raw('map', 'r1/odom', pose, t), *clutter]))
            at(node, t)
            wait(functools.partial(holds, node, pose), 60.0, f'map -> r1/odom of {t:g} s')
            assert len(node.tf.tree.parents) <= 2 and not node.tf.tree.dropped   # no clutter kept
            commanded.append(drives(node, t))
        assert all(commanded) and node.tf.cut == 10
        state, _ = node.inputs.state(node.now())
        assert state is not None and state[:2] == pytest.approx([3.1, 1.5])   # the flood's last map -> odom
    finally:
        neighbour.destroy_node()
        node.destroy_node()


def test_a_stale_map_to_odom_is_refused_saying_how_old_and_tf_static_never_ages(context: Any) -> None:
    node = make(context)
    try:
        at(node, 1.0)
        node.tf.take(message(('map', 'r1/odom', (2.0, 0.5, 0.0), 1.0)))
        assert drives(node, 1.0)
        # The localizer stopped: 3.2 s later its transform is not where the robot is.
        assert tick(node, 4.2) == (DiagnosticStatus.WARN, 'waiting', (
            'waiting for localization on /tf (map -> r1/odom): map -> r1/odom from TF is 3.2 s old '
            '(transform_tolerance 0.3 s beyond the 1 s a localizer may take between two)'))
        assert not np.any(node.last_command != 0.0)
        node.tf.take(message(('map', 'r1/odom', (2.0, 0.5, 0.0), 4.2)))   # it is back
        assert drives(node, 4.25)
        node.tf.take_static(message(('map', 'r1/odom', (0.0, 0.0, 0.0), 0.0)))   # a fixed map -> odom
        assert drives(node, 100.0)
        state, _ = node.inputs.state(node.now())
        assert state is not None and tuple(state[:2]) == (1.0, 1.0)
    finally:
        node.destroy_node()


def test_an_older_or_far_future_map_to_odom_does_not_win(context: Any) -> None:
    """The localizer's newest transform holds against a late one, a neighbour's older one under another parent,
    and one stamped far in the future (which, kept, would stay the newest for ever)."""
    node = make(context)
    try:
        odometry(node, 5.0)
        node.tf.take(message(('map', 'r1/odom', (2.0, 0.5, 0.0), 5.0)))
        node.tf.take(message(('map', 'r1/odom', (9.0, 9.0, 0.0), 4.5)))     # late
        node.tf.take(message(('world', 'r1/odom', (5.0, 5.0, 0.0), 4.8)))   # a neighbour's older word
        state, problem = node.inputs.state(node.now())
        assert problem == '' and state is not None and state[:2] == pytest.approx([3.0, 1.5])
        node.tf.take(message(('map', 'r1/odom', (9.0, 9.0, 0.0), 5.0 + 1e6)))
        odometry(node, 5.1)
        node.tf.take(message(('map', 'r1/odom', (1.0, 0.0, 0.0), 5.1)))
        state, problem = node.inputs.state(node.now())
        assert problem == '' and state is not None and state[:2] == pytest.approx([2.0, 1.0])
    finally:
        node.destroy_node()


class Queue:
    """A stand-in for the listener's polled /tf subscription holding what came since the last poll."""

    def __init__(self, messages: list[bytes]) -> None:
        self.messages = messages
        self.msg_type = TFMessage
        self.handle = self

    def take_message(self, _cls: Any, _raw: bool) -> tuple[bytes, None] | None:
        return (self.messages.pop(0), None) if self.messages else None

    def take_all(self) -> list[Any]:
        out = [deserialize_message(m, TFMessage) for m in self.messages]
        self.messages.clear()
        return out

    def destroy(self) -> None:
        pass


def test_many_small_messages_between_two_lookups_are_read_whole_up_to_the_poll_bound(context: Any) -> None:
    node = make(context)
    try:
        odometry(node, 2.0)
        size = TF_MESSAGE_TRANSFORMS // 2
        batches = [[raw('clutter', f'c{m}_{i}', (0.0, 0.0, 0.0), 2.0) for i in range(size)] for m in range(10)]
        batches[-1].append(raw('map', 'r1/odom', (2.0, 0.5, 0.0), 2.0))   # in a message past the bound
        node.tf.dynamic = Queue([cdr.tf_message_cdr(batch) for batch in batches])   # type: ignore[assignment]  # a stand-in
        state, problem = node.inputs.state(node.now())
        assert problem == '' and state is not None and state[:2] == pytest.approx([3.0, 1.5])
        # The first TF_POLL_TRANSFORMS read whole (FRAMES_MAX of them kept), the messages after cut to r1/odom.
        assert len(node.tf.tree.parents) == FRAMES_MAX and node.tf.tree.dropped == TF_POLL_TRANSFORMS + 1 - FRAMES_MAX
        assert node.tf.cut == 10 - TF_POLL_TRANSFORMS // size
    finally:
        node.destroy_node()


def test_a_localizer_whose_map_to_odom_rides_only_in_a_flood_drives_the_robot_at_every_tick(context: Any) -> None:
    """benchmarks.hostile_inputs' tf_flood: once the robot drives, the localizer's map -> odom comes only inside
    messages of 20,000 transforms, which its rclpy took 0.1-0.3 s to serialise after stamping them, at ~3.5 Hz:
    each arrived 0.15 s old and was 0.45 s old before the next came. Judged stale past transform_tolerance (0.3 s),
    the robot held between two and ended `waiting`. It is read from each message (cut to the frames looked up), and
    it drives at every tick; a localizer that stops is still found out, TF_LOCALIZER_INTERVAL plus
    transform_tolerance after its last transform."""
    node = make(context)
    try:
        clutter = [raw('clutter', f'clutter_{k}', (float(k), 0.0, 0.0), 0.0) for k in range(CLUTTER - 1)]
        period, late = 0.3, 0.15
        stamps = [1.0 + period * k for k in range(10)]
        flood = [cdr.tf_message_cdr([raw('map', 'r1/odom', (2.0 + 0.01 * k, 0.5, 0.0), stamp), *clutter])
                 for k, stamp in enumerate(stamps)]
        queue = Queue([])
        node.tf.dynamic = queue   # type: ignore[assignment]  # a stand-in: what came since the last poll
        waiting = []
        for step in range(23, int(round(6.0 / DT))):   # 1.15 s, the first message's arrival, to 6 s
            t = step * DT
            queue.messages.extend(m for m, stamp in zip(flood, stamps) if t - 1e-9 <= stamp + late < t + DT - 1e-9)
            status = tick(node, t)
            if status[1] == 'waiting':
                waiting.append((round(t, 2), status[2]))
            elif t <= stamps[-1] + late + TF_LOCALIZER_INTERVAL:
                assert status[1] in DRIVING and np.any(node.last_command != 0.0), status
        stopped = stamps[-1] + TF_LOCALIZER_INTERVAL + 0.3   # the localizer's last transform, and what it may take
        assert waiting and all(t > stopped for t, _ in waiting), waiting[:3]
        assert waiting[0][1].startswith('waiting for localization on /tf (map -> r1/odom): map -> r1/odom from TF is '
                                        '1.4 s old')
        assert node.tf.cut == len(flood) and len(node.tf.tree.parents) <= 2
    finally:
        node.destroy_node()
