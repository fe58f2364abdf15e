"""fastep-bench as users run it: the table and figures it writes, one-line errors with exit 2."""

import json
import subprocess
import sys

import pytest

from fastep_core.experiments.families import rows_of, run_families
from fastep_core.experiments.random_worlds import FAMILIES, FAMILY_SEED0
from msg_tools.bench_cli import main as bench_main


def test_fastep_bench_writes_the_table_and_figures(tmp_path, capsys):
    assert bench_main(['--runs', '2', '--scenarios', 'table2_s3', '--workers', '1', '--out', str(tmp_path)]) == 0
    text = (tmp_path / 'table2.md').read_text()
    assert 'FAStep-Kinematic against ACO-Kinematic' in text and 'Optimal-Kinematic' in text
    for figure in ('path_length', 'compute_time', 'paths'):
        assert (tmp_path / 'figures' / f'table2_{figure}.png').stat().st_size > 1000


@pytest.mark.parametrize('args', [['--runs', '0'], ['--algorithms', 'nope'], ['--scenarios', 'no_such_scenario'],
                                  ['--report', 'a/b'], ['--bogus'], ['--families', 'nope'], ['--worlds', '3'],
                                  ['--families', '--worlds', '0'], ['--families', 'u_trap', '--scenarios', 'table2_s1'],
                                  ['--planner-set', 'no_such_parameter=1'], ['--planner-set', 'stuck_steps'],
                                  ['--planner-set', 'max_speed=-1'], ['--families', '--planner-set', 'stuck_steps=x'],
                                  ['--worst-of', 'aco'], ['--families', '--algorithms', 'fastep', '--worst-of', 'aco'],
                                  # counts no run could finish: they only filled the memory (issue 32)
                                  ['--runs', '3000000'], ['--runs', '99999999999999999999'],
                                  ['--families', '--worlds', '99999999999'], ['--workers', '100000']])
def test_bad_input_exits_2_with_one_line(args):
    done = subprocess.run([sys.executable, '-m', 'msg_tools.bench_cli', *args], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and 'Traceback' not in done.stderr
    assert done.stdout == ''


def test_families_on_one_world_each_write_a_table_json_and_figures_that_agree(tmp_path, capsys):
    # The exact-path planner only: it draws no random numbers and is the cheapest to run.
    assert bench_main(['--families', '--worlds', '1', '--algorithms', 'optimal', '--workers', '1',
                       '--worst-of', 'optimal', '--out', str(tmp_path)]) == 0
    text = (tmp_path / 'families.md').read_text()
    assert text in capsys.readouterr().out
    result = json.loads((tmp_path / 'families.json').read_text())
    assert result['families'] == list(FAMILIES) and result['worlds'] == 1
    rows, summary = result['rows'], result['summary']
    assert {r['family'] for r in rows} == set(FAMILIES) and {r['world'] for r in rows} == {FAMILY_SEED0}
    assert [s['family'] for s in summary] == list(FAMILIES)
    for s in summary:
        mine = [r for r in rows if r['family'] == s['family']]
        assert s['robot_runs'] == len(mine) and s['runs'] == 1 and s['worlds'] == 1
        assert s['arrived'] == sum(r['reached'] and not r['collided'] for r in mine)
        ratios = [r['path_opt'] for r in mine if r['path_opt'] is not None]
        assert s['path_opt_worst'] == pytest.approx(max(ratios))
        for r in mine:
            assert r['path_opt'] is None or r['path_opt'] == pytest.approx(r['path_length'] / r['optimum'])
        assert f"| {s['arrived']}/{s['robot_runs']} | {s['collided']} | {s['path_opt_mean']:.3f} |" in text
    assert len([r for r in rows if r['family'] == 'multi_robot']) >= 2
    assert '### Worst path / optimum per family (Optimal-Kinematic)' in text
    for figure in ('path_opt', 'cpu', 'worst'):
        assert (tmp_path / 'figures' / f'families_{figure}.png').stat().st_size > 1000


def test_family_results_do_not_depend_on_the_number_of_workers():
    def measured(workers):
        rows = rows_of(run_families(['u_trap', 'tractor_trailer'], ['optimal'], 2, workers=workers))
        return [(r.family, r.world, r.robot, r.reached, r.collided, r.path_length, r.optimum, r.activations)
                for r in rows]
    assert measured(1) == measured(2)
