"""fastep-sim as users run it: exit codes, one-line errors, the JSON contract, the figure."""

import json
import subprocess
import sys

import pytest

from fastep_core.scenario import builtin_names
from msg_tools.sim_cli import main


def run_cli(*args):
    return subprocess.run([sys.executable, '-m', 'msg_tools.sim_cli', *args], capture_output=True, text=True,
                          timeout=120)


def test_list_names_every_builtin(capsys):
    assert main(['--list']) == 0
    assert capsys.readouterr().out.split() == builtin_names()


def test_json_has_the_documented_keys(tmp_path):
    out = tmp_path / 'r.json'
    assert main(['table2_s3', '--seed', '3', '--runs', '2', '--json', str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc['scenario'] == 'table2_s3' and doc['algorithm'] == 'fastep'
    assert [r['seed'] for r in doc['runs']] == [3, 4]
    robot = doc['runs'][0]['robots'][0]
    for key in ('name', 'reached', 'collided', 'path_length', 'sim_time', 'compute_time', 'min_clearance',
                'activations', 'trajectory'):
        assert key in robot
    assert robot['reached'] is True and robot['sim_time'] > 0
    assert all(len(row) == 3 for row in robot['trajectory'])


def test_tractor_trailer_trajectory_rows_carry_both_headings(tmp_path):
    out = tmp_path / 'a.json'
    assert main(['application', '--json', str(out)]) == 0
    rows = json.loads(out.read_text())['runs'][0]['robots'][0]['trajectory']
    assert all(len(row) == 5 for row in rows)


def test_plot_writes_a_png(tmp_path):
    out = tmp_path / 'fig.png'
    assert main(['table2_s2', '--algorithm', 'aco', '--plot', str(out)]) == 0
    assert out.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


BAD_FILES = {
    'unknown_key': 'workspace: [0, 0, 50, 50]\nrobots: []\ncolour: red\n',
    'negative_radius': ('workspace: [0, 0, 50, 50]\nobstacles:\n  - circle: {center: [20, 20], radius: -1}\n'
                        'robots:\n  - {name: r1, model: point_mass, start: [5, 5], goal: [45, 45], radius: 0.5}\n'),
    'goal_in_obstacle': ('workspace: [0, 0, 50, 50]\nobstacles:\n  - circle: {center: [45, 45], radius: 2}\n'
                         'robots:\n  - {name: r1, model: point_mass, start: [5, 5], goal: [45, 45], radius: 0.5}\n'),
    'start_outside': ('workspace: [0, 0, 50, 50]\n'
                      'robots:\n  - {name: r1, model: point_mass, start: [-5, 5], goal: [45, 45], radius: 0.5}\n'),
    'nan': ('workspace: [0, 0, 50, 50]\n'
            'robots:\n  - {name: r1, model: point_mass, start: [.nan, 5], goal: [45, 45], radius: 0.5}\n'),
    'duplicate_names': ('workspace: [0, 0, 50, 50]\nrobots:\n'
                        '  - {name: r1, model: point_mass, start: [5, 5], goal: [45, 45], radius: 0.5}\n'
                        '  - {name: r1, model: point_mass, start: [5, 45], goal: [45, 5], radius: 0.5}\n'),
    'unknown_model': ('workspace: [0, 0, 50, 50]\n'
                      'robots:\n  - {name: r1, model: hovercraft, start: [5, 5], goal: [45, 45], radius: 0.5}\n'),
    'syntax_error': 'workspace: [0, 0, 50, 50\nrobots: {\n',
    'python_tag': 'workspace: !!python/object/apply:os.system ["echo hi"]\nrobots: []\n',
}


@pytest.mark.parametrize('case', sorted(BAD_FILES))
def test_bad_scenario_exits_2_with_one_line(tmp_path, case):
    path = tmp_path / f'{case}.yaml'
    path.write_text(BAD_FILES[case])
    proc = run_cli(str(path))
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert 'Traceback' not in proc.stderr and proc.stderr.startswith('fastep-sim: error:')


@pytest.mark.parametrize('args', [['no_such_scenario'], ['table2_s1', '--algorithm', 'pso'],
                                  ['table2_s1', '--runs', '0'], ['table2_s1', '--seed', 'x'],
                                  ['table2_s1', '--seed', '-1'], []])
def test_bad_arguments_exit_2_with_one_line(args):
    proc = run_cli(*args)
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
