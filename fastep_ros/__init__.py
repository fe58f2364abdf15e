"""fastep_ros: the rclpy nodes (plant, map, planner, clock) and the fastep-launch launcher."""

import os as _os
import signal as _signal
import sys as _sys


def _quiet_exit(signum: int, frame: object) -> None:
    _sys.exit(0)


# A node started by fastep-launch that is stopped while it is still importing (Ctrl-C right after the start)
# ends quietly instead of printing a KeyboardInterrupt traceback; its main() then installs rclpy's handling.
if _os.environ.get('FASTEP_PARENT_PID') and _os.getppid() == int(_os.environ['FASTEP_PARENT_PID']):
    _signal.signal(_signal.SIGINT, _quiet_exit)
