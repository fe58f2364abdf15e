"""The test graphs' ROS domains (fastep_testing/graph.py): a process holds at most MAX_HELD, so a pytest worker
that ran many graph tests leaves domains to the other (CI failed with "no free ROS domain" when one held all)."""

from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

from fastep_testing import graph


def test_a_process_holds_at_most_max_held_domains_and_the_released_ones_are_free_to_others() -> None:
    taken = []
    for _ in range(graph.MAX_HELD + 10):
        held = set(graph._held)
        taken.append(graph.free_domain())
        # Never one this process still holds (one it released may come again: it is free to anyone, us too) ...
        assert taken[-1] not in held
    assert len(graph._held) <= graph.MAX_HELD            # ... but only the newest are kept
    assert taken[-1] in graph._held
    # Released: those taken beyond MAX_HELD. Other test processes may hold many of the 100 domains meanwhile (the
    # graph workers of make test), so fewer than MAX_HELD + 10 distinct ones may have been free to take.
    released = [d for d in dict.fromkeys(taken) if d not in graph._held]
    assert len(released) >= len(set(taken)) - graph.MAX_HELD >= 1, (len(set(taken)), released)
    lock = Path(tempfile.gettempdir()) / f'fastep-ros-test-domain-{released[0]}.lock'
    probe = ('import fcntl, sys; f = open(sys.argv[1], "a"); '
             'fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB); print("locked")')
    done = subprocess.run([sys.executable, '-c', probe, str(lock)], capture_output=True, text=True, timeout=30)
    assert done.stdout.strip() == 'locked', done.stderr   # another process can take a released domain
