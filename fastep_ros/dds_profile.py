"""Fast DDS discovery settings for the processes fastep-launch starts, and for the launcher's own participant.

A DDS participant that joins while others exist sometimes drops their endpoint announcements (they can arrive
before it has taken the announcement of the participant that sent them) and learns those endpoints only when that
participant announces itself again: every 3 s by Fast DDS's default. A launch starts its processes at once, so
most starts waited 1.5-2.5 s for a planner's goal subscription or the recorder's odometry subscription to match
(measured with two small processes: 1 start in 8 matched after 2.9 s, the others after 0.05 s; with announcements
every 0.25 s the slow one took 0.18 s). fastep-launch therefore has each participant announce itself every
ANNOUNCEMENT_PERIOD: a few hundred bytes per participant and period, handled by Fast DDS's own threads.

Only with Fast DDS (the default rmw, the only one in the PyPI wheels) and only when the user has not given a
profile file of their own (FASTRTPS_DEFAULT_PROFILES_FILE / FASTDDS_DEFAULT_PROFILES_FILE): theirs is kept.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import MutableMapping
from pathlib import Path

__all__ = ['ANNOUNCEMENT_PERIOD', 'PROFILE_ENV', 'use_discovery_profile']

ANNOUNCEMENT_PERIOD = 0.25   # seconds between a participant's announcements (Fast DDS's default: 3)
PROFILE_ENV = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE')
FAST_DDS = ('', 'rmw_fastrtps_cpp', 'rmw_fastrtps_dynamic_cpp')

_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<!-- Written by fastep-launch for the processes it starts (fastep_ros/dds_profile.py says why). -->
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <participant profile_name="fastep_launch" is_default_profile="true">
    <rtps>
      <builtin>
        <discovery_config>
          <leaseAnnouncement><sec>{sec}</sec><nanosec>{nanosec}</nanosec></leaseAnnouncement>
        </discovery_config>
      </builtin>
    </rtps>
  </participant>
</profiles>
"""


def use_discovery_profile(env: MutableMapping[str, str] = os.environ) -> Path | None:
    """Write the profile to a temporary file and name it in `env` (the launcher's environment, which its processes
    inherit); None, `env` unchanged, when the rmw is not Fast DDS or a profile file is set already. The caller
    removes the file at the end."""
    if any(env.get(name) for name in PROFILE_ENV) or env.get('RMW_IMPLEMENTATION', '') not in FAST_DDS:
        return None
    nanoseconds = round(ANNOUNCEMENT_PERIOD * 1e9)
    fd, name = tempfile.mkstemp(prefix='fastep_launch_', suffix='.xml')
    with os.fdopen(fd, 'w') as out:
        out.write(_PROFILE.format(sec=nanoseconds // 1_000_000_000, nanosec=nanoseconds % 1_000_000_000))
    env[PROFILE_ENV[0]] = name
    return Path(name)
