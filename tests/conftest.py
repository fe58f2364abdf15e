"""Hypothesis profiles for the property tests, and how pytest-xdist spreads the suite over its workers.

Hypothesis: `ci` (the default, what `make test` runs) is derandomised, so every run tries the same examples and
a red build means the code changed, not the draw. `explore` (`make fuzz`): fresh random examples each run, to
find new counterexamples by hand; add any it finds to the test as an `@example`.

xdist (`make test` runs `-n 2 --dist loadgroup`): every test under tests/fastep_ros/ runs ROS 2 nodes on a live
DDS graph, and they all form one work unit, run one after another on one worker, while the other worker takes
the tests that need no graph one by one. Each graph has its own DDS domain, so two could run side by side, but
on a 2-core machine two graphs at once plus CPU-bound tests starve the nodes and timing tests (replay rates,
lock-step clock holds) turn flaky. xdist hands out the largest unit first, so the graph tests start at once and
the rest fills the other core. The unit is chosen here by folder, not with `xdist_group` marks: on pytest 9.2
xdist 3.8 silently ignores those marks (it renames node ids, which pytest 9.2 no longer lets it do).

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

settings.register_profile('ci', derandomize=True)
settings.register_profile('explore', derandomize=False)
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
# Live-graph tests outside tests/fastep_ros/ that join its group: the robot harness runs real node processes too.
GRAPH_FILES = (Path(__file__).resolve().parent / 'fastep_testing' / 'test_robot_harness.py',)
GRAPH_GROUP = 'ros_graph'


@pytest.hookimpl(optionalhook=True)  # an xdist hook: pytest without xdist never calls it
def pytest_xdist_make_scheduler(config: pytest.Config, log: Any) -> Any:
    """--dist loadgroup, with every test of tests/fastep_ros/ (and of GRAPH_FILES) in one group."""
    if config.getvalue('dist') != 'loadgroup':
        return None
    from xdist.scheduler import LoadGroupScheduling

    prefixes = (GRAPH_TESTS.relative_to(config.rootpath).as_posix() + '/',
                *(path.relative_to(config.rootpath).as_posix() + '::' for path in GRAPH_FILES))

    class GraphGroupScheduling(LoadGroupScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return GRAPH_GROUP if nodeid.startswith(prefixes) else super()._split_scope(nodeid)

    return GraphGroupScheduling(config, log)
