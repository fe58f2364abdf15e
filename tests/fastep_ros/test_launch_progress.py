"""fastep-launch's progress display (fastep_ros.launch_progress), driven by a fake wall clock: no ROS, no waiting."""

from __future__ import annotations

import io

from fastep_ros.launch_progress import Progress


class FakeClock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_without_a_terminal_progress_is_an_occasional_plain_line_and_one_at_the_end() -> None:
    out, clock = io.StringIO(), FakeClock()
    progress = Progress('fastep-launch', 16, out, every=10.0, clock=clock)
    progress.start()
    for step in range(1, 200):       # 25 wall seconds in spins of 1/8 s, at 4x real time
        clock.t += 0.125
        progress.update(step // 16, 0, 0.5 * step)
    progress.update(14, 2, 100.0)
    clock.t += 0.125
    progress.close()
    progress.close()                 # a second close writes nothing more
    progress.update(16, 0, 200.0)    # nor an update after it
    lines = out.getvalue().splitlines()
    assert '\r' not in out.getvalue()
    assert lines == ['fastep-launch: 5/16 arrived, simulated 40.0 s, 4.0x real time',
                     'fastep-launch: 10/16 arrived, simulated 80.0 s, 4.0x real time',
                     'fastep-launch: 14/16 arrived, simulated 100.0 s, 4.0x real time, 2 failed']


def test_no_progress_writes_nothing() -> None:
    out = io.StringIO()
    progress = Progress('fastep-launch', 2, out, enabled=False)
    progress.start()
    progress.update(1, 0, 5.0)
    progress.close()
    assert out.getvalue() == ''


def test_on_a_terminal_progress_is_one_bar_redrawn_in_place() -> None:
    out, clock = Terminal(), FakeClock()
    progress = Progress('fastep-launch', 16, out, refresh=0.0, clock=clock)
    progress.start()
    for step in range(1, 11):
        clock.t += 1.0
        progress.update(step, 0, 20.0 * step)
    progress.close()
    text = out.getvalue()
    assert text.count('\n') == 1                      # one line, redrawn with carriage returns
    assert text.count('\r') >= 10
    last = text.rstrip('\n').split('\r')[-1]
    assert last.startswith('arrived 10/16 |') and last.endswith('simulated 200.0 s, 20.0x real time'), last
