"""The processes of one fastep-launch: started in the groups of its --layout, gated, stopped in order.

Each group of nodes (fastep_ros.layouts) is one process, `python -m fastep_ros.<node>` or a fastep-container. They
start with FASTEP_LAUNCH_GATE set (fastep_ros.common): they import, then wait for a line on stdin before they join
DDS, so that they import while the launcher looks for another graph on the domain and join only if there is none
(open_gates; stop() lets a process still at its gate go without starting). They inherit the launcher's
environment, with the folder of this package first on PYTHONPATH, FASTEP_PARENT_PID (a node gets SIGINT when the
launcher dies) and OPENBLAS_NUM_THREADS=1 (numpy's BLAS threads spun after each call of the nodes' small arrays).
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Any, Callable, Sequence

from fastep_ros.common import GATE_ENV
from fastep_ros.executors import EXECUTOR_ENV
from fastep_ros.layouts import Member, group
from fastep_ros.layouts import command as layout_command

__all__ = ['GRACE', 'Placement', 'Processes', 'ros_value']

Placement = Callable[[Sequence[Member]], Sequence[str]]
"""Where a process of nodes runs: the command prefix that puts it there (e.g. `ip netns exec HOST`, `ssh HOST`), from
the nodes it runs; [] for this computer (benchmarks.multi_host puts robots on other hosts)."""

GRACE = 5.0             # wall seconds a process gets to stop after SIGINT
GATE_GRACE = 60.0       # ... to import and leave at its gate when the launch stops before opening the gates


def ros_value(value: Any) -> str:
    """A parameter value as `--ros-args -p name:=VALUE` takes it."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(float(value))
    if isinstance(value, (list, tuple)):
        if all(isinstance(v, str) for v in value):
            return '[' + ', '.join(value) + ']'
        return '[' + ', '.join(ros_value(float(v)) for v in value) + ']'
    return str(value)


class Processes:
    """The child processes of one launch; stop() ends every one of them.

    start() adds a node; with the `node` layout it starts at once in a process of its own, otherwise when launch()
    starts every process of the layout (fastep_ros.layouts). `items` has one (label, process) per node, so a node
    shares its container's process with the others in it."""

    def __init__(self, verbose: bool, layout: str = 'node', executor: str | None = None,
                 placement: Placement | None = None) -> None:
        self.verbose = verbose
        self.layout = layout
        self.placement = placement
        self.items: list[tuple[str, subprocess.Popen[bytes]]] = []
        self.pending: list[Member] = []
        self.opened = False   # open_gates() was called
        self.labels: dict[int, str] = {}   # process id -> its label (a container's: fastep-robot /r1, fastep-graph)
        self.env = dict(os.environ)
        root = str(Path(__file__).resolve().parent.parent)
        self.env['PYTHONPATH'] = os.pathsep.join(p for p in (root, self.env.get('PYTHONPATH', '')) if p)
        self.env['FASTEP_PARENT_PID'] = str(os.getpid())
        self.env[GATE_ENV] = '1'   # each process imports, then waits for open_gates() before it joins DDS
        self.env.setdefault('PYTHONUNBUFFERED', '1')
        # A process's numpy would start a BLAS thread per core that spins after each call (5 % of the CPU of a
        # lock-step run in perf); the nodes' arrays are small.
        self.env.setdefault('OPENBLAS_NUM_THREADS', '1')
        if executor is not None:
            self.env[EXECUTOR_ENV] = executor

    def start(self, label: str, module: str, namespace: str, params: dict[str, Any]) -> None:
        self.pending.append(Member(label, module, namespace, params))
        if self.layout == 'node':
            self.launch()

    def launch(self) -> None:
        """Start the processes of the nodes added since the last call, grouped as the layout says."""
        pending, self.pending = self.pending, []
        for label, members in group(self.layout, pending):
            cmd = layout_command(members, 'info' if self.verbose else 'warn', ros_value)
            if self.placement is not None:
                cmd = [*self.placement(members), *cmd]
            # A new session: Ctrl-C in a terminal reaches only the launcher, which then stops the nodes in order.
            proc = subprocess.Popen(cmd, env=self.env, stdin=subprocess.PIPE, start_new_session=True)
            self.labels[proc.pid] = label
            self.items += [(m.label, proc) for m in members]
            if self.opened:
                self._open(proc)

    def open_gates(self) -> None:
        """Let every process started so far (and from now on at once) join DDS (fastep_ros.common.GATE_ENV)."""
        self.opened = True
        for proc in self.processes():
            self._open(proc)

    @staticmethod
    def _open(proc: subprocess.Popen[bytes], go: bool = True) -> None:
        """Write the process its line (or, not `go`, just end its stdin: it exits without starting)."""
        if proc.stdin is None or proc.stdin.closed:
            return
        try:
            if go:
                proc.stdin.write(b'\n')
            proc.stdin.close()
        except OSError:   # it is gone already
            pass

    def processes(self) -> list[subprocess.Popen[bytes]]:
        return list({proc.pid: proc for _, proc in self.items}.values())

    def running(self, label: str) -> bool:
        """Is the process of `label` (a node's, e.g. 'fastep-record') started and not exited?"""
        return any(self.labels[proc.pid] == label and proc.poll() is None for proc in self.processes())

    def dead(self) -> list[tuple[str, int]]:
        return [(self.labels[proc.pid], proc.returncode) for proc in self.processes() if proc.poll() is not None]

    def stop(self) -> None:
        """SIGINT every process (the clock first, so time stops before the nodes do), SIGKILL after GRACE; a process
        still at its gate is let go without starting. Before the gates opened (a launch that refuses to start) no
        signal is sent: each process leaves at its gate once imported (SIGKILL after GATE_GRACE). A SIGINT could
        land while a Python interpreter imports its own site module, before any of our code runs, and print
        "Fatal Python error: init_import_site" (a loaded CI)."""
        for proc in self.processes():
            self._open(proc, go=False)
        if not self.opened:
            self._wait(self.processes(), GATE_GRACE)
            return
        clocks = [proc for proc in self.processes() if self.labels[proc.pid] == 'fastep-clock']
        others = [proc for proc in reversed(self.processes()) if self.labels[proc.pid] != 'fastep-clock']
        self._interrupt(clocks, GRACE / 2)
        self._interrupt(others, GRACE)

    @staticmethod
    def _interrupt(procs: list[subprocess.Popen[bytes]], grace: float) -> None:
        for proc in procs:
            if proc.poll() is None:
                try:
                    proc.send_signal(signal.SIGINT)
                except ProcessLookupError:
                    pass
        Processes._wait(procs, grace)

    @staticmethod
    def _wait(procs: list[subprocess.Popen[bytes]], grace: float) -> None:
        """Wait for the processes to exit, SIGKILL those left after `grace` seconds."""
        deadline = time.monotonic() + grace
        for proc in procs:
            try:
                proc.wait(timeout=max(0.05, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
