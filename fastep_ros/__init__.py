"""fastep_ros: the rclpy nodes (plant, map, planner, clock) and the fastep-launch launcher."""

import os as _os
import signal as _signal
import sys as _sys
from types import FrameType as _FrameType

_LAUNCHED = bool(_os.environ.get('FASTEP_PARENT_PID')) and \
    str(_os.getppid()) == _os.environ.get('FASTEP_PARENT_PID')


def _importing(frame: '_FrameType | None') -> bool:
    while frame is not None:
        if frame.f_code.co_filename.startswith('<frozen importlib'):
            return True
        frame = frame.f_back
    return False


def _quiet_exit(signum: int, frame: '_FrameType | None') -> None:
    """Ctrl-C while the program is still importing (rclpy, numpy, scipy take seconds on a loaded machine) ends it
    without a KeyboardInterrupt traceback: exit 0 for a node fastep-launch started (it is being stopped), 130
    otherwise. Once imported, a program's main() installs its own handling (node_main, fastep-launch); until then,
    or in a program that does not, Ctrl-C is the KeyboardInterrupt of Python's default handler.

    The exit is immediate (os._exit, stdout and stderr flushed): nothing has joined DDS or opened a file yet, and a
    SystemExit raised while a C extension initialises (rclpy's) came out as "ImportError: initialization failed"
    with two tracebacks (a launch that refused to start beside another graph stopped a node importing rclpy)."""
    if _LAUNCHED:
        _exit_now(0)
    if _importing(frame):
        _exit_now(130)
    raise KeyboardInterrupt


def _exit_now(code: int) -> None:
    for stream in (_sys.stdout, _sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):   # closed, or no stream at all
            pass
    _os._exit(code)


# Only in a program (a fastep-* command, python -m fastep_ros.<module>): a test or a user's code importing fastep_ros
# keeps its own handling.
if _LAUNCHED or _sys.argv[:1] == ['-m'] or _os.path.basename(_sys.argv[0] if _sys.argv else '').startswith('fastep-'):
    _signal.signal(_signal.SIGINT, _quiet_exit)
