"""fastep_ros.dds_profile: the Fast DDS profile fastep-launch gives its processes."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from fastep_ros.dds_profile import ANNOUNCEMENT_PERIOD, PROFILE_ENV, use_discovery_profile
from fastep_testing.graph import free_domain


def test_the_profile_is_written_and_named_only_where_it_is_fast_dds_and_unset(tmp_path: Path) -> None:
    env: dict[str, str] = {}
    path = use_discovery_profile(env)
    assert path is not None
    try:
        assert env == {PROFILE_ENV[0]: str(path)}
        text = path.read_text()
        assert '<leaseAnnouncement><sec>0</sec><nanosec>250000000</nanosec></leaseAnnouncement>' in text
        assert ANNOUNCEMENT_PERIOD == 0.25
    finally:
        path.unlink()
    theirs = {PROFILE_ENV[1]: str(tmp_path / 'theirs.xml')}
    assert use_discovery_profile(theirs) is None and theirs == {PROFILE_ENV[1]: str(tmp_path / 'theirs.xml')}
    other_rmw = {'RMW_IMPLEMENTATION': 'rmw_cyclonedds_cpp'}
    assert use_discovery_profile(other_rmw) is None and other_rmw == {'RMW_IMPLEMENTATION': 'rmw_cyclonedds_cpp'}


def test_fast_dds_takes_the_profile() -> None:
    """A node started with the profile says nothing of it: Fast DDS reports an XML it cannot parse (on stdout)."""
    env: dict[str, str] = {'ROS_DOMAIN_ID': str(free_domain()), 'ROS_AUTOMATIC_DISCOVERY_RANGE': 'LOCALHOST'}
    path = use_discovery_profile(env)
    assert path is not None
    try:
        code = 'import rclpy; rclpy.init(); n = rclpy.create_node("probe"); n.destroy_node(); rclpy.shutdown()'
        done = subprocess.run([sys.executable, '-c', code], env={**os.environ, **env}, capture_output=True, text=True,
                              timeout=60)
        assert done.returncode == 0, done.stderr
        assert 'XMLPARSER' not in done.stdout + done.stderr, done.stdout
        broken = path.read_text().replace('</sec>', '</sek>')
        path.write_text(broken)
        done = subprocess.run([sys.executable, '-c', code], env={**os.environ, **env}, capture_output=True, text=True,
                              timeout=60)
        assert 'XMLPARSER' in done.stdout + done.stderr   # so the check above can fail
    finally:
        path.unlink()
