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

Nothing waits without a bound: the peer at ADDRESS must answer as a Dask scheduler within CONNECT_TIMEOUT (a port
that accepts and never speaks, an HTTP server, a Dask worker: one line, exit 2). A worker that dies has its tasks
rerun by the scheduler (up to `scheduler.allowed-failures` deaths each); a batch with tasks left and no worker in
the cluster waits configured_no_worker_timeout() s for one to join, then ends with BatchIncomplete: what is done
stays the caller's, the items not finished are in it, one line.
"""

from __future__ import annotations

import argparse
import asyncio
import concurrent.futures
import contextlib
import itertools
import logging
import math
import re
import uuid
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Iterable, Iterator, TypeVar, cast

from fastep_core.errors import FastepError

if TYPE_CHECKING:
    from distributed import Client

__all__ = ['ClusterError', 'BatchIncomplete', 'ClusterSpec', 'Engine', 'cluster_spec', 'open_cluster', 'MISSING',
           'CLUSTER_HELP', 'CONNECT_TIMEOUT', 'NO_WORKER_TIMEOUT', 'WORKER_CHECK',
           'configured_no_worker_timeout',
           'RETRIES', 'WINDOW_PER_WORKER']

T = TypeVar('T')
R = TypeVar('R')

MISSING = "--cluster needs Dask: pip install 'fastep_ros[cluster]'"
CLUSTER_HELP = ('run on a Dask cluster instead of --workers processes: the address of a running scheduler '
                '(tcp://HOST:8786), or local:N for N worker processes on this machine; needs the extra '
                "fastep_ros[cluster]; the same results")
CONNECT_TIMEOUT = 5.0
"""Seconds for the peer at --cluster ADDRESS to answer as a Dask scheduler (its identity), and for each step of
the client joining it or a local cluster starting: a scheduler answers in milliseconds on a LAN and well under a
second across the world. Beyond it: one line and exit 2 (nothing listening; a port that accepts and never speaks,
or an HTTP server, which once held fastep-bench silent for 289 s; a peer that is not a scheduler)."""
NO_WORKER_TIMEOUT = 60.0
"""Seconds a batch with tasks left and no worker in the cluster waits for one to join (again), unless the Dask
config sets `distributed.scheduler.no-workers-timeout` (Dask's own bound on a task waiting without a worker; e.g.
DASK_DISTRIBUTED__SCHEDULER__NO_WORKERS_TIMEOUT=10m for workers that queue for a machine). A minute covers a
worker restarted by its nanny or its machine (seconds). Beyond it the batch ends (BatchIncomplete): the runs done
are written, the rest said to be missing, one line; its only worker killed, a batch once waited for ever."""
WORKER_CHECK = 1.0
"""Seconds without a result after which the scheduler is asked whether any worker is left: a lost worker is
noticed within about a second, at the cost of one small request per second of waiting."""
RETRIES = 3
"""A task that raises is tried again this often (a worker that dies costs its tasks nothing: the scheduler
reschedules them, up to distributed's `scheduler.allowed-failures` deaths per task)."""
WINDOW_PER_WORKER = 4
"""Tasks in flight per worker thread: enough that no worker waits for the next, few enough to hold in memory."""
MAX_LOCAL = 256

_ADDRESS = re.compile(r'^(?:(tcp|tls|ws|wss)://)?([A-Za-z0-9_.\-]+|\[[0-9A-Fa-f:]+\]):(\d{1,5})$')


class ClusterError(FastepError):
    """Dask is missing, a scheduler cannot be reached, or a task killed worker after worker."""


class BatchIncomplete(ClusterError):
    """A batch ended before every task: no worker came back within Engine.no_worker_timeout, the scheduler went
    away, or a task killed every worker it ran on. `missing`: the items without a result (those in flight, then those
    never submitted); `done`: what the batch's owner kept of the rest (experiments.run_batch: its records)."""

    def __init__(self, reason: str, done: int, missing: list[Any]) -> None:
        super().__init__(f'{reason}: {done} of {done + len(missing)} runs done, {len(missing)} missing')
        self.reason = reason
        self.missing = missing
        self.total = done + len(missing)
        self.done: list[Any] = []


class _Lost(Exception):
    """No result can come: the cluster has no worker (none joined in time), or no scheduler."""


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


def configured_no_worker_timeout() -> float:
    """Seconds a batch waits for a worker when none is left: `distributed.scheduler.no-workers-timeout` from the
    Dask config, NO_WORKER_TIMEOUT when it is unset; a ClusterError (one line) for a value that is no duration."""
    import dask
    from dask.utils import parse_timedelta
    value = dask.config.get('distributed.scheduler.no-workers-timeout', None)
    if value is None:
        return NO_WORKER_TIMEOUT
    try:
        seconds = float(parse_timedelta(value, default='s'))
    except (TypeError, ValueError, KeyError):   # KeyError: an unknown unit
        seconds = math.nan
    if not (math.isfinite(seconds) and seconds >= 0.0):
        raise ClusterError(f'distributed.scheduler.no-workers-timeout: expected a duration >= 0, got {value!r}')
    return seconds


class Engine:
    """A connected Dask client: `map_unordered` for batches, `map` for differential evolution."""

    def __init__(self, client: Client, retries: int = RETRIES, no_worker_timeout: float | None = None) -> None:
        self.client = client
        self.retries = retries
        self.no_worker_timeout = configured_no_worker_timeout() if no_worker_timeout is None else no_worker_timeout

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
        leave), the next items taken from `items` as they end. BatchIncomplete when no result can come (no worker
        within no_worker_timeout, no scheduler, a task that killed every worker it ran on): the items not done in
        it, those in flight cancelled."""
        todo = iter(items)
        keys = self._keys(name)
        size = window or WINDOW_PER_WORKER * self.threads
        running: dict[Any, T] = {}      # future -> its item, in submission order
        done = 0

        def feed(n: int) -> None:
            for item in itertools.islice(todo, max(n, 0)):
                running[self.client.submit(job, item, key=next(keys), retries=self.retries)] = item

        feed(size)
        while running:
            try:
                finished = self._finished(running)
                results = [(future, self._result(future)) for future in finished]
            except (_Lost, ClusterError) as exc:
                missing = [*running.values(), *todo]
                with contextlib.suppress(Exception):   # a scheduler that went away has nothing to cancel
                    cast(Any, self.client).cancel(list(running))
                raise BatchIncomplete(str(exc), done, missing) from None
            for future, result in results:
                del running[future]
                future.release()
                done += 1
                if window is None and done % size == 0:
                    size = WINDOW_PER_WORKER * self.threads
                feed(size - len(running))
                yield result

    def map(self, job: Callable[[T], R], items: Iterable[T], name: str = 'fastep') -> list[R]:
        """[job(item) for item in items], on the cluster, in order (a map-like `workers=` for scipy)."""
        items = list(items)
        if not items:
            return []
        keys = self._keys(name)
        futures = self.client.map(job, items, key=[next(keys) for _ in items], retries=self.retries)
        try:
            waiting = dict.fromkeys(futures)
            while waiting:
                for future in self._finished(waiting):
                    del waiting[future]
            return [self._result(f) for f in futures]
        except _Lost as exc:
            raise ClusterError(str(exc)) from None
        finally:
            with contextlib.suppress(Exception):   # a scheduler that went away has nothing to cancel
                cast(Any, self.client).cancel(futures)

    def _finished(self, running: dict[Any, Any]) -> list[Any]:
        """The futures of `running` that have ended (one at least). Every WORKER_CHECK s without one, the scheduler
        is asked for its workers; with none, one has no_worker_timeout s to join, or _Lost."""
        distributed = _distributed()
        while True:
            try:
                with cast(Any, self.client).as_current():   # distributed.wait takes the current client
                    return list(distributed.wait(list(running), timeout=WORKER_CHECK,
                                                 return_when='FIRST_COMPLETED').done)
            except TimeoutError:
                pass
            except distributed.CancelledError:
                raise _Lost('lost the Dask scheduler (its tasks were cancelled)') from None
            self._a_worker()

    def _a_worker(self) -> None:
        """Return when the cluster has a worker, waiting up to no_worker_timeout s for one to join; _Lost if none
        did, or the scheduler cannot say."""
        client = cast(Any, self.client)
        try:
            if client.nthreads():
                return
            if self.no_worker_timeout > 0:   # wait_for_workers(timeout=0) would wait for ever
                with contextlib.suppress(TimeoutError):
                    client.wait_for_workers(1, timeout=self.no_worker_timeout)
                    return
        except Exception as exc:
            raise _Lost(f'lost the Dask scheduler ({_line(exc)})') from None
        raise _Lost(f'no Dask worker in the cluster for {self.no_worker_timeout:g} s '
                    '(distributed.scheduler.no-workers-timeout)')

    def _result(self, future: Any) -> Any:
        distributed = _distributed()
        try:
            return future.result()
        except distributed.KilledWorker as exc:
            raise ClusterError(f'a task killed every worker it ran on ({_line(exc)})') from None
        except (distributed.scheduler.NoWorkerError, distributed.scheduler.NoValidWorkerError) as exc:
            raise _Lost(f'the Dask scheduler found no worker for a task ({_line(exc)})') from None
        except distributed.CancelledError:
            raise _Lost('lost the Dask scheduler (its tasks were cancelled)') from None


@contextlib.contextmanager
def open_cluster(spec: ClusterSpec | str, timeout: float = CONNECT_TIMEOUT) -> Iterator[Engine]:
    """An Engine on the cluster `spec` names; a local cluster is started here and shut down on leaving."""
    if isinstance(spec, str):
        try:
            spec = cluster_spec(spec)
        except argparse.ArgumentTypeError as exc:
            raise ClusterError(str(exc)) from None
    distributed = _distributed()
    no_worker_timeout = configured_no_worker_timeout()   # a bad value: one line before connecting
    with contextlib.ExitStack() as stack:
        # The client logs a traceback of its own while it retries a scheduler that went away; what that means for
        # the batch is one line of ours (BatchIncomplete, ClusterError).
        client_log = logging.getLogger('distributed.client')
        stack.callback(client_log.setLevel, client_log.level)
        client_log.setLevel(logging.CRITICAL)
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
            _is_a_scheduler(distributed, address, timeout)
        try:
            client = stack.enter_context(distributed.Client(address, timeout=timeout, set_as_default=False))
        except Exception as exc:  # OSError after the timeout; a scheduler that stopped answering
            raise ClusterError(f'cannot reach the Dask scheduler at {address}: {_line(exc)}') from None
        yield Engine(client, no_worker_timeout=no_worker_timeout)


def _is_a_scheduler(distributed: Any, address: str, timeout: float) -> None:
    """Return when the peer at `address` says, within `timeout` s, that it is a Dask scheduler; else ClusterError.

    Asked before Client(address, timeout=): the client bounds its connection attempts and each request, but not
    the handshake in between, where a peer that accepts and never speaks held it for ever. Asked on an event loop
    of its own, in a thread of its own, so a caller's running loop (a notebook) is no matter."""
    async def identity() -> Any:
        args = distributed.Security().get_connection_args('client')   # tls:// as the client will connect
        scheduler = distributed.rpc(address, timeout=timeout, connection_args=args)
        try:
            return await scheduler.identity()
        finally:
            await scheduler.close_rpc()

    async def bounded() -> Any:
        return await asyncio.wait_for(identity(), timeout)
    with concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix='fastep-scheduler-probe') as probe:
        try:
            info = probe.submit(asyncio.run, bounded()).result()
        except TimeoutError:
            raise ClusterError(f'no Dask scheduler at {address}: no answer within {timeout:g} s') from None
        except Exception as exc:  # refused, reset, bytes that are not Dask's
            raise ClusterError(f'no Dask scheduler at {address}: {_line(exc)}') from None
    kind = info.get('type') if isinstance(info, dict) else None
    if kind != 'Scheduler':
        raise ClusterError(f'no Dask scheduler at {address}: the peer is a {kind or "stranger"}')


def _line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return (text[0] if text else type(exc).__name__)[:200]
