"""Robots on separate computers (fastep_testing.multi_host): hosts as network namespaces on a bridge."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from fastep_testing.graph import free_domain, isolated_env, stop_process
from fastep_testing.hosts import Hosts, HostsError, remove_stale

pytestmark = pytest.mark.skipif(os.geteuid() != 0 or shutil.which('ip') is None,
                                reason='network namespaces need root and iproute2')


# One ICMP echo from a raw socket (root may open one; the machine need not have ping), exit 0 on the reply.
PING = """
import socket, struct, sys
s = socket.socket(socket.AF_INET, socket.SOCK_RAW, socket.IPPROTO_ICMP)
s.settimeout(1.0)
body = struct.pack('!BBHHH', 8, 0, 0, 7, 1) + b'fastep'
words = sum(struct.unpack('!%dH' % (len(body) // 2), body))
words = (words >> 16) + (words & 0xffff)
checksum = ~(words + (words >> 16)) & 0xffff
s.sendto(body[:2] + struct.pack('!H', checksum) + body[4:], (sys.argv[1], 0))
try:
    while True:
        data, peer = s.recvfrom(1024)
        if peer[0] == sys.argv[1] and data[20] == 0:
            raise SystemExit(0)
except socket.timeout:
    raise SystemExit(1)
"""


def _reaches(hosts: Hosts, k: int, address: str) -> bool:
    return hosts.run(k, [sys.executable, '-c', PING, address]).returncode == 0


def test_hosts_reach_each_other_over_their_links_only_and_a_dropped_link_cuts_one_off() -> None:
    with Hosts(3) as hosts:
        names = list(hosts.names)
        assert _reaches(hosts, 1, hosts.addresses[0]) and _reaches(hosts, 2, hosts.addresses[1])
        hosts.drop(2)
        assert not _reaches(hosts, 0, hosts.addresses[2]) and _reaches(hosts, 0, hosts.addresses[1])
        hosts.restore(2)
        assert _reaches(hosts, 0, hosts.addresses[2])
    listed = subprocess.run(['ip', 'netns', 'list'], capture_output=True, text=True).stdout
    assert not any(name in listed for name in names), 'every namespace is removed'


def test_namespaces_of_a_harness_that_died_are_removed_and_bad_counts_are_one_line() -> None:
    dead = subprocess.Popen([sys.executable, '-c', 'pass'])
    dead.wait()
    name = f'fastep-mh{dead.pid}-h0'
    subprocess.run(['ip', 'netns', 'add', name], check=True)
    try:
        assert name in remove_stale()
    finally:
        subprocess.run(['ip', 'netns', 'delete', name], capture_output=True)
    with pytest.raises(HostsError, match='hosts must be >= 1'):
        Hosts(0)


def _harness(tmp_path: Path, *args: str, timeout: float = 240.0) -> tuple[int, str, dict]:
    out = tmp_path / 'run.json'
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    proc = subprocess.Popen([sys.executable, '-m', 'fastep_testing.multi_host', *args, '--json', str(out)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, stdin=subprocess.DEVNULL)
    try:
        stdout, _ = proc.communicate(timeout=timeout)
    finally:
        stop_process(proc)
    return proc.returncode, stdout, json.loads(out.read_text()) if out.is_file() else {}


def test_robots_on_another_host_make_the_run_fastep_sim_makes(tmp_path: Path) -> None:
    """The map and the clock on host 0, both robots on host 1, discovered by multicast over the bridge, UDP only:
    in lock step, the very run of fastep-sim."""
    code, stdout, data = _harness(tmp_path, '--hosts', '2', '--robots', '2', '--radius', '6')
    assert code == 0, stdout
    assert 'r1 on host 1, r2 on host 1' in stdout and '2 robot(s) on their way' in stdout
    assert "the run is fastep-sim's" in stdout
    assert data['multi_host']['same_as_fastep_sim'] and data['multi_host']['max_position_difference'] == 0.0
    assert all(r['reached'] for r in data['runs'][0]['robots'])


def test_static_peers_without_multicast_and_a_link_dropping_out_on_wall_time(tmp_path: Path) -> None:
    """Multicast off on every link (discovery by ROS_STATIC_PEERS), each robot on a host of its own, on wall time;
    r2's host loses its link for 2 s on the way: both robots still arrive, timed on the wall clock."""
    code, stdout, data = _harness(tmp_path, '--hosts', '3', '--robots', '2', '--radius', '6', '--peers',
                                  '--no-clock', '--drop', '2', '--drop-at', '1', '--drop-for', '2')
    assert code == 0, stdout
    assert 'discovery by ROS_STATIC_PEERS, multicast off' in stdout and 'r1 on host 1, r2 on host 2' in stdout
    drop = data['multi_host']['drop']
    assert [event.split(' at ')[0] for event in drop['events']] == ['host 2 link down', 'host 2 link up']
    robots = data['runs'][0]['robots']
    assert all(r['reached'] and not r['collided'] for r in robots)
    # 12 m across the circle at 2 m/s at most: a wall-clock time of at least 6 s (not the 0.0 s of a status
    # time cut to six digits).
    assert all(r['sim_time'] >= 6.0 for r in robots), [r['sim_time'] for r in robots]
