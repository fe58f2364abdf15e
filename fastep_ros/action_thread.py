"""The planner's Nav2 action servers on a node and a thread of their own: `<planner>_navigation`.

rclpy's ActionServer takes a goal request and converts it into Python messages (ActionServer.take_data: a
PoseStamped is six Python objects, 100,000 poses about 4 s on a 2-core machine) on the executor that spins the
server's node, before any callback can look at it. On the planner's executor that conversion ran between two
control ticks: cmd_vel stopped for up to 5 s (benchmarks/hostile_inputs.py, many_poses). So the three servers
(fastep_ros.navigate_actions) live on a node of their own, `<planner node name>_navigation` in the planner's
namespace (the action names clients use are the planner's as before: `<ns>/navigate_to_pose`, ...), spun by a
SingleThreadedExecutor of its own on the thread `ActionThread` starts. The conversion runs there, in Python code
(the message classes' __init__), so the GIL passes to the planner's executor every switch interval (the planner
sets 0.5 ms) and the control tick keeps its rate.

What runs on this thread: taking the requests (goal, cancel, result, expiry), the goal callback (accepted while
the planner is active), the cancel callback (accepted: rclpy marks the goal CANCELING), the execute coroutine,
which posts an ActionGoal (fastep_ros.planner_threads) to `inbox` and awaits its `done`, then makes the goal's
terminal transition the planner chose and returns its result, and rclpy's sending of results and expiry of ended
goals. Everything else of a goal (its poses checked, driving, feedback, its end) is the planner executor's, which
drains `inbox` on its control tick (NavigateActions.check). The node keeps wall time: it has no /clock
subscription of its own, so goal stamps and ACTION_RESULT_TIMEOUT are wall seconds.

Why the hand-over is thread-safe (rclpy 7.1.6: rclpy/action/server.py, task.py, executors.py,
src/rclpy/action_server.cpp):

- `inbox` is a queue.SimpleQueue: put on this thread, drained whole on the planner's executor.
- `done` is an rclpy Future made here without an executor. Future.set_result takes the Future's lock and calls no
  callback (the execute coroutine awaits it by polling: Future.__await__ yields while it is pending, and the
  executor resumes every pending task each time it wakes). So the planner's side sets it and then wakes this
  executor (`wake`: Executor.wake triggers the executor's guard condition; rcl_trigger_guard_condition is
  thread-safe, and it is how rclpy's own create_task and context shutdown wake an executor from other threads).
  A trigger persists until the next wait, so a wake while this thread is busy is not lost. The executor here is
  a SingleThreadedExecutor whatever the planner spins on (the EventsExecutor has no guard conditions to wake it).
- Feedback is published from the planner's side: ServerGoalHandle.publish_feedback takes only the goal handle's
  own lock, and the C++ ActionServer.publish_feedback (rcl_action_publish_feedback, an rcl_publish) runs with the
  GIL held (no gil_scoped_release in action_server.cpp), so it cannot interleave with another rcl_action call
  made from Python, as rclpy's MultiThreadedExecutor already relies on when execute callbacks publish feedback.
  is_cancel_requested (read by the planner each tick) is a status read under the same handle lock.
- The terminal transition (succeed, abort, canceled) is made HERE, by the execute coroutine, not by the planner:
  ServerGoalHandle._update_state calls ActionServer.notify_goal_done, which takes the server's lock, and this
  thread holds that lock in take_data for the whole conversion of a request (seconds for 100,000 poses); made by
  the planner it would stop the control tick for as long. Made here, notify_goal_done also rearms the
  result_timeout expiry timer on the thread whose wait set holds it (rclpy._execute_goal then sets the result
  future and the result goes out).
- The collector: a request's conversion makes its objects by the hundred thousand, and each full collection
  (generation 2) traverses every object tracked, holding the GIL: 16 to 95 ms apiece, six of them while 100,000
  poses were converted (load 8). So no full collection runs while a goal request is taken (`collector_held`:
  the threshold of generation 2 raised, process-wide, for as long as any action thread takes one; the young
  generations are still collected), and a request of more than FREEZE_POSES poses is moved out of the
  collector's sight once converted (gc.freeze, as node_main does after building the nodes: its objects are still
  freed by their reference counts; what was garbage in cycles at that moment stays). Once its goal ended, the
  execute coroutine frees its poses RELEASE_CHUNK at a time (`release_poses`): freed at once, 100,000 poses held
  the GIL for 40-60 ms.
- Stopping: `stop` sets a flag and wakes the executor; this thread spins a few more times without waiting (the
  answers posted before the stop go out), then destroys the servers, shuts its executor down and destroys its
  node, itself, so nothing is used by two threads while it is destroyed; `stop` joins it.
"""

