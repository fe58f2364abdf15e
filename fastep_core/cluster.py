"""Batches on a Dask cluster: `--cluster ADDRESS` (a running scheduler) or `--cluster local:N` (N worker processes).

Why Dask (distributed), not Ray: it is pure Python and light to start on a laptop (Ray starts a raylet, a GCS and a
shared-memory object store); its futures take `retries=`, and the scheduler hands the tasks of a lost worker to
another one by itself; `Client(address)` joins an existing cluster (`dask scheduler`, `dask worker ADDRESS` on
other machines); `as_completed` gives results as they end, for the progress bar. It is an optional extra
(`pip install 'fastep_ros[cluster]'`), imported only here and only when a cluster is asked for.

The results do not depend on the engine: a task is a deterministic function of (scenario, algorithm, seed,
overrides), and the callers sort what comes back. `Engine.map_unordered` keeps a bounded window of tasks in
flight, fed from an iterator (experiments.Tasks never makes a whole batch at once); `Engine.map` keeps the order
(differential evolution's `workers=`). Each task has a key of its own (batch id + index).
"""

from __future__ import annotations

import argparse
import contextlib
import itertools
import re
import uuid
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator, TypeVar, cast

from fastep_core.errors import FastepError

if TYPE_CHECKING:
    from distributed import Client

__all__ = ['ClusterError', 'ClusterSpec', 'Engine', 'cluster_spec', 'open_cluster', 'MISSING', 'CLUSTER_HELP',
           'CONNECT_TIMEOUT',
           'RETRIES', 'WINDOW_PER_WORKER']

T = TypeVar('T')
R = TypeVar('R')

MISSING = "--cluster needs Dask: pip install 'fastep_ros[cluster]'"
CLUSTER_HELP = ('run on a Dask cluster instead of --workers processes: the address of a running scheduler '
                '(tcp://HOST:8786), or local:N for N worker processes on this machine; needs the extra '
                "fastep_ros[cluster]; the same results")
CONNECT_TIMEOUT = 5.0
"""Seconds to reach a scheduler (or start a local cluster's) before giving up with one line."""
RETRIES = 3
"""A task that raises is tried again this often (a worker that dies costs its tasks nothing: the scheduler
reschedules them, up to distributed's `scheduler.allowed-failures` deaths per task)."""
WINDOW_PER_WORKER = 4
"""Tasks in flight per worker thread: enough that no worker waits for the next, few enough to hold in memory."""
MAX_LOCAL = 256

_ADDRESS = re.compile(r'^(?:(tcp|tls|ws|wss)://)?([A-Za-z0-9_.\-]+|\[[0-9A-Fa-f:]+\]):(\d{1,5})$')


class ClusterError(FastepError):
    """Dask is missing, a scheduler cannot be reached, or a task killed worker after worker."""


@dataclass(frozen=True)
class ClusterSpec:
    """What --cluster names: `local` worker processes on this machine, or the `address` of a scheduler."""

    local: int = 0
    address: str = ''

    def __str__(self) -> str:
        return f'local:{self.local}' if self.local else self.address


def cluster_spec(text: str) -> ClusterSpec:
    """Parse `local:N` (1 <= N <= 256) or a scheduler address `[tcp://]HOST:PORT` (the argparse type of
    --cluster: argparse.ArgumentTypeError, one line, for anything else)."""
    kind, colon, rest = text.partition(':')
    if kind == 'local' and colon:
        if not rest.isdigit() or not 1 <= int(rest) <= MAX_LOCAL:
            raise argparse.ArgumentTypeError(f'local:N needs 1 <= N <= {MAX_LOCAL} worker processes, got {text!r}')
        return ClusterSpec(local=int(rest))
    found = _ADDRESS.match(text)
    if found is None or not 1 <= int(found.group(3)) <= 65535:
        raise argparse.ArgumentTypeError(f'expected local:N or a scheduler address like tcp://HOST:8786, got {text!r}')
    return ClusterSpec(address=text if found.group(1) else f'tcp://{text}')


