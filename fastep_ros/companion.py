"""The planner's other Nav2 servers, beside its navigation actions: what each group of them is to NavigateActions.

NavigateActions (fastep_ros/navigate_actions.py) makes the action thread and its node, and with them every group
`companion_classes()` lists there: paths (fastep_ros/path_actions.py), behaviours (behaviour_actions.py), costmap
clearing (costmap_services.py). Each is a `Companion`; `CompanionServers` is what they share.
"""

from __future__ import annotations

from typing import Any, Protocol

__all__ = ['PREEMPTED', 'Companion', 'CompanionServers']

PREEMPTED = 0   # Nav2's error code for a goal preempted: accept_pending_goal aborts it with empty_result()


class Companion(Protocol):
    """Another group of Nav2 servers on the navigation node and its thread (NavigateActions.side), made with the
    NavigateActions in configure: `served` maps action names to nav2_msgs actions (their goals are accepted, posted
    and ended as NavigateActions' are); services it makes itself on `side.node` (their callbacks run on the action
    thread). On the planner's executor: `start` takes a goal handed over (ActionGoal; not `active`, or accepted
    before a deactivation since: it ends aborted), `check` runs every control tick, `end` ends a goal handed over
    (its terminal state and result to the goal's Future, then `side.wake()`), `destroy` ends all it has (cleanup)."""

    served: dict[str, Any]

    def start(self, goal: Any, active: bool) -> None: ...
    def check(self) -> None: ...
    def end(self, goal: Any, how: str, message: str) -> None: ...
    def destroy(self) -> None: ...


class CompanionServers:
    """What every Companion shares: its NavigateActions (`actions`: the node, the action thread `side`) and ending
    a goal handed over with a result of its action (`end`)."""

    served: dict[str, Any] = {}

    def __init__(self, actions: Any) -> None:
        self.actions = actions
        self.node = actions.node

    def start(self, goal: Any, active: bool) -> None:
        self.end(goal, 'aborted', f'{goal.kind} is not served by fastep')

    def check(self) -> None:
        pass

    def end(self, goal: Any, how: str, message: str, code: int | None = None, **fields: Any) -> None:
        """`goal` ended `how` ('succeeded', 'canceled', 'aborted'): its result with `code` (default: the action's
        UNKNOWN for an abort, else 0), `message` and `fields`, handed to its execute coroutine (which the action
        thread then resumes to make the transition and send the result)."""
        if goal.done.done():
            return
        result = self.served[goal.kind].Result()
        if code is None:
            code = int(getattr(result, 'UNKNOWN', 0)) if how == 'aborted' else 0
        result.error_code, result.error_msg = code, message
        for name, value in fields.items():
            setattr(result, name, value)
        if how not in ('succeeded', 'canceled'):
            self.node.get_logger().info(f'{goal.kind} goal aborted: {message}')
        goal.done.set_result((how, result))
        self.actions.side.wake()

    def destroy(self) -> None:
        pass
