"""Batch experiments, their statistics, tuning and the fastep-tune command line (small and fast)."""

import math
import subprocess
import sys

import numpy as np
import pytest

from fastep_core.errors import ParameterError
from fastep_core.experiments import batches, tuning
from fastep_core.experiments.batches import Record


def record(algorithm, seed, path, compute, scenario='s', ok=True, robot='r1'):
    return Record(scenario, algorithm, seed, robot, ok, False, path, 100.0 + path if ok else None, compute, 0.3,
                  1, 'arrived' if ok else 'failed', compute)


def synthetic(n=20, seed=0):
    rng = np.random.default_rng(seed)
    return ([record('fastep', k, 50.0 + rng.normal(0, 0.1), 0.1 + rng.uniform(0, 0.01)) for k in range(n)] +
            [record('aco', k, 52.0 + rng.normal(0, 0.1), 0.3 + rng.uniform(0, 0.01)) for k in range(n)])


def test_enhancement_is_the_papers_formula():
    # Table 2, scenario 2: path 65.75 -> 59.69 is 9.22 %, time 283.25 -> 154.04 is 45.62 %.
    assert batches.enhancement(65.75, 59.69) == pytest.approx(9.22, abs=0.005)
    assert batches.enhancement(283.25, 154.04) == pytest.approx(45.62, abs=0.005)


def test_summary_statistics_on_synthetic_records():
    records = [record('fastep', k, p, 0.1) for k, p in enumerate([50.0, 52.0, 54.0])]
    records.append(record('fastep', 3, 999.0, 0.5, ok=False))       # a failed run: no path or time, but compute
    (s,) = batches.summarise(records)
    assert (s.runs, s.arrived, s.collided) == (4, 3, 0)
    assert s.mean['path_length'] == pytest.approx(52.0)
    assert s.std['path_length'] == pytest.approx(2.0)                 # sample std, ddof = 1
    assert s.mean['sim_time'] == pytest.approx(152.0)
    assert s.mean['compute_time'] == pytest.approx(0.2)


def test_compare_finds_a_clear_difference_and_none_between_equals():
    records = synthetic()
    c = batches.compare(records, 's', 'path_length')
    assert c.a_better and c.p_value < 1e-6
    assert c.enhancement == pytest.approx((52.0 - 50.0) / 52.0 * 100, abs=0.2)
    same = [record('fastep', k, 50.0, 0.1) for k in range(5)] + [record('aco', k, 50.0, 0.1) for k in range(5)]
    c = batches.compare(same, 's', 'path_length')
    assert c.p_value == 1.0 and not c.a_better
    assert math.isnan(batches.compare(records, 'other', 'path_length').p_value)


def test_markdown_report_has_the_papers_numbers_and_ours():
    records = [Record('table2_s3', r.algorithm, r.seed, 'r1', True, False, r.path_length, r.sim_time,
                      r.compute_time, 0.3, 1, '', r.compute_time) for r in synthetic(5)]
    text = batches.markdown_report(records, {'table2_s3': {'r1': 45.51}})
    assert '45.73' in text and '48.54' in text and '5.79 %' in text       # the paper's row for scenario 3
    assert '| table2_s3 | r1 | FAStep-Kinematic | 5/5 |' in text
    assert f'{50.0 / 45.51:.3f}'[:4] in text                              # the optimality ratio


def test_markdown_report_puts_every_planner_against_each_baseline():
    rng = np.random.default_rng(1)
    records = [Record('table2_s3', r.algorithm, r.seed, 'r1', True, False, r.path_length, r.sim_time,
                      r.compute_time, 0.3, 1, '', r.compute_time)
               for r in synthetic(8) + [record('dwa', k, 51.0 + rng.normal(0, 0.1), 0.2) for k in range(8)]]
    text = batches.markdown_report(records, {'table2_s3': {'r1': 45.51}})
    table = text.split('### Every planner against the baselines')[1].split('###')[0]
    assert '| planner | path (m) | vs ACO-Kinematic: enh. | p | vs DWA: enh. | p |' in table
    fastep = next(line for line in table.splitlines() if line.startswith('| table2_s3 | FAStep-Kinematic |'))
    cells = [c.strip() for c in fastep.strip('|').split('|')]
    assert float(cells[3].rstrip(' %')) == pytest.approx((52.0 - 50.0) / 52.0 * 100, abs=0.5)   # vs ACO
    assert float(cells[5].rstrip(' %')) == pytest.approx((51.0 - 50.0) / 51.0 * 100, abs=0.5)   # vs DWA
    assert '| table2_s3 | ACO-Kinematic | 5' in table and '| - | - |' in table   # no comparison with itself