def _distributed() -> Any:
    """The distributed module, or a ClusterError saying how to install it."""
    try:
        import distributed
    except ImportError:
        raise ClusterError(MISSING) from None
    return distributed


class Engine:
    """A connected Dask client: `map_unordered` for batches, `map` for differential evolution."""

    def __init__(self, client: Client, retries: int = RETRIES) -> None:
        self.client = client
        self.retries = retries

    @property
    def threads(self) -> int:
        """Worker threads in the cluster now (at least 1)."""
        return max(1, int(sum(cast(Any, self.client).nthreads().values())))   # untyped in distributed

    def _keys(self, name: str) -> Iterator[str]:
        batch = uuid.uuid4().hex[:12]   # a name only, so two clients of one scheduler never share a key
        return (f'{name}-{batch}-{i}' for i in itertools.count())

    def map_unordered(self, job: Callable[[T], R], items: Iterable[T], name: str = 'fastep',
                      window: int | None = None) -> Iterator[R]:
        """job(item) for every item, in the order they finish; at most `window` submitted and not yet yielded
        (default WINDOW_PER_WORKER x the worker threads, counted again as results come: workers may join or
        leave), the next items taken from `items` as they end."""
        distributed = _distributed()
        todo = iter(items)
        keys = self._keys(name)
        size = window or WINDOW_PER_WORKER * self.threads
        running = distributed.as_completed(loop=self.client.loop)
        in_flight = done = 0

        def feed(n: int) -> None:
            nonlocal in_flight
            for item in itertools.islice(todo, max(n, 0)):
                running.add(self.client.submit(job, item, key=next(keys), retries=self.retries))
                in_flight += 1

        feed(size)
        for future in running:
            result = self._result(future)
            future.release()
            in_flight, done = in_flight - 1, done + 1
            if window is None and done % size == 0:
                size = WINDOW_PER_WORKER * self.threads
            feed(size - in_flight)
            yield result

    def map(self, job: Callable[[T], R], items: Iterable[T], name: str = 'fastep') -> list[R]:
        """[job(item) for item in items], on the cluster, in order (a map-like `workers=` for scipy)."""
        items = list(items)
        if not items:
            return []
        keys = self._keys(name)
        futures = self.client.map(job, items, key=[next(keys) for _ in items], retries=self.retries)
        try:
            return [self._result(f) for f in futures]
        finally:
            cast(Any, self.client).cancel(futures)

    def _result(self, future: Any) -> Any:
        distributed = _distributed()
        try:
            return future.result()
        except distributed.KilledWorker as exc:
            raise ClusterError(f'a task killed every worker it ran on ({exc})') from None


@contextlib.contextmanager
def open_cluster(spec: ClusterSpec | str, timeout: float = CONNECT_TIMEOUT) -> Iterator[Engine]:
    """An Engine on the cluster `spec` names; a local cluster is started here and shut down on leaving."""
    if isinstance(spec, str):
        try:
            spec = cluster_spec(spec)
        except argparse.ArgumentTypeError as exc:
            raise ClusterError(str(exc)) from None
    distributed = _distributed()
    with contextlib.ExitStack() as stack:
        if spec.local:
            try:
                # Dashboard on a free port (8787 may be taken); one thread per process: runs hold the GIL.
                local = stack.enter_context(distributed.LocalCluster(
                    n_workers=spec.local, threads_per_worker=1, processes=True, dashboard_address='127.0.0.1:0',
                    host='127.0.0.1', scheduler_port=0))
            except Exception as exc:
                raise ClusterError(f'cannot start a local Dask cluster: {_line(exc)}') from None
            address = local.scheduler_address
        else:
            address = spec.address
        try:
            client = stack.enter_context(distributed.Client(address, timeout=timeout, set_as_default=False))
        except Exception as exc:  # OSError after the timeout; a peer that is no scheduler gives stranger ones
            raise ClusterError(f'cannot reach the Dask scheduler at {address}: {_line(exc)}') from None
        yield Engine(client)


def _line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return (text[0] if text else type(exc).__name__)[:200]
