"""Small helpers shared by the fastep_ros nodes: parameter declaration, the main() wrapper.

Topic names and QoS profiles are in msg_tools.interface.
"""

from __future__ import annotations

import copy
import functools
import gc
import math
import os
import signal
import sys
import time
import weakref
from dataclasses import Field, dataclass
from typing import Any, Callable, Sequence

import rclpy
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import InvalidParameterValueException, ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.signals import SignalHandlerOptions

from fastep_core.cli import guard
from fastep_core.errors import FastepError
from fastep_ros.errors import StartupError  # re-exported: every node raises it next to declare()
from fastep_ros.executors import make_executor
from fastep_ros.limits import CLOCK_JUMP_LIMIT, PERIOD_RANGE, RATE_RANGE  # re-exported for the nodes
from fastep_ros.parameters import warn_unknown_overrides

__all__ = ['CLOCK_JUMP_LIMIT', 'GATE_ENV', 'PERIOD_RANGE', 'RATE_RANGE', 'ClockGuard', 'Param', 'StartupError',
           'check_range', 'declare', 'declare_empty_array', 'declare_strings', 'declare_table', 'declared',
           'guard_clock', 'node_main', 'quiet_at_stop', 'unit_suffix']


INT64_MAX = 2**63 - 1

_TYPES = {bool: Parameter.Type.BOOL, int: Parameter.Type.INTEGER, float: Parameter.Type.DOUBLE,
          str: Parameter.Type.STRING}


def _widen_integer_override(node: Node, name: str, default: Any) -> None:
    """Let `-p rtf:=5` / `-p start:=[5, 25]` set a double (array) parameter, as a user would expect.

    rclpy keeps command-line overrides in Node._parameter_overrides; if that ever changes, integers are
    simply refused with the one-line error below.
    """
    overrides = getattr(node, '_parameter_overrides', None)
    if not isinstance(overrides, dict) or name not in overrides:
        return
    given = overrides[name]
    if isinstance(default, float) and given.type_ == Parameter.Type.INTEGER:
        overrides[name] = Parameter(name, Parameter.Type.DOUBLE, float(given.value))
    elif default is None and given.type_ == Parameter.Type.INTEGER_ARRAY:
        overrides[name] = Parameter(name, Parameter.Type.DOUBLE_ARRAY, [float(v) for v in given.value])


def _descriptor_range(descriptor: ParameterDescriptor, default: Any, value_range: tuple[float, float]) -> None:
    """Put value_range into the descriptor as ROS tools read it (integer_range / floating_point_range)."""
    low, high = value_range
    if isinstance(default, bool):
        return
    if isinstance(default, int):
        descriptor.integer_range = [IntegerRange(from_value=int(max(low, -INT64_MAX)),
                                                 to_value=int(min(high, INT64_MAX)), step=1)]
    elif isinstance(default, float):
        # An open end is the largest double: tools (rqt_reconfigure, `ros2 param describe`) expect finite bounds.
        descriptor.floating_point_range = [FloatingPointRange(from_value=max(float(low), -sys.float_info.max),
                                                              to_value=min(float(high), sys.float_info.max), step=0.0)]


def declare_empty_array(node: Node, name: str, kind: Parameter.Type, descriptor: ParameterDescriptor) -> list[Any]:
    """An array parameter of type `kind` whose default is []; returns its value. Declared by its type alone it
    had no value (GetParameters answered an empty list for it, and parameter dumps broke), and rclpy infers an
    empty list's type as a byte array: it is declared writable, given [] unless overridden, then made read-only
    if the descriptor says so. Raises rclpy's ParameterException for an override of another type."""
    writable = copy.deepcopy(descriptor)
    writable.read_only = False
    if node.declare_parameter(name, kind, writable).type_ == Parameter.Type.NOT_SET:
        node.set_parameters([Parameter(name, kind, [])])
    descriptor.type = writable.type
    node.set_descriptor(name, descriptor)
    return list(node.get_parameter(name).value)


def declare_strings(node: Node, name: str, description: str) -> list[str]:
    """Declare a read-only string array parameter whose default is [] and return its value, the empty strings left
    out (a launch file's ['']). Given as `[]` on the command line, rclpy had no type for it (a traceback); a value
    of another type is a StartupError with one line."""
    descriptor = ParameterDescriptor(name=name, type=Parameter.Type.STRING_ARRAY.value, read_only=True,
                                     description=description)
    try:
        value = declare_empty_array(node, name, Parameter.Type.STRING_ARRAY, descriptor)
    except ParameterException as exc:
        raise StartupError(f'parameter {name} must be a string array: {exc}') from None
    return [str(each) for each in value or [] if each]


