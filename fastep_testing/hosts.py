"""Computers on one machine: Linux network namespaces joined by a bridge, for runs that span "hosts".

Each host is a network namespace with a loopback and one veth link (`eth0`, 10.77.0.<k+1>/24) whose other end is
on a bridge in a namespace of its own (the switch), so nothing of the machine's own network is touched and two
harnesses never see each other. A host reaches the others only over its link: `drop(k)` takes host k's link down
(a Wi-Fi drop-out), `restore(k)` brings it back. `multicast=False` turns multicast off on every link, as on many
Wi-Fi networks: DDS then finds its peers only through ROS_STATIC_PEERS (`peers`). Needs root (CAP_NET_ADMIN) and
iproute2's `ip`. Namespaces left behind by a harness that was killed are removed when the next one starts.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from typing import Sequence

__all__ = ['Hosts', 'HostsError', 'SUBNET']

SUBNET = '10.77.0'          # host k is SUBNET.(k+1)
PREFIX = 'fastep-mh'        # namespace names: fastep-mh<pid>-h<k>, fastep-mh<pid>-sw
_NAME = re.compile(rf'^{PREFIX}(\d+)-(h\d+|sw)$')


class HostsError(Exception):
    """The namespaces cannot be made (not root, no `ip`, a command that failed); one line."""


def _ip(*args: str) -> None:
    proc = subprocess.run(['ip', *args], capture_output=True, text=True)
    if proc.returncode != 0:
        raise HostsError(f'ip {" ".join(args)}: {proc.stderr.strip() or f"exit {proc.returncode}"}')


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale() -> list[str]:
    """Delete the namespaces of harnesses whose process is gone; their names."""
    proc = subprocess.run(['ip', 'netns', 'list'], capture_output=True, text=True)
    gone = []
    for line in proc.stdout.splitlines():
        name = line.split()[0] if line.split() else ''
        match = _NAME.match(name)
        if match and not _alive(int(match.group(1))):
            subprocess.run(['ip', 'netns', 'delete', name], capture_output=True)
            gone.append(name)
    return gone


class Hosts:
    """`count` hosts on a bridge; a context manager that removes every namespace and link it made."""

    def __init__(self, count: int, multicast: bool = True) -> None:
        if count < 1:
            raise HostsError(f'hosts must be >= 1, got {count}')
        if count > 250:
            raise HostsError(f'hosts must be <= 250 (one /24), got {count}')
        self.count, self.multicast = count, multicast
        tag = f'{PREFIX}{os.getpid()}'
        self.switch = f'{tag}-sw'
        self.names = [f'{tag}-h{k}' for k in range(count)]
        self.made: list[str] = []

    @property
    def addresses(self) -> list[str]:
        return [f'{SUBNET}.{k + 1}' for k in range(self.count)]

    @property
    def peers(self) -> str:
        """ROS_STATIC_PEERS for a node on any of the hosts: every host's address."""
        return ';'.join(self.addresses)

    def exec_prefix(self, k: int) -> list[str]:
        """The command prefix that runs a command on host k."""
        return ['ip', 'netns', 'exec', self.names[k]]

    def __enter__(self) -> Hosts:
        if os.geteuid() != 0:
            raise HostsError('network namespaces need root (CAP_NET_ADMIN): run as root')
        if shutil.which('ip') is None:
            raise HostsError("iproute2's `ip` is not on PATH")
        remove_stale()
        try:
            self._make()
        except BaseException:
            self.close()
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _make(self) -> None:
        for name in (self.switch, *self.names):
            _ip('netns', 'add', name)
            self.made.append(name)
            _ip('-n', name, 'link', 'set', 'lo', 'up')
        _ip('-n', self.switch, 'link', 'add', 'br0', 'type', 'bridge')
        _ip('-n', self.switch, 'link', 'set', 'br0', 'up')
        for k, name in enumerate(self.names):
            # Made in the switch, then one end moved to the host (short names: a link's is at most 15 characters).
            _ip('-n', self.switch, 'link', 'add', f'p{k}', 'type', 'veth', 'peer', 'name', 'eth0', 'netns', name)
            _ip('-n', self.switch, 'link', 'set', f'p{k}', 'master', 'br0')
            _ip('-n', self.switch, 'link', 'set', f'p{k}', 'up')
            _ip('-n', name, 'addr', 'add', f'{self.addresses[k]}/24', 'dev', 'eth0')
            if not self.multicast:
                _ip('-n', name, 'link', 'set', 'eth0', 'multicast', 'off')
            _ip('-n', name, 'link', 'set', 'eth0', 'up')
            if self.multicast:
                # DDS discovery sends to 239.255.0.1: without a route for it a send fails (no default route here).
                _ip('-n', name, 'route', 'add', '224.0.0.0/4', 'dev', 'eth0')

    def drop(self, k: int) -> None:
        """Host k's link goes down at the switch: it reaches no other host until restore(k)."""
        _ip('-n', self.switch, 'link', 'set', f'p{k}', 'down')

    def restore(self, k: int) -> None:
        _ip('-n', self.switch, 'link', 'set', f'p{k}', 'up')

    def run(self, k: int, cmd: Sequence[str], **kwargs: object) -> subprocess.CompletedProcess[str]:
        """Run `cmd` on host k to its end (text output captured)."""
        return subprocess.run([*self.exec_prefix(k), *cmd], capture_output=True, text=True, **kwargs)  # type: ignore[call-overload]  # kwargs are subprocess.run's

    def close(self) -> None:
        """Delete the namespaces (their links go with them). Safe to call twice."""
        for name in reversed(self.made):
            subprocess.run(['ip', 'netns', 'delete', name], capture_output=True)
        self.made = []