from __future__ import annotations

import contextlib
import gc
import queue
import threading
from typing import Any, Callable, Iterator

from rclpy.executors import ExternalShutdownException, ShutdownException

from fastep_ros.executors import make_executor
from fastep_ros.limits import GOAL_POSES_MAX

__all__ = ['ActionThread', 'FREEZE_POSES', 'NODE_SUFFIX', 'RELEASE_CHUNK', 'collector_held', 'release_poses']

NODE_SUFFIX = '_navigation'   # the node's name: the planner's and this
IDLE_WAKE = 1.0               # s: the longest the executor waits when nothing wakes it (a stop wakes it: stop)
FLUSH_SPINS = 20              # spins without waiting once stopping: answers posted before the stop go out


FREEZE_POSES = GOAL_POSES_MAX   # a goal request with more poses is moved out of the collector's sight, converted
RELEASE_CHUNK = 1000            # poses freed at a time once a goal ended (about 0.5 ms of the GIL each)
_FULL_COLLECTIONS_OFF = 2 ** 31 - 1
_held = [0]                     # action threads taking a request now (under _collector_lock) ...
_saved: list[tuple[int, ...]] = []   # ... and the thresholds before the first of them
_collector_lock = threading.Lock()


@contextlib.contextmanager
def collector_held() -> Iterator[None]:
    """No full collection while this runs (any thread's allocations included); the young generations are still
    collected. Process-wide and nested: the thresholds come back when the last action thread leaves."""
    with _collector_lock:
        if _held[0] == 0:
            _saved[:] = [gc.get_threshold()]
            first, second = _saved[0][:2]
            gc.set_threshold(first, second, _FULL_COLLECTIONS_OFF)
        _held[0] += 1
    try:
        yield
    finally:
        with _collector_lock:
            _held[0] -= 1
            if _held[0] == 0:
                gc.set_threshold(*_saved[0])


def release_poses(goal: Any) -> None:
    """A goal's poses freed RELEASE_CHUNK at a time, the GIL free for other threads between two chunks (the goal's
    message keeps an empty list). Its run's own list (GoalPoses.given) and missed waypoints keep the poses they
    name."""
    poses = getattr(goal, 'poses', None)
    if not isinstance(poses, list):
        return
    while poses:
        del poses[-RELEASE_CHUNK:]


def _server_class() -> type:
    """rclpy's ActionServer, taking a goal request with the collector held (module docstring)."""
    from rclpy.action import ActionServer

    class Server(ActionServer):
        def take_data(self) -> Any:
            if not getattr(self, '_is_goal_request_ready', True):   # rclpy's is_ready sets it before take_data
                return super().take_data()
            with collector_held():
                data = super().take_data()
                taken = data.get('goal') if isinstance(data, dict) else None
                if taken is not None and len(getattr(taken[1].goal, 'poses', ())) > FREEZE_POSES:
                    gc.freeze()
            return data
    return Server


