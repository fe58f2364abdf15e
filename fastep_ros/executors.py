"""Which rclpy executor a fastep node process spins on: rclpy's SingleThreadedExecutor or its EventsExecutor.

    FASTEP_EXECUTOR=events|single   (environment; fastep-launch --executor sets it for every node it starts)

`single` is rclpy's SingleThreadedExecutor: a Python loop that rebuilds a wait set on every wake-up. `events`
is rclpy.experimental.EventsExecutor: a C++ event queue fed by the middleware's listeners, so a message costs the
callback and the conversion, not a wait-set rebuild. It costs less CPU for every node and layout
(docs/benchmarks.md, "Executors and process layouts"), so it is DEFAULT_EXECUTOR; exact lock step
(fastep_ros.lock_step) does not depend on the order callbacks run in, so runs equal fastep-sim's on both.

Both are driven by fastep_ros.common's spin loop; timers on simulated time and the /clock guard
(common.guard_clock) work on both (tests/fastep_ros/test_executors.py).
"""

from __future__ import annotations

import inspect
import os
from typing import Any, Callable

from rclpy.executors import Executor, SingleThreadedExecutor

from fastep_ros.errors import StartupError

__all__ = ['DEFAULT_EXECUTOR', 'EXECUTORS', 'EXECUTOR_ENV', 'MessageInfoCallback', 'executor_kind', 'make_executor']

EXECUTOR_ENV = 'FASTEP_EXECUTOR'
EXECUTORS = ('events', 'single')
DEFAULT_EXECUTOR = 'events'


class _SingleThreaded(SingleThreadedExecutor):
    """rclpy's, with a class default for the attribute its __del__ reads: a stop (the context shut down by a
    signal) while its __init__ runs left the object without it, and Python printed an AttributeError from __del__."""

    _sigint_gc = None  # type: ignore[assignment]  # only read when __init__ did not set it


def executor_kind(kind: str | None = None) -> str:
    """`kind`, else $FASTEP_EXECUTOR, else DEFAULT_EXECUTOR; a StartupError (one line, exit 2) if unknown."""
    chosen = kind or os.environ.get(EXECUTOR_ENV, '').strip() or DEFAULT_EXECUTOR
    if chosen not in EXECUTORS:
        raise StartupError(f'{EXECUTOR_ENV} must be one of {", ".join(EXECUTORS)}, got {chosen!r}')
    return chosen


def make_executor(kind: str | None = None, context: Any = None) -> Executor:
    """A new executor of the chosen kind (executor_kind) on `context` (rclpy's default one if None)."""
    if executor_kind(kind) == 'events':
        from rclpy.experimental import EventsExecutor
        return EventsExecutor(context=context)
    return _SingleThreaded(context=context)


class MessageInfoCallback:
    """A subscription callback that takes (message, message info) on either executor.

    rclpy's Subscription gives a callback the message info when its signature takes two arguments. The
    SingleThreadedExecutor then calls callback(msg, info); rclpy 7.1.6's EventsExecutor calls callback((msg, info)),
    one tuple, and a plain two-parameter function failed inside spin_once ("SystemError: null argument to
    internal routine": the plant's cmd_vel callback ended the node). This object shows rclpy a two-parameter
    signature and accepts both calls.
    """

    __signature__ = inspect.Signature([inspect.Parameter('msg', inspect.Parameter.POSITIONAL_ONLY),
                                       inspect.Parameter('info', inspect.Parameter.POSITIONAL_ONLY)])

    def __init__(self, callback: Callable[[Any, Any], None]) -> None:
        self.callback = callback

    def __call__(self, *args: Any) -> None:
        if len(args) == 1 and isinstance(args[0], tuple) and len(args[0]) == 2:
            args = args[0]
        self.callback(*args)
