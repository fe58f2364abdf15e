"""Hypothesis profiles for the property tests, and how pytest-xdist spreads the suite over its workers.

Hypothesis: `ci` (the default, what `make test` runs) is derandomised, so every run tries the same examples and
a red build means the code changed, not the draw. `explore` (`make fuzz`): fresh random examples each run, to
find new counterexamples by hand; add any it finds to the test as an `@example`.

xdist (`make test` runs `-n 3 --dist loadgroup`): every test under tests/fastep_ros/ runs ROS 2 nodes on a live
DDS graph. They form two work units, each run one after another on one worker: the tests that drive robots on wall
time and judge where they went (DRIVING_FILES: faults, stalled nodes; they wait for what they check and time
nothing themselves), and the rest (lock step, fastep-launch, the recorder, replay: the timing tests). The third
worker takes the tests that need no graph one by one. The graphs mostly wait for wall time, so two of them and
the CPU-bound tests share 2 cores: `make test` took 3:43 of tests (1935) instead of 5:55 with one unit on -n 2.
xdist hands out the largest units first, so the graph tests start at once. The units are chosen here by file,
not with `xdist_group` marks: on pytest 9.2 xdist 3.8 silently ignores those marks (it renames node ids, which
pytest 9.2 no longer lets it do).

Signals: a node's main() (fastep_ros.common.node_main) ignores SIGINT and SIGTERM once it has stopped, as the
process it is meant to be the main of should while it exits. Called in a test, that would stay in the worker
and pass on to every process it starts later (an ignored signal is inherited), which then ignore Ctrl-C: every
test gets the worker's handlers back.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path
from typing import Any, Iterator

import pytest
from hypothesis import settings

# No wall-clock deadline: the properties are pure functions, and a busy machine only makes them slower.
settings.register_profile('ci', derandomize=True, deadline=None)
settings.register_profile('explore', derandomize=False, deadline=None)
settings.load_profile(os.environ.get('HYPOTHESIS_PROFILE', 'ci'))



@pytest.fixture(autouse=True)
def _signal_handlers_restored() -> Iterator[None]:
    saved = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    yield
    for sig, handler in saved.items():
        if signal.getsignal(sig) is not handler and handler is not None:
            signal.signal(sig, handler)


# A suite started in the background of a non-interactive shell (`make test &`, a CI script's job) inherits
# SIGINT ignored, and so would every process the tests start: those that check what Ctrl-C does would wait for
# nothing. The tests are not for the shell's Ctrl-C: take the default back (the process's own stays usable).
for _signum, _default in ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, signal.SIG_DFL)):
    if signal.getsignal(_signum) is signal.SIG_IGN:
        signal.signal(_signum, _default)


GRAPH_TESTS = Path(__file__).resolve().parent / 'fastep_ros'
# Live-graph tests outside tests/fastep_ros/ that join a group: the robot harness runs real node processes too.
GRAPH_FILES = (Path(__file__).resolve().parent / 'fastep_testing' / 'test_robot_harness.py',)
# The graph tests that drive robots on wall time and judge where they went (faults, a stalled node): they wait for
# what they check, with long timeouts, and need no timing of their own; their own group, beside the other one.
DRIVING_FILES = tuple(GRAPH_TESTS / name for name in (
    'test_faults.py', 'test_stale_inputs.py', 'test_single_robot.py', 'test_two_robots.py',
    'test_diff_drive_graph.py', 'test_robots.py', 'test_diagnostics.py')) + GRAPH_FILES
# Live-graph tests outside tests/fastep_ros/ in the other group: robots on hosts of their own (network namespaces).
HOST_FILES = (Path(__file__).resolve().parent / 'fastep_testing' / 'test_multi_host.py',)
GRAPH_GROUP, DRIVING_GROUP = 'ros_graph', 'ros_driving'


@pytest.hookimpl(optionalhook=True)  # an xdist hook: pytest without xdist never calls it
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """--dist loadgroup, with the tests of tests/fastep_ros/ (and GRAPH_FILES, HOST_FILES) in two groups:
    DRIVING_FILES, and the rest (lock step, launch, recorder, replay: the timing tests; robots on other hosts)."""
    if config.getvalue('dist') != 'loadgroup':
        return None
    from xdist.scheduler import LoadGroupScheduling

    graph = GRAPH_TESTS.relative_to(config.rootpath).as_posix() + '/'
    driving = tuple(path.relative_to(config.rootpath).as_posix() + '::' for path in DRIVING_FILES)
    hosts = tuple(path.relative_to(config.rootpath).as_posix() + '::' for path in HOST_FILES)

    class GraphGroupScheduling(LoadGroupScheduling):
        def _split_scope(self, nodeid: str) -> str:
            if nodeid.startswith(driving):
                return DRIVING_GROUP
            return GRAPH_GROUP if nodeid.startswith((graph, *hosts)) else super()._split_scope(nodeid)

    return GraphGroupScheduling(config, log)