class ActionThread:
    """A node in the planner's namespace for the action servers, and the thread that spins it (module docstring).

    The planner's executor makes it (NavigateActions, in configure), makes the servers on it (`serve`), starts it,
    drains `take`, answers through the goals' Futures and `wake`, and ends it with `stop` (cleanup, shutdown,
    destroy_node). This thread only spins: the callbacks the servers were given run here."""

    def __init__(self, planner: Any) -> None:
        from rclpy.node import Node
        from rclpy.parameter import Parameter
        self.name = f'{planner.get_name()}{NODE_SUFFIX}'
        self.logger = planner.get_logger()
        namespace = planner.get_namespace()
        # The process's own remappings (-r __node:=..., -r __ns:=...) would rename this node like the planner: its
        # name and namespace are given as node-local arguments, which rcl applies before the process's.
        self.node = Node(self.name, namespace=namespace, context=planner.context,
                         cli_args=['--ros-args', '-r', f'__node:={self.name}', '-r', f'__ns:={namespace}'],
                         start_parameter_services=False,
                         parameter_overrides=[Parameter('use_sim_time', value=False)])
        self.executor = make_executor('single', context=planner.context)
        self.executor.add_node(self.node)
        self.servers: list[Any] = []
        self.inbox: queue.SimpleQueue[Any] = queue.SimpleQueue()
        self._stopping = threading.Event()
        # rclpy's Executor.wake() only makes a waiting spin_once look again: with no callback ready it waits on
        # until its timeout, and a stop would wait up to IDLE_WAKE. A guard condition with a callback is work:
        # spin_once returns and the loop sees the stop.
        self._stop_guard = self.node.create_guard_condition(lambda: None)
        self.thread = threading.Thread(target=self._spin, name=self.name, daemon=True)
        self.ident: int | None = None   # the thread's, once it runs (tests)
        self._released = False

    def serve(self, action: Any, name: str, execute: Callable[[Any], Any], **options: Any) -> Any:
        """An rclpy ActionServer for `action` on this node (before `start`: nothing spins it yet)."""
        server = _server_class()(self.node, action, name, execute, **options)
        self.servers.append(server)
        return server

    def start(self) -> None:
        self.thread.start()

    # ------------------------------------------------------------------------------------------ hand-over
    def post(self, item: Any) -> None:
        """This thread: a request for the planner's executor."""
        self.inbox.put(item)

    def take(self) -> list[Any]:
        """The planner's executor: every request posted since the last take, in order."""
        items = []
        while True:
            try:
                items.append(self.inbox.get_nowait())
            except queue.Empty:
                return items

    def wake(self) -> None:
        """Any thread: the executor looks again (a goal's Future was set: its coroutine resumes)."""
        if self._released:
            return
        try:
            self.executor.wake()
        except Exception:  # noqa: BLE001  the context shut down and this thread released its executor meanwhile
            pass

    # ------------------------------------------------------------------------------------------ the thread
    def _spin(self) -> None:
        self.ident = threading.get_ident()
        context = self.node.context
        warned = False
        try:
            while not self._stopping.is_set() and context.ok():
                try:
                    self.executor.spin_once(timeout_sec=IDLE_WAKE)
                except (ExternalShutdownException, ShutdownException):
                    return
                except Exception as exc:  # noqa: BLE001  a bad request is one line, never the end of the servers
                    if not context.ok():
                        return
                    if not warned:
                        self.logger.error(f'{self.name}: {type(exc).__name__}: {exc}'.splitlines()[0])
                        warned = True
            for _ in range(FLUSH_SPINS):
                if not context.ok():
                    return
                self.executor.spin_once(timeout_sec=0.0)
        except (ExternalShutdownException, ShutdownException):
            return
        except Exception:  # noqa: BLE001  stopping: what is left is released below
            return
        finally:
            self._release()

    def _release(self) -> None:
        """The servers, the executor and the node destroyed (on this thread, or by `stop` if it never ran)."""
        if self._released:
            return
        self._released = True
        for server in self.servers:
            try:
                server.destroy()
            except Exception:  # noqa: BLE001  the context already shut down: nothing left to release
                pass
        self.servers.clear()
        try:
            self.executor.shutdown()
        finally:
            self.node.destroy_node()

    def stop(self, timeout: float) -> bool:
        """End the thread (its servers and node destroyed) within `timeout` seconds; False if it still runs (a
        request under conversion: it releases everything itself when done)."""
        self._stopping.set()
        if not self.thread.is_alive() and self.thread.ident is None:   # never started
            self._release()
            return True
        if not self._released:
            try:
                self._stop_guard.trigger()
            except Exception:  # noqa: BLE001  the thread released its node meanwhile (the context shut down)
                pass
        self.thread.join(timeout)
        return not self.thread.is_alive()