def test_run_batch_shows_its_progress_on_stderr_when_asked(capsys):
    records = batches.run_batch(['table2_s3'], ['optimal'], 1, workers=1, progress=True, label='bench')
    captured = capsys.readouterr()
    assert len(records) == 1 and captured.out == ''
    assert 'bench' in captured.err and '1/1' in captured.err


def test_run_batch_refuses_zero_runs():
    with pytest.raises(ParameterError, match='runs must be >= 1'):
        batches.run_batch(['table2_s3'], ['fastep'], 0)


def test_run_batch_is_reproducible_and_independent_of_workers():
    serial = batches.run_batch(['table2_s3'], ['fastep', 'optimal'], 2, workers=1)
    pooled = batches.run_batch(['table2_s3'], ['fastep', 'optimal'], 2, workers=2)
    assert [(r.algorithm, r.seed) for r in serial] == [('fastep', 0), ('fastep', 1), ('optimal', 0)]
    assert [(r.path_length, r.reached) for r in serial] == [(r.path_length, r.reached) for r in pooled]
    assert all(r.ok for r in serial)


@pytest.mark.parametrize('args', [['--popsize', '0'], ['--maxiter', '-1'],
                                  ['--seeds', '99999999999999999999'], ['--popsize', '99999999999'],
                                  ['--maxiter', '100000'], ['--test-seeds', '1000001'],
                                  ['--train', 'table2_s1', '--test', 'table2_s1'],
                                  ['--test', 'no_such_scenario'], ['--bogus']])
def test_fastep_tune_bad_input_exits_2_with_one_line(args):
    done = subprocess.run([sys.executable, '-m', 'fastep_core.experiments.tuning', *args], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and 'Traceback' not in done.stderr
    assert done.stdout == ''


def test_tuning_decodes_the_paper_ranges():
    assert tuning.decode([0.18, 0.18, -2.0, 2.0]) == pytest.approx({'a': 0.18, 'b': 0.18, 'c': 0.01,
                                                                    'step_radius': 2.0})
    low, high = np.array(list(tuning.PARAMETERS.values())).T
    assert tuning.decode(low)['c'] == pytest.approx(1e-5) and tuning.decode(high)['c'] == pytest.approx(0.01)


def test_tuning_penalises_failures():
    ok = [record('fastep', 0, 50.0, 0.1)]
    failed = ok + [record('fastep', 1, 10.0, 0.1, ok=False)]
    assert tuning.run_cost(ok) == 50.0
    assert tuning.run_cost(failed) == pytest.approx((50.0 + 10.0 + tuning.PENALTY) / 2)


def test_a_tiny_search_is_seeded_and_never_worse_than_table_1():
    kwargs = dict(train=('table2_s3',), seeds=(0,), popsize=1, maxiter=1, workers=1, seed=3)
    first, again = tuning.tune(**kwargs), tuning.tune(**kwargs)
    assert first.params == again.params and first.cost == again.cost
    assert first.cost <= first.table1_cost
    assert set(first.params) == {'a', 'b', 'c', 'step_radius'}
    assert 0.1 <= first.params['a'] <= 1.0 and 1e-5 <= first.params['c'] <= 0.01


def test_the_tasks_of_a_batch_are_made_when_asked_for() -> None:
    """Issue "Faults", item 6: `--runs 3000000` built every task first (1.8 GB in 60 s, no result). Tasks is the
    same list, made one task at a time."""
    from fastep_core.experiments.batches import Tasks
    every = Tasks(['table2_s1', 'application'], ['fastep', 'optimal', 'aco'], 100_000, seed0=5)
    assert len(every) == 2 * (100_000 + 1 + 100_000)
    assert every[0] == ('table2_s1', 'fastep', 5) and every[99_999] == ('table2_s1', 'fastep', 100_004)
    assert every[100_000] == ('table2_s1', 'optimal', 5) and every[100_001] == ('table2_s1', 'aco', 5)
    assert every[-1] == ('application', 'aco', 100_004)
    small = Tasks(['table2_s1', 'application'], ['fastep', 'optimal'], 3, seed0=1)
    assert list(small) == batches.tasks(['table2_s1', 'application'], ['fastep', 'optimal'], 3, seed0=1) == [
        (s, a, seed) for s in ('table2_s1', 'application') for a, seeds in (('fastep', (1, 2, 3)), ('optimal', (1,)))
        for seed in seeds]
    with pytest.raises(IndexError):
        every[len(every)]
