"""The planner's Nav2 action servers on a node and a thread of their own (fastep_ros/action_thread.py): a goal's
request is taken and converted there, never on the executor that runs the planner's control tick, on either
executor a planner process spins; the goal's logic (its poses refused, its result) still answers; cleanup joins
the thread and destroys its node. Structural: which thread did what, never how long it took."""

from __future__ import annotations

import gc
import threading
from typing import Any

import pytest
from rclpy.parameter import Parameter

from fastep_ros.planner import PlannerNode
from fastep_testing.services import Services
from msg_tools.convert import point_to_pose_stamped

pytest.importorskip('nav2_msgs.action', reason='nav2_msgs is built by make (interfaces/build.sh)')

NS = '/r1'
ABORTED, CANCELED = 6, 5   # action_msgs/GoalStatus


def _planner(context: Any, **params: Any) -> PlannerNode:
    values = {'planning_thread': False, 'workspace': [0.0, 0.0, 20.0, 20.0], **params}
    return PlannerNode(context=context, namespace=NS,
                       parameter_overrides=[Parameter(k, value=v) for k, v in values.items()])


def _answer(services: Services, future: Any, what: str) -> Any:
    assert services.spin_until(future.done, 60.0), what
    return future.result()


@pytest.mark.parametrize('executor', ['events', 'single'])
def test_a_goal_request_is_converted_on_the_action_thread_while_the_control_tick_runs_on_the_executor(
        context: Any, executor: str, monkeypatch: pytest.MonkeyPatch) -> None:
    from nav2_msgs.action import NavigateThroughPoses, NavigateToPose
    from rclpy.action import ActionClient
    from rclpy.action.server import ActionServer

    from fastep_ros.limits import GOAL_POSES_MAX
    taken: list[tuple[int, str, str]] = []   # every goal request rclpy took: (thread, node, namespace)
    held: list[int] = []                     # generation 2's threshold while it was taken
    take_data = ActionServer.take_data

    def recording_take_data(server: Any) -> Any:
        data = take_data(server)
        if 'goal' in data:   # converted into Python messages just now, in take_goal_request
            taken.append((threading.get_ident(), server._node.get_name(), server._node.get_namespace()))
            held.append(gc.get_threshold()[2])
        return data
    monkeypatch.setattr(ActionServer, 'take_data', recording_take_data)
    ticks: list[int] = []   # the threads the control tick ran on
    on_control = PlannerNode.on_control

    def recording_on_control(node: PlannerNode, at: float | None = None) -> None:
        ticks.append(threading.get_ident())
        on_control(node, at)
    monkeypatch.setattr(PlannerNode, 'on_control', recording_on_control)

    planner = _planner(context)
    services = Services(context, planner, executor)   # spins the planner (and the client) on this thread
    try:
        actions = planner.actions
        assert actions is not None
        # The servers are not the planner node's: on `planner_navigation` in its namespace, on the graph.
        assert all(server._node is not planner for server in actions.servers)
        assert (actions.side.node.get_name(), actions.side.node.get_namespace()) == ('planner_navigation', NS)
        assert not any(type(w).__name__ == 'ActionServer' for w in planner.waitables)
        assert services.spin_until(lambda: ('planner_navigation', NS) in
                                   services.client.get_node_names_and_namespaces(), 30.0)

        through = ActionClient(services.client, NavigateThroughPoses, f'{NS}/navigate_through_poses')
        to_pose = ActionClient(services.client, NavigateToPose, f'{NS}/navigate_to_pose')
        assert services.spin_until(lambda: through.server_is_ready() and to_pose.server_is_ready(), 30.0)
        # One pose more than a goal may have: converted on the action thread, refused by the planner's side.
        too_many = NavigateThroughPoses.Goal(poses=[point_to_pose_stamped((4.0, 10.0))] * (GOAL_POSES_MAX + 1))
        handle = _answer(services, through.send_goal_async(too_many), 'the goal to be answered')
        assert handle.accepted
        done = _answer(services, handle.get_result_async(), 'the result')
        assert (done.status, done.result.error_code) == (ABORTED, 200)
        assert f'{GOAL_POSES_MAX + 1} poses' in done.result.error_msg, done.result.error_msg
        # A goal the planner takes (no world yet: it waits for one), cancelled: CANCELED, as before.
        handle = _answer(services, to_pose.send_goal_async(NavigateToPose.Goal(pose=point_to_pose_stamped((4.0, 9.0)))),
                         'the second goal to be answered')
        assert handle.accepted
        _answer(services, handle.cancel_goal_async(), 'the cancel')
        assert _answer(services, handle.get_result_async(), 'the cancelled result').status == CANCELED

        here = threading.get_ident()   # the planner's executor's thread
        assert ticks and set(ticks) == {here}
        assert len(taken) == 2 and {t[1:] for t in taken} == {('planner_navigation', NS)}, taken
        assert {t[0] for t in taken} == {actions.side.ident} and here not in {t[0] for t in taken}
        assert min(held) > 10 ** 9   # no full collection while a request is converted (collector_held)
    finally:
        services.close()


