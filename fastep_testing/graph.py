"""Live ROS graphs for tests and benchmarks that run real fastep_ros node processes.

Every graph lives on its own DDS domain (a free ROS_DOMAIN_ID in 1..100, see free_domain) with
ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, and every process a test starts is stopped (SIGINT, wait, SIGKILL)
in a finally block. The test process talks to the graph through a helper rclpy node in its own context on the
same domain.
"""

from __future__ import annotations

import fcntl
import itertools
import math
import os
import signal
import socket
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path
from typing import Any, Callable

from fastep_ros.processes import ros_value

ROOT = Path(__file__).resolve().parents[1]  # the repository root
_domains = itertools.count()

# Small, fast scenarios: gains 0.5 and 2 m/s, so a run takes ~15-20 simulated seconds.
ONE_CIRCLE = """\
name: one_circle
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [10, 10], radius: 1.5}
robots:
  - name: r1
    model: point_mass
    start: [2, 10]
    goal: [18, 10.5]
    radius: 0.5
planner: {alpha1: 0.5, alpha2: 0.5, max_speed: 2.0}
"""

CROSSING = """\
name: crossing
workspace: [0, 0, 20, 20]
robots:
  - name: r1
    model: point_mass
    start: [3, 3]
    goal: [17, 17]
    radius: 0.5
  - name: r2
    model: point_mass
    start: [17, 3]
    goal: [3, 17]
    radius: 0.5
planner: {alpha1: 0.5, alpha2: 0.5, max_speed: 2.0}
"""

# 'fastep' (not the nodes' default, fastep_route): the tests count the swarm's steps round the circle.
FAST = {'alpha1': 0.5, 'alpha2': 0.5, 'max_speed': 2.0, 'algorithm': 'fastep'}


_held: dict[int, Any] = {}  # domain -> open lock file (flock released when this process exits or MAX_HELD passes)
MAX_HELD = 20
"""Domains one process holds at most. Each test graph takes a fresh domain and kept it locked until its process
exited: a pytest worker that had run 100 graph tests held every domain, and the other worker, holding none to
fall back on, failed with "no free ROS domain" (CI, 2026-11-26). Beyond MAX_HELD the oldest domain nobody runs
on (its discovery port is free) is released to the other processes. Three workers (make test) hold 60 at most,
leaving 40 of the 100 to whichever needs them."""


PARTICIPANTS_CHECKED = 10
"""Participants per domain whose discovery ports are checked: the first one's port alone missed a graph whose first
participant (a helper, the first node up) had gone while the others still ran, and a test on the reused domain
saw a `/planner` not its own (CI, 2026-12-02)."""


def _port_free(domain: int) -> bool:
    """Are the discovery ports of a domain's first PARTICIPANTS_CHECKED DDS participants (7410 + 250 d + 2 p, RTPS's
    well-known unicast ports) unbound, i.e. nobody on it?"""
    for participant in range(PARTICIPANTS_CHECKED):
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            sock.bind(('0.0.0.0', 7410 + 250 * domain + 2 * participant))
        except OSError:
            return False
        finally:
            sock.close()
    return True


def _lock(domain: int) -> Any:
    path = Path(tempfile.gettempdir()) / f'fastep-ros-test-domain-{domain}.lock'
    f = open(path, 'a')
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        f.close()
        return None
    return f


def free_domain() -> int:
    """A ROS_DOMAIN_ID in 1..100 that no other test process has taken (a lock file per domain, held until this
    process exits) and on which no DDS participant runs now. Domains this process used before are taken again
    only when all others are busy."""
    start = os.getpid() * 7 + next(_domains) * 13
    candidates = [1 + (start + k) % 100 for k in range(100)]
    for domain in candidates:
        if domain in _held or not _port_free(domain):
            continue
        lock = _lock(domain)
        if lock is not None:
            _held[domain] = lock
            _release_oldest()
            return domain
    for domain in candidates:
        if domain in _held and _port_free(domain):
            return domain
    raise RuntimeError('no free ROS domain in 1..100 for an isolated test graph')


def _release_oldest() -> None:
    """Unlock the domains held longest, down to MAX_HELD, skipping any a participant still runs on."""
    for domain in list(_held)[:-1]:   # oldest first; never the one just taken
        if len(_held) <= MAX_HELD:
            return
        if _port_free(domain):
            _held.pop(domain).close()   # closing the file releases its flock