_DECLARED: weakref.WeakKeyDictionary[Node, dict[str, Param]] = weakref.WeakKeyDictionary()


def unit_suffix(unit: str) -> str:
    """A unit as it follows a number in a message: ' m/s'; '' for none."""
    return f' {unit.strip()}' if unit.strip() else ''


def declared(node: Node) -> dict[str, Param]:
    """What `declare` was given for each parameter of the node, by name, in declaration order: the unit and the
    component a descriptor has no field for (the reference pages, fastep_ros.reference, show them)."""
    return dict(_DECLARED.get(node, {}))


def declare(node: Node, name: str, default: Any, description: str, *, read_only: bool = True,
            constraints: str = '', value_range: tuple[float, float] | None = None, unit: str = '',
            component: str = '') -> Any:
    """Declare a statically typed parameter with a description and return its value.

    `default` None declares a double array whose default is empty ([]). value_range (low, high) goes into the
    descriptor as integer_range / floating_point_range, which rclpy enforces on every set (the override included:
    a value outside it is a StartupError here, `unit` after the range); constraints is free text beside it.
    unit: the value's unit ('m/s'; '' for a count or a ratio); component: the part of the node it sets, its
    section of the reference page (fastep_ros.reference).
    read_only False: the node changes it at runtime (fastep_ros.parameters.DynamicParameters).
    Integers are accepted for doubles; any other wrong type is a StartupError with one line.
    """
    _DECLARED.setdefault(node, {})[name] = Param(name, default, description, constraints, value_range, unit.strip(),
                                                 read_only, component)
    if value_range is not None and not constraints:
        constraints = f'range [{value_range[0]:g}, {value_range[1]:g}]{unit_suffix(unit)}'
    descriptor = ParameterDescriptor(name=name, description=description, read_only=read_only,
                                     additional_constraints=constraints)
    if value_range is not None:
        _descriptor_range(descriptor, default, value_range)
    _widen_integer_override(node, name, default)
    try:
        if default is None:
            value = declare_empty_array(node, name, Parameter.Type.DOUBLE_ARRAY, descriptor)
        else:
            value = node.declare_parameter(name, default, descriptor).value
    except InvalidParameterValueException as exc:
        if value_range is not None:
            override = getattr(node, '_parameter_overrides', {}).get(name)
            given = None if override is None else override.value
            if isinstance(given, (int, float)) and not math.isfinite(given):
                raise StartupError(f'parameter {name} must be finite, got {given}') from None
            shown = f'{given:g}' if isinstance(given, (int, float)) else str(exc)
            raise StartupError(f'parameter {name} must be in [{value_range[0]:g}, {value_range[1]:g}]'
                               f'{unit_suffix(unit)}, got {shown}') from None
        raise StartupError(f'parameter {name}: {exc}') from None
    except ParameterException as exc:
        kind = _TYPES.get(type(default), Parameter.Type.DOUBLE_ARRAY).name.lower().replace('_', ' ')
        raise StartupError(f'parameter {name} must be of type {kind}: {exc}') from None
    if isinstance(value, float) and not math.isfinite(value):
        raise StartupError(f'parameter {name} must be finite, got {value}')
    if isinstance(value, list) and not all(math.isfinite(v) for v in value if isinstance(v, float)):
        raise StartupError(f'parameter {name} must be finite, got {value}')
    return value


@dataclass(frozen=True)
class Param:
    """One parameter of a node's table: what `declare` is given (a node declares its table in one loop)."""

    name: str
    default: Any
    description: str
    constraints: str = ''
    value_range: tuple[float, float] | None = None
    unit: str = ''
    read_only: bool = True
    component: str = ''   # the part of the node it sets: its section of the reference page

    @classmethod
    def of_field(cls, f: Field[Any], default: Any) -> Param:
        """A dataclass field with `description`, `range`, `unit` and `component` metadata (fastep_core
        PlannerParams): tunable."""
        low, high = f.metadata['range']
        return cls(f.name, default, f.metadata['description'], value_range=(low, high), read_only=False,
                   unit=f.metadata.get('unit', ''), component=f.metadata.get('component', ''))

    def declare(self, node: Node) -> Any:
        return declare(node, self.name, self.default, self.description, read_only=self.read_only,
                       constraints=self.constraints, value_range=self.value_range, unit=self.unit,
                       component=self.component)


def declare_table(node: Node, table: Sequence[Param]) -> dict[str, Any]:
    """Declare every parameter of `table` in its order; their values by name."""
    return {param.name: param.declare(node) for param in table}


