"""--cluster batches that cannot hang (experiments.cluster): a peer that is no Dask scheduler is given up on with one
line and exit 2; a batch whose only worker dies for good ends once no worker came back within the bound, with the
runs done written, those that did not finish said to be missing, one line and exit 1. The commands run in
subprocesses with a generous outer timeout: before these bounds, both waited for ever (or for minutes)."""

from __future__ import annotations

import contextlib
import http.server
import json
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path
from typing import Callable, ContextManager, Iterator

import pytest

from fastep_core.experiments import batches
from fastep_core.experiments.cluster import ClusterError, open_cluster

distributed = pytest.importorskip('distributed')

REPO = Path(__file__).resolve().parents[2]
OUTER = 300.0
"""Seconds a command may take in these tests before it counts as hung: far beyond the bounds under test, so a
loaded machine (imports, a worker starting) never trips it."""
OUTER_CONNECT = 120.0
"""The same for a command that only has to give up on its --cluster (a few seconds of imports, then the bound)."""


@contextlib.contextmanager
def silent_listener() -> Iterator[int]:
    """A TCP port that accepts every connection and never says a word (nor closes it)."""
    server = socket.create_server(('127.0.0.1', 0))
    held: list[socket.socket] = []

    def accept() -> None:
        with contextlib.suppress(OSError):       # the listener closed: the test is over
            while True:
                held.append(server.accept()[0])
    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        yield server.getsockname()[1]
    finally:
        server.close()
        for conn in held:
            conn.close()


@contextlib.contextmanager
def http_listener() -> Iterator[int]:
    """An HTTP server (it answers what it cannot parse with a 400 page and hangs up)."""
    server = http.server.ThreadingHTTPServer(('127.0.0.1', 0), http.server.BaseHTTPRequestHandler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield server.server_address[1]
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.parametrize('listener', [silent_listener, http_listener])
@pytest.mark.parametrize('command', ['msg_tools.bench_cli', 'fastep_core.experiments.tuning'])
def test_a_peer_that_is_no_scheduler_is_one_line_and_exit_2(command: str,
                                                            listener: Callable[[], ContextManager[int]]) -> None:
    tiny = ['--runs', '1', '--scenarios', 'table2_s3', '--algorithms', 'optimal', '--no-figures', '--out', '/nowhere'] \
        if command == 'msg_tools.bench_cli' else ['--popsize', '1', '--maxiter', '1']
    with listener() as port:
        done = subprocess.run([sys.executable, '-m', command, *tiny, '--cluster', f'tcp://127.0.0.1:{port}'],
                              capture_output=True, text=True, timeout=OUTER_CONNECT, cwd=REPO)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in done.stderr, done.stderr
    assert f'tcp://127.0.0.1:{port}' in lines[0] and 'no Dask scheduler' in lines[0], lines[0]
    assert done.stdout == ''


RUNNER = '''
import os, sys, time
from distributed import get_worker
from fastep_core.experiments import batches
from msg_tools.bench_cli import main


class DieAfter:
    """run_task, writing a file per run that ended; the run after `done` of them kills its worker (no nanny
    brings it back), once the client took every result made (none left in the worker's memory)."""

    def __init__(self, folder, done):
        self.folder, self.done = folder, done

    def __call__(self, task, **kwargs):
        if len(os.listdir(self.folder)) >= self.done:
            worker, deadline = get_worker(), time.monotonic() + 120.0
            while len(worker.data) and time.monotonic() < deadline:
                time.sleep(0.05)
            os._exit(17)
        records = batches.run_task(task, **kwargs)
        open(os.path.join(self.folder, '%s %s %d' % task), 'x').close()
        return records


batches.run_task = DieAfter(sys.argv[1], int(sys.argv[2]))   # pickled by value: it lives in __main__
sys.exit(main(sys.argv[3:]))
'''


def test_a_batch_whose_only_worker_dies_ends_with_the_done_runs_written(tmp_path: Path) -> None:
    ended = tmp_path / 'ended'
    ended.mkdir()
    out = tmp_path / 'out'
    every = batches.tasks(['table2_s3'], ['fastep'], 5)
    # The scheduler of a LocalCluster (in this process) and one worker process without a nanny: killed, it stays
    # dead, as a `dask worker` on another machine that went away.
    with distributed.LocalCluster(n_workers=0, host='127.0.0.1', scheduler_port=0,
                                  dashboard_address='127.0.0.1:0') as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        worker = subprocess.Popen([sys.executable, '-m', 'distributed.cli.dask_worker', cluster.scheduler_address,
                                   '--no-nanny', '--nthreads', '1', '--no-dashboard'], cwd=REPO,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            client.wait_for_workers(1, timeout=OUTER)
            env = {**os.environ, 'DASK_DISTRIBUTED__SCHEDULER__NO_WORKERS_TIMEOUT': '5s'}
            done = subprocess.run(
                [sys.executable, '-c', RUNNER, str(ended), '2', '--runs', '5', '--scenarios', 'table2_s3',
                 '--algorithms', 'fastep', '--no-figures', '--cluster', cluster.scheduler_address,
                 '--out', str(out), '--json', str(out / 'runs.json')],
                capture_output=True, text=True, timeout=OUTER, cwd=REPO, env=env)
        finally:
            worker.kill()
            worker.wait(timeout=OUTER)
    assert worker.returncode == 17                          # it did die in the middle of the batch
    assert done.returncode == 1, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and 'Traceback' not in done.stderr, done.stderr
    assert 'no Dask worker' in lines[0] and '2 of 5 runs done, 3 missing' in lines[0], lines[0]
    finished = sorted(name.name for name in ended.iterdir())
    assert len(finished) == 2
    data = json.loads((out / 'runs.json').read_text())
    assert sorted(f'{r["scenario"]} {r["algorithm"]} {r["seed"]}' for r in data['records']) == finished
    missing = [(m['scenario'], m['algorithm'], m['seed']) for m in data['missing']]
    assert sorted(missing + [(r['scenario'], r['algorithm'], r['seed']) for r in data['records']]) == every
    report = (out / 'table2.md').read_text()
    assert '### Runs missing' in report and '3 of 5 runs' in report and 'table2_s3 fastep seeds' in report, report


@pytest.mark.parametrize('value', ['soon', '-1s', 'inf'])
def test_a_bad_no_workers_timeout_is_one_line_before_any_cluster(value: str) -> None:
    import dask
    with dask.config.set({'distributed.scheduler.no-workers-timeout': value}):
        with pytest.raises(ClusterError, match='distributed.scheduler.no-workers-timeout: expected a duration'):
            with open_cluster('tcp://127.0.0.1:1'):    # refused at once were it asked
                pass