def test_the_action_thread_is_made_by_configure_and_joined_by_cleanup(context: Any) -> None:
    """Nav2's order: unconfigured, no action node and no thread; configured (inactive), both, and a goal is
    rejected; cleaned up, the thread joined and the node gone from the graph; configured again, both afresh."""
    from nav2_msgs.action import NavigateToPose
    from rclpy.action import ActionClient
    planner = _planner(context, autostart=False)
    services = Services(context, planner)
    threads = threading.active_count()
    try:
        assert planner.actions is None and threading.active_count() == threads
        for _ in range(2):
            assert services.change_state('configure')
            actions = planner.actions
            assert actions is not None and actions.side.thread.is_alive()
            client = ActionClient(services.client, NavigateToPose, f'{NS}/navigate_to_pose')
            assert services.spin_until(client.server_is_ready, 30.0)
            goal = NavigateToPose.Goal(pose=point_to_pose_stamped((4.0, 9.0)))
            assert not _answer(services, client.send_goal_async(goal), 'the goal to be answered').accepted
            client.destroy()
            assert services.change_state('cleanup')
            assert planner.actions is None and not actions.side.thread.is_alive()
            assert threading.active_count() == threads
            assert services.spin_until(lambda: ('planner_navigation', NS) not in
                                       services.client.get_node_names_and_namespaces(), 30.0)
    finally:
        services.close()


def test_a_stop_ends_the_thread_while_its_executor_waits_with_nothing_to_do(
        context: Any, monkeypatch: pytest.MonkeyPatch) -> None:
    """rclpy's Executor.wake() does not end a spin_once that has no callback ready: a stop waited for the idle
    timeout (0.8 s a planner at every process's end). With that timeout at two minutes, a stop still ends the
    thread: it is woken, not timed out."""
    from fastep_ros import action_thread
    monkeypatch.setattr(action_thread, 'IDLE_WAKE', 120.0)
    planner = _planner(context, autostart=False)
    side = action_thread.ActionThread(planner)
    try:
        side.start()
        assert side.thread.is_alive()
        threading.Event().wait(0.3)   # into its wait: nothing is served, nothing comes
        assert side.stop(60.0), 'the action thread waited for its idle timeout'
        assert not side.thread.is_alive()
    finally:
        side.stop(1.0)
        planner.destroy_node()


def test_the_collector_is_held_while_any_request_is_taken_and_a_goal_s_poses_are_freed_in_chunks() -> None:
    """collector_held: generation 2's threshold off while any action thread takes a request (nested, as two
    planners' threads in one process may), back as it was after the last; release_poses empties a goal's list."""
    from geometry_msgs.msg import PoseStamped
    from nav2_msgs.action import NavigateThroughPoses

    from fastep_ros.action_thread import RELEASE_CHUNK, collector_held, release_poses
    before = gc.get_threshold()
    with collector_held():
        assert gc.get_threshold()[:2] == before[:2] and gc.get_threshold()[2] > 10 ** 9
        with collector_held():
            assert gc.get_threshold()[2] > 10 ** 9
        assert gc.get_threshold()[2] > 10 ** 9   # the outer one still takes its request
    assert gc.get_threshold() == before
    kept = PoseStamped()
    goal = NavigateThroughPoses.Goal(poses=[kept] + [PoseStamped() for _ in range(2 * RELEASE_CHUNK + 1)])
    mine = list(goal.poses)   # a run's own list (GoalPoses.given) keeps what it names
    release_poses(goal)
    assert list(goal.poses) == [] and mine[0] is kept and len(mine) == 2 * RELEASE_CHUNK + 2
    release_poses(NavigateThroughPoses.Goal())   # nothing to free