def table_values(node: Node, table: Sequence[Param]) -> dict[str, Any]:
    """The values the parameters of `table` (declared) have now, by name: what a managed node's configure builds
    from, a value set while it was unconfigured included (rclpy checked its type and range). One that is not finite
    is a StartupError with one line, as at declaration."""
    values = {}
    for param in table:
        value = node.get_parameter(param.name).value
        if isinstance(value, float) and not math.isfinite(value) or \
                isinstance(value, list) and not all(math.isfinite(v) for v in value if isinstance(v, float)):
            raise StartupError(f'parameter {param.name} must be finite, got {value}')
        values[param.name] = value
    return values


def check_range(name: str, value: float, low: float, high: float, unit: str = '') -> None:
    """A StartupError (one line, exit 2) unless low <= value <= high."""
    if not low <= value <= high:
        raise StartupError(f'parameter {name} must be in [{low:g}, {high:g}]{unit_suffix(unit)}, got {value:g}')


class ClockGuard:
    """The /clock handler of a node on simulated time: rclpy's TimeSource.clock_callback behind two checks.

    A message rclpy cannot turn into a time (sec < 0: "Seconds value must not be negative", raised inside the
    executor, ended the node; nanosec >= 1e9) is ignored. A time that goes back, or runs more than
    CLOCK_JUMP_LIMIT ahead of the last one, is taken only once the next message confirms it (comes at or after
    it, within the limit): a lone message far off (sec = 2^31 - 1) is ignored, while a clock that really
    restarts or jumps (a replay started from another time) costs one message. Each is a throttled warning.

    Before each time is taken, the node's timers on that clock are repaired (repair_timers): rclpy's EventsExecutor
    calls a timer on simulated time twice for one period when the next /clock time comes while its call is still
    queued (timers_manager.cpp queues a call at each look that finds the timer due, without looking whether one is
    queued already, and rcl_timer_call moves the timer a period on at each call), and the timer then skips the period
    after. In lock step a plant whose integration timer skipped a period never publishes that period's odometry (the
    clock waits for it): the graph stood LOCK_WAIT (5 s) and went on without it, "lock step: nothing stamped ...".
    """

    def __init__(self, node: Node, deliver: Callable[[Any], None]) -> None:
        self.node = node
        self.deliver = deliver
        self.heard: float | None = None     # time.monotonic() of the last message taken (sim_time.SimTimeWatch)
        self.last: float | None = None      # seconds of the last time taken
        self.pending: float | None = None   # a jump waiting for its confirmation
        self.skipped = 0                    # timers put back by repair_timers (they would have skipped a period)

    def __call__(self, msg: Any) -> None:
        sec, nanosec = int(msg.clock.sec), int(msg.clock.nanosec)
        if sec < 0 or not 0 <= nanosec < 1_000_000_000:
            self.warn(f'ignoring /clock message sec={sec} nanosec={nanosec}: not a valid time')
            return
        t = sec + nanosec * 1e-9
        last, pending = self.last, self.pending
        self.pending = None
        if last is not None and not last <= t <= last + CLOCK_JUMP_LIMIT and \
                not (pending is not None and pending <= t <= pending + CLOCK_JUMP_LIMIT):
            self.pending = t
            self.warn(f'ignoring /clock at {t:.9g} s after {last:.9g} s: a jump back or of more than '
                      f'{CLOCK_JUMP_LIMIT:g} s ahead is taken only when the next message confirms it')
            return
        self.last = t
        self.heard = time.monotonic()
        self.repair_timers()
        self.deliver(msg)

    def repair_timers(self) -> None:
        """Put back each timer of the node's clock that was called once too often: a timer due next more than one
        period ahead of the time now. A timer called when due is next due within a period (rcl_timer_call moves it a
        period on, then skips the periods missed), a reset one a period from now, and time only goes on; only a
        call of a timer that was not due (the EventsExecutor's second call of one period) puts it further. A reset
        makes it due a period from now: the period it was going to skip. Called before the new time is taken, so
        the executor's look at that time finds the timer due once."""
        clock = self.node.get_clock()
        for timer in self.node.timers:
            if timer.clock is not clock:
                continue   # a timer on another clock (wall time, steady time): /clock does not move it
            period = timer.timer_period_ns
            until = timer.time_until_next_call()   # None: cancelled
            if period > 0 and until is not None and until > period:
                timer.reset()
                self.skipped += 1

    def warn(self, text: str) -> None:
        self.node.get_logger().warning(text, throttle_duration_sec=5.0)


