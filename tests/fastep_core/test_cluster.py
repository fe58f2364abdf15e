"""Batches on a Dask cluster (experiments.cluster): the records of the process pool, a lost worker costing only its
task, and one-line errors for a bad --cluster. Every cluster is local and closed by its context manager."""

from __future__ import annotations

import dataclasses
import json
import operator
import os
import subprocess
import sys
from pathlib import Path
from typing import Iterator

import pytest

from fastep_core.experiments import batches, tuning
from fastep_core.experiments.cluster import ClusterError, ClusterSpec, cluster_spec, open_cluster
from msg_tools.bench_cli import main as bench_main

distributed = pytest.importorskip('distributed')

TIMES = ('compute_time', 'cpu_time')   # measured, so different in every run of any engine


def without_times(records: list[batches.Record]) -> list[dict[str, object]]:
    return [{k: v for k, v in dataclasses.asdict(r).items() if k not in TIMES} for r in records]


@pytest.mark.parametrize('text, spec', [('local:2', ClusterSpec(local=2)),
                                        ('tcp://10.0.0.5:8786', ClusterSpec(address='tcp://10.0.0.5:8786')),
                                        ('node-7.lab:8786', ClusterSpec(address='tcp://node-7.lab:8786')),
                                        ('tls://[::1]:8786', ClusterSpec(address='tls://[::1]:8786'))])
def test_cluster_specs(text: str, spec: ClusterSpec) -> None:
    assert cluster_spec(text) == spec and str(spec) in (text, f'tcp://{text}')


@pytest.mark.parametrize('text', ['local:0', 'local:abc', 'local:', 'local:257', 'nohost', 'tcp://h:0',
                                  'tcp://h:99999', 'http://h:8786', 'h:8786/x', ''])
def test_bad_cluster_specs_are_one_line(text: str) -> None:
    with pytest.raises(ClusterError) as raised:
        with open_cluster(text):
            pass
    assert '\n' not in str(raised.value)


def test_without_dask_the_error_says_what_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, 'distributed', None)   # import distributed: ImportError
    with pytest.raises(ClusterError, match=r"--cluster needs Dask: pip install 'fastep_ros\[cluster\]'"):
        with open_cluster('local:1'):
            pass


def test_a_batch_on_a_local_cluster_gives_the_records_of_the_pool() -> None:
    args = (['table2_s1', 'table2_s3'], ['fastep', 'optimal'], 2)
    pooled = batches.run_batch(*args, workers=2)
    clustered = batches.run_batch(*args, cluster='local:2')
    assert [(r.scenario, r.algorithm, r.seed) for r in clustered] == [(r.scenario, r.algorithm, r.seed)
                                                                       for r in pooled]
    assert without_times(clustered) == without_times(pooled)


def test_a_bounded_window_of_tasks_is_in_flight_and_map_keeps_the_order() -> None:
    pulled = []

    def items() -> Iterator[int]:
        for i in range(40):
            pulled.append(i)
            yield i
    with open_cluster('local:1') as engine:
        out = []
        for result in engine.map_unordered(operator.neg, items(), window=3):
            out.append(result)
            assert len(pulled) - len(out) <= 3      # taken from the iterator and not back yet
        assert sorted(out) == sorted(-i for i in range(40))
        assert engine.map(operator.neg, range(25)) == [-i for i in range(25)] and engine.map(abs, []) == []


class DieOnce:
    """run_task, but the first process to start `victim` dies on the spot (os._exit, as a killed worker would)."""

    def __init__(self, marker: Path, victim: batches.Task) -> None:
        self.marker, self.victim = str(marker), victim

    def __call__(self, task: batches.Task) -> list[batches.Record]:
        if task == self.victim:
            try:
                os.close(os.open(self.marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY))
            except FileExistsError:
                pass                # died here once already: run it
            else:
                os._exit(17)
        return batches.run_task(task)


def test_a_lost_worker_costs_only_its_task_which_runs_again(tmp_path: Path) -> None:
    import cloudpickle
    every = batches.Tasks(['table2_s3'], ['fastep'], 3)
    marker = tmp_path / 'died'
    module = sys.modules[DieOnce.__module__]
    cloudpickle.register_pickle_by_value(module)   # the workers cannot import a test module by name
    try:
        with open_cluster('local:2') as engine:
            out = [r for records in engine.map_unordered(DieOnce(marker, every[1]), every) for r in records]
    finally:
        cloudpickle.unregister_pickle_by_value(module)
    assert marker.exists()           # a worker did die in the middle of a task
    out.sort(key=lambda r: (r.seed, r.robot))
    assert without_times(out) == without_times(batches.run_batch(['table2_s3'], ['fastep'], 3, workers=1))


def test_a_tiny_search_on_a_cluster_finds_what_the_pool_finds() -> None:
    kwargs = dict(train=('table2_s3',), seeds=(0,), popsize=1, maxiter=1, seed=3)
    pooled = tuning.tune(workers=2, **kwargs)
    clustered = tuning.tune(cluster='local:2', **kwargs)
    assert (clustered.params, clustered.cost, clustered.evaluations) == (pooled.params, pooled.cost, pooled.evaluations)


def test_fastep_bench_on_a_cluster_writes_the_json_of_the_pool(tmp_path: Path, capsys: pytest.CaptureFixture[str]
                                                              ) -> None:
    common = ['--runs', '2', '--scenarios', 'table2_s3', '--algorithms', 'fastep', 'optimal', '--no-figures']
    for name, engine in (('pool', ['--workers', '2']), ('cluster', ['--cluster', 'local:2'])):
        assert bench_main([*common, *engine, '--out', str(tmp_path / name), '--json', str(tmp_path / f'{name}.json')]
                          ) == 0

    def read(name: str) -> dict[str, object]:
        data = json.loads((tmp_path / f'{name}.json').read_text())
        for record in data['records']:
            for key in TIMES:
                del record[key]
        return data
    assert read('cluster') == read('pool') and len(read('pool')['records']) == 3


@pytest.mark.parametrize('args', [['--cluster', 'local:0'], ['--cluster', 'local:abc'],
                                  ['--cluster', 'local:2', '--workers', '2'],
                                  ['--cluster', 'tcp://127.0.0.1:1']])   # nothing listens there: refused
@pytest.mark.parametrize('command', ['msg_tools.bench_cli', 'fastep_core.experiments.tuning'])
def test_a_bad_cluster_is_one_line(command: str, args: list[str]) -> None:
    tiny = ['--runs', '1', '--scenarios', 'table2_s3', '--algorithms', 'optimal', '--no-figures', '--out', '/nowhere'] \
        if command == 'msg_tools.bench_cli' else ['--popsize', '1', '--maxiter', '1']
    done = subprocess.run([sys.executable, '-m', command, *tiny, *args], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and 'Traceback' not in done.stderr, done.stderr
    assert done.stdout == ''