def without_dds_noise(text: str) -> str:
    """`text` without Fast DDS's own log lines: its shared-memory transport prints "[RTPS_TRANSPORT_SHM Error] Failed
    init_port ..." when two processes race for a port's lock file (under load, many nodes at once) and goes on over
    UDP. A test that counts a node's own lines counts them without these."""
    return ''.join(line for line in text.splitlines(keepends=True) if 'RTPS_TRANSPORT_SHM' not in line)


def isolated_env(domain: int, log_dir: Path) -> dict[str, str]:
    env = dict(os.environ)
    env.update(ROS_DOMAIN_ID=str(domain), ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', ROS_LOG_DIR=str(log_dir),
               PYTHONUNBUFFERED='1', RCUTILS_LOGGING_BUFFERED_STREAM='0')
    env['PYTHONPATH'] = os.pathsep.join(p for p in (str(ROOT), env.get('PYTHONPATH', '')) if p)
    env.pop('ROS_LOCALHOST_ONLY', None)
    return env


class Graph:
    """Node processes on one isolated domain, plus a helper node in this process."""

    def __init__(self, tmp: Path) -> None:
        self.domain = free_domain()
        self.tmp = tmp
        self.env = isolated_env(self.domain, tmp / 'roslog')
        # A node that hangs can be asked where (SIGABRT: Python's fault handler writes every thread's stack to its
        # log before it dies); used by failure diagnoses only.
        self.env['PYTHONFAULTHANDLER'] = '1'
        self.procs: dict[str, subprocess.Popen[bytes]] = {}
        self.helper: Helper | None = None

    def start(self, label: str, module: str, namespace: str = '/', **params: Any) -> subprocess.Popen[bytes]:
        cmd = [sys.executable, '-m', f'fastep_ros.{module}', '--ros-args', '-r', f'__ns:={namespace}',
               '--log-level', os.environ.get('FASTEP_TEST_LOG_LEVEL', 'warn')]
        for name, value in params.items():
            cmd += ['-p', f'{name}:={ros_value(value)}']
        log = open(self.tmp / f'{label.replace("/", "_")}.log', 'wb')
        proc = subprocess.Popen(cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        log.close()
        self.procs[label] = proc
        return proc

    def stop(self, label: str, sig: int = signal.SIGINT) -> int:
        return stop_process(self.procs[label], sig)

    def stacks(self, label: str, wait: float = 3.0) -> str:
        """Where a running node process is (its threads' Python stacks, from the fault handler), ending it; '' when
        it is not running."""
        proc = self.procs[label]
        if proc.poll() is not None:
            return ''
        before = len(self.log(label))
        proc.send_signal(signal.SIGABRT)
        try:
            proc.wait(timeout=wait)
        except subprocess.TimeoutExpired:
            pass
        return self.log(label)[before:]

    def log(self, label: str) -> str:
        return (self.tmp / f'{label.replace("/", "_")}.log').read_text(errors='replace')

    def close(self) -> None:
        try:
            if self.helper is not None:
                self.helper.close()
        finally:
            for proc in self.procs.values():
                if proc.poll() is None:
                    proc.send_signal(signal.SIGINT)
            for proc in self.procs.values():
                stop_process(proc)


def stop_process(proc: subprocess.Popen[Any], sig: int = signal.SIGINT, grace: float = 5.0) -> int:
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(timeout=grace)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode


class Helper:
    """An rclpy node in the test process (own context, same domain): publishes goals, records topics."""

    def __init__(self, domain: int, executor: str = 'single') -> None:
        """`executor` as fastep_ros.executors names them (a benchmark's helper follows every robot: `events` costs
        it less of the machine it measures)."""
        import rclpy
        from rclpy.signals import SignalHandlerOptions

        from fastep_ros.executors import make_executor

        self.rclpy = rclpy
        self.context = rclpy.Context()
        saved = os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE')
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'  # read when the context starts
        try:
            rclpy.init(args=[], context=self.context, domain_id=domain,
                       signal_handler_options=SignalHandlerOptions.NO)
        finally:
            if saved is None:
                del os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE']
            else:
                os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = saved
        self.node = rclpy.create_node('test_helper', context=self.context)
        self.executor = make_executor(executor, context=self.context)
        self.executor.add_node(self.node)
        self.records: dict[str, list[Any]] = {}
        self.goal_pubs: dict[str, Any] = {}

    def record(self, topic: str, msg_type: Any, qos: Any = None) -> list[Any]:
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        if topic not in self.records:
            self.records[topic] = []
            self.node.create_subscription(msg_type, topic, self.records[topic].append,
                                          qos or QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE))
        return self.records[topic]

    def wait_heard(self, topic: str, timeout: float = 60.0) -> None:
        """Spin until a recorded topic has delivered a message. DDS matches the two ends of a connection each on
        its own (under load, seconds apart), so a subscription on the graph may still miss what is sent: a test
        that judges a run from recorded odometry first waits to hear it (plants at rest publish their start)."""
        self.spin_until(lambda: bool(self.records[topic]), timeout, f'a message on {topic}')

    def wait_recorded_through(self, topic: str, t: float, timeout: float = 60.0) -> None:
        """Spin until a recorded topic has delivered a message stamped at `t` or later. A node's status can reach
        this helper before the odometry it judged from does (a busy machine delays this process more than the
        nodes), so a test that checks where a robot ended first waits for the odometry up to that status's time."""
        seen = self.records[topic]
        self.spin_until(lambda: bool(seen) and max(stamp(m) for m in seen[-50:]) >= t, timeout,
                        lambda: f'a message on {topic} stamped {t:.3f} s or later (last '
                                f'{stamp(seen[-1]) if seen else "none"})')

    def follow_clock(self) -> list[Any]:
        """Subscribe to /clock (a clock started with wait_for_subscribers counting this helper then runs)."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
        return self.record('/clock', Clock, QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT))

    def record_status(self, namespace: str) -> list[dict[str, Any]]:
        from diagnostic_msgs.msg import DiagnosticStatus

        from msg_tools.interface import STATUS_QOS
        return self.record(f'{namespace}/status', DiagnosticStatus, STATUS_QOS)

    def wait_status(self, namespace: str, accept: Callable[[dict[str, Any]], bool], timeout: float,
                    what: str) -> dict[str, Any]:
        """Spin until the latest status of `namespace` satisfies `accept`; return it."""
        # The last status when the wait timed out (formatted now, it would be the one it began with).
        self.spin_until(lambda: bool(self.status(namespace)) and accept(self.status(namespace)), timeout,
                        lambda: f'{what} (last status of {namespace}: {self.status(namespace)})')
        return self.status(namespace)

    def status(self, namespace: str) -> dict[str, Any]:
        from msg_tools.convert import diagnostic_to_dict
        seen = self.records.get(f'{namespace}/status') or []
        return diagnostic_to_dict(seen[-1]) if seen else {}

    def send_goal(self, namespace: str, goal: tuple[float, float]) -> None:
        from geometry_msgs.msg import PoseStamped

        from msg_tools.convert import point_to_pose_stamped
        from msg_tools.interface import RELIABLE
        topic = f'{namespace}/goal_pose'
        if topic not in self.goal_pubs:
            self.goal_pubs[topic] = self.node.create_publisher(PoseStamped, topic, RELIABLE)
            self.spin_until(lambda: self.goal_pubs[topic].get_subscription_count() > 0, 20.0,
                            f'a subscriber on {topic}')
        self.goal_pubs[topic].publish(point_to_pose_stamped(goal))

    def spin_until(self, predicate: Callable[[], bool], timeout: float,
                   what: str | Callable[[], str] = 'condition') -> None:
        """Spin until predicate() holds; after `timeout` s an AssertionError names `what` (a callable: what it
        returns then, e.g. the state at the timeout)."""
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                text = what() if callable(what) else what
                raise AssertionError(f'timed out after {timeout:g} s waiting for {text}')
            self.executor.spin_once(timeout_sec=0.02)

    def spin_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)

    def close(self) -> None:
        self.executor.shutdown()
        self.node.destroy_node()
        self.rclpy.try_shutdown(context=self.context)


def write(path: Path, text: str) -> Path:
    path.write_text(textwrap.dedent(text))
    return path


def odom_xy(msg: Any) -> tuple[float, float]:
    return msg.pose.pose.position.x, msg.pose.pose.position.y


def stamp(msg: Any) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def distance(a: tuple[float, float], b: tuple[float, float]) -> float:
    return math.hypot(a[0] - b[0], a[1] - b[1])