class RepeatedLine:
    """A log line that may come often (a goal per message: goals at 1 kHz wrote 130 MB of log an hour): at most
    one per `period` wall seconds; the next one says how many were left out meanwhile."""

    def __init__(self, log: Callable[[str], None], period: float = 1.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.log, self.period, self.clock = log, period, clock
        self.last = -math.inf
        self.left_out = 0

    def __call__(self, text: str) -> None:
        now = self.clock()
        if now - self.last < self.period:
            self.left_out += 1
            return
        if self.left_out:
            text += f' ({self.left_out} more such line{"s" if self.left_out > 1 else ""} left out before it)'
        self.log(text)
        self.last, self.left_out = now, 0


class LatestLine:
    """A log line about a setting that may change with every message (a speed limit: 6,788 lines in 10 s): a change
    is said at once when no line was said in the last `period` wall seconds; the changes within the period are
    counted, and the newest is said once it is over (`flush`, which a timer calls), as the latest of how many."""

    def __init__(self, log: Callable[[str], None], period: float,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.log, self.period, self.clock = log, period, clock
        self.said_at = -math.inf     # clock() of the last line
        self.pending: str | None = None   # the newest change not said yet
        self.changes = 0             # changes since the last line

    def __call__(self, text: str) -> None:
        self.pending, self.changes = text, self.changes + 1
        self.flush()

    def flush(self) -> None:
        """Say the newest change if one is unsaid and the period since the last line is over."""
        now = self.clock()
        if self.pending is None or now - self.said_at < self.period:
            return
        text = self.pending if self.changes == 1 else \
            f'{self.pending} (the latest of {self.changes} changes since the line before)'
        self.log(text)
        self.said_at, self.pending, self.changes = now, None, 0


def shown(text: str, limit: int = 60) -> str:
    """repr(text), cut to about `limit` characters: what a message from the outside may echo of a string it was
    given (a 10 KB goal frame_id went whole into status)."""
    return repr(text) if len(text) <= limit else f'{text[:limit]!r}... ({len(text)} characters)'


def quiet_at_stop(callback: Callable[..., None]) -> Callable[..., None]:
    """A node method called back by the executor that publishes: an error raised because a stop (SIGINT) shut the
    context down while it ran is the stop, not a fault. The EventsExecutor logged it as a FATAL line with a
    traceback at the end of every fastep-launch --executor events run (a planner publishing the command of the
    odometry that came last)."""
    @functools.wraps(callback)
    def called(self: Node, *args: Any, **kwargs: Any) -> None:
        try:
            callback(self, *args, **kwargs)
        except Exception:
            if self.context.ok():
                raise
    return called


def guard_clock(node: Node) -> ClockGuard | None:
    """Put ClockGuard in front of the node's /clock handling (now, and if use_sim_time is switched on later).

    rclpy builds the TimeSource and its /clock subscription inside Node.__init__; this reaches into both (private
    attributes). Should they change, the node starts anyway, unguarded (the test of the guard fails then), and
    None is returned.
    """
    source = getattr(node, '_time_source', None)
    deliver = getattr(source, 'clock_callback', None)
    if isinstance(deliver, ClockGuard):
        return deliver
    if source is None or deliver is None:
        return None
    guarded = ClockGuard(node, deliver)
    source.clock_callback = guarded
    subscription = getattr(source, '_clock_sub', None)
    if subscription is not None:
        subscription.callback = guarded
    return guarded


PARENT_ENV = 'FASTEP_PARENT_PID'
GATE_ENV = 'FASTEP_LAUNCH_GATE'   # '1': wait for the launcher's line on stdin before joining DDS (_gate_opened)


def _die_with_parent() -> None:
    """When started by fastep-launch (FASTEP_PARENT_PID set), get SIGINT if the launcher dies (Linux only)."""
    parent = os.environ.get(PARENT_ENV)
    if not parent or not sys.platform.startswith('linux'):
        return
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGINT)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        return
    if str(os.getppid()) != parent:  # the launcher is already gone
        raise SystemExit(1)


def _spin(nodes: Sequence[Node], executor: rclpy.executors.Executor) -> None:
    """rclpy.spin until a stop signal (_stop_signalled) or the context's shutdown, but quiet about the races of a
    stop: an error raised because the context was shut down while spinning ends the loop, and a message rclpy
    cannot convert (seen with Fast DDS while a peer process stops) is dropped with one warning instead of ending
    the node."""
    for node in nodes:
        executor.add_node(node)
    node = nodes[0]
    warned = False
    while rclpy.ok() and not _stop_signalled:
        try:
            # A timeout: rclpy 7.1.6's EventsExecutor never returned from spin_once() without one; and a signal's
            # Python handler runs only when this returns (or a callback runs), so it bounds the time to stop.
            executor.spin_once(timeout_sec=STOP_POLL)
        except (KeyboardInterrupt, ExternalShutdownException):
            raise
        except Exception as exc:
            if not rclpy.ok():
                break
            if not (isinstance(exc, RuntimeError) and 'Unable to convert call argument' in str(exc)):
                raise
            if not warned:
                node.get_logger().warning(f'dropped a message rclpy could not convert: {exc}')
                warned = True


STOP_POLL = 0.1
"""Seconds: the longest a node process takes to notice SIGINT / SIGTERM while nothing else happens."""

_stop_signalled: list[int] = []   # SIGINT / SIGTERM received: the spin loop ends and the node is cleaned up


def _ignore_stop_signals() -> None:
    """Python's handlers for SIGINT / SIGTERM: remember the signal, raise nothing. rclpy.init installs none
    (node_main): rclpy's own handler shut the context down at once, from any point of the spin, and rclpy 7.1.6's
    EventsExecutor, stopped that way in the middle of taking a node's entities, kept callbacks it no longer
    tracked and aborted the process when it was destroyed ("Destroying callback manager with callbacks
    remaining", CI, 2026-11-28). Now the spin loop sees the signal, the executor is shut down while the context
    is up, and only then the nodes and the context."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda signum, frame: _stop_signalled.append(signum))


def node_main(prog: str, factory: Callable[[], Node | Sequence[Node]], args: Sequence[str] | None = None) -> int:
    """rclpy.init, build the node (or the nodes: fastep_ros.container), spin until Ctrl-C / shutdown.

    Returns the exit code: 0 after a normal stop, 2 (with one line on stderr, no traceback) when the node
    cannot start with its parameters (a FastepError, e.g. StartupError: fastep_core.cli.guard prints it).
    It is a process's main: once the node has stopped, the process ignores SIGINT and SIGTERM while it exits
    (and processes it starts after that would inherit the ignoring).
    """
    _die_with_parent()
    # Python's default SIGINT handler raised KeyboardInterrupt at a random point, e.g. inside a destructor (a
    # traceback), and the default SIGTERM action ended the node there (a recorder with its file unfinished, when a
    # second SIGTERM came during the clean-up).
    _ignore_stop_signals()
    return guard(prog, lambda: _run_node(factory, args))


def _gate_opened() -> bool:
    """Started by fastep-launch with GATE_ENV: wait, imports done, until the launcher opens the gate (a line on
    stdin), so that the process joins DDS only once the launcher has seen that no other graph shares the domain
    (and the imports overlap that look). False if the launcher closed it instead (it refused to run)."""
    if os.environ.get(GATE_ENV) != '1':
        return True
    try:
        return bool(sys.stdin.readline())
    except (OSError, ValueError):   # no stdin
        return False


def _run_node(factory: Callable[[], Node | Sequence[Node]], args: Sequence[str] | None) -> int:
    """node_main's body: 0 after a stop (Ctrl-C is a normal stop for a node); a FastepError propagates,
    after the node is destroyed and ROS shut down."""
    if not _gate_opened() or _stop_signalled:
        return 0
    try:
        rclpy.init(args=None if args is None else list(args), signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:   # e.g. UnknownROSArgsError for a mistyped --ros-args
        raise StartupError(f'cannot start ROS: {type(exc).__name__}: {exc}'.splitlines()[0]) from None
    nodes: list[Node] = []
    executor = None
    try:
        if _stop_signalled:   # during rclpy.init
            raise KeyboardInterrupt
        # The executor before the node: a node that has logged that it is up is what a user (or a test) stops.
        executor = make_executor()   # FASTEP_EXECUTOR (fastep_ros.executors)
        built = factory()
        nodes = [built] if isinstance(built, Node) else list(built)
        for each in nodes:
            warn_unknown_overrides(each)
        # What imports and the node's construction made lives as long as the process: out of the collector's sight,
        # so its full passes look only at what came after (a planner's 72 000 objects took 25 ms a pass, holding
        # the GIL: a control tick waits that long).
        gc.freeze()
        _spin(nodes, executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except FastepError:
        raise
    except Exception:
        if rclpy.ok():
            raise
        # the context shut down (a recorder that cannot write) while a node was being built: its calls fail
    finally:
        if executor is not None:
            executor.shutdown()
        for node in reversed(nodes):
            node.destroy_node()
        rclpy.try_shutdown()
        # Stopped and cleaned up: a second Ctrl-C / SIGTERM has nothing left to stop. Ignored at the OS level (a
        # Python handler is reset to the default action while the interpreter exits: a signal then ended the
        # process with -2 / -15 after a clean stop).
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, signal.SIG_IGN)
    return 0
