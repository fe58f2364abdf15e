"""fastep-sim as users run it: exit codes, one-line errors, the JSON contract, the figure."""

import json
import queue
import signal
import subprocess
import sys
import threading

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


def test_dwa_runs_a_point_mass_and_refuses_a_tractor_trailer_in_one_line(tmp_path):
    out = tmp_path / 'd.json'
    assert main(['table2_s3', '--algorithm', 'dwa', '--json', str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc['algorithm'] == 'dwa' and doc['runs'][0]['robots'][0]['reached'] is True
    proc = run_cli('application', '--algorithm', 'dwa')
    assert proc.returncode == 2 and proc.stdout == ''
    assert proc.stderr == ('fastep-sim: error: dwa drives point_mass and diff_drive robots only; robot r1 is a '
                           'tractor_trailer (choose fastep, fastep_paper, aco, optimal, fastep_route)\n')


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


# ----------------------------------------------------------------------------------------------- issue "Hardening"

@pytest.mark.parametrize('name', ['p.xyz', 'out', 'fig.png.bak'])
def test_a_figure_file_of_no_known_format_is_refused_before_any_run(tmp_path, name):
    """--plot p.xyz tracebacked after the runs; --plot out said 'wrote out' when it wrote out.png (item 19)."""
    proc = run_cli('table2_s3', '--plot', str(tmp_path / name))
    assert proc.returncode == 2 and proc.stdout == '', proc.stdout
    assert proc.stderr.startswith('fastep-sim: error: argument --plot: the figure file must end in .png, .pdf, '
                                  '.svg') and len(proc.stderr.splitlines()) == 1, proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_plot_as_svg(tmp_path):
    out = tmp_path / 'fig.svg'
    assert main(['table2_s3', '--plot', str(out)]) == 0
    assert out.read_bytes().startswith(b'<?xml')


QUICK = ('workspace: [0, 0, 10, 10]\n'
         'robots:\n  - {name: r1, model: point_mass, start: [5, 5], goal: [5.5, 5], radius: 0.5}\n')


def test_json_is_streamed_as_runs_finish_and_is_the_same_document(tmp_path):
    scenario, out = tmp_path / 'quick.yaml', tmp_path / 'r.json'
    scenario.write_text(QUICK)
    assert main([str(scenario), '--runs', '3', '--seed', '5', '--json', str(out)]) == 0
    text = out.read_text()
    doc = json.loads(text)
    assert json.dumps(doc) + '\n' == text   # byte for byte what json.dumps of the whole document gave
    assert list(doc) == ['scenario', 'algorithm', 'runs'] and [r['seed'] for r in doc['runs']] == [5, 6, 7]


def test_memory_does_not_grow_with_the_number_of_runs(tmp_path, monkeypatch):
    """All runs (~2.4 MB each) were held until the end: a million runs exhausted memory first (item 21)."""
    import gc
    import weakref

    from msg_tools import sim_cli

    scenario = tmp_path / 'quick.yaml'
    scenario.write_text(QUICK)
    finished, most_alive = [], []

    def simulate(*args, **kwargs):
        gc.collect()
        most_alive.append(sum(ref() is not None for ref in finished))
        run = real_simulate(*args, **kwargs)
        finished.append(weakref.ref(run))
        return run

    real_simulate = sim_cli.simulate
    monkeypatch.setattr(sim_cli, 'simulate', simulate)
    assert main([str(scenario), '--runs', '12', '--json', str(tmp_path / 'r.json'),
                 '--plot', str(tmp_path / 'f.png')]) == 0
    assert max(most_alive) == 0, most_alive   # none: each run is written out as it ends


@pytest.mark.parametrize('signum, code, said', [(signal.SIGINT, 130, 'interrupted'),
                                                (signal.SIGTERM, 143, 'stopped by SIGTERM')])
def test_ctrl_c_keeps_every_finished_run(tmp_path, signum, code, said):
    """Ctrl-C during --runs N lost every finished run: the JSON was written only at the end (item 21)."""
    scenario, out, figure = tmp_path / 'quick.yaml', tmp_path / 'r.json', tmp_path / 'f.png'
    scenario.write_text(QUICK)
    proc = subprocess.Popen([sys.executable, '-m', 'msg_tools.sim_cli', str(scenario), '--runs', '100000',
                             '--json', str(out), '--plot', str(figure)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    lines: queue.Queue[str] = queue.Queue()
    reader = threading.Thread(target=lambda: [lines.put(line) for line in iter(proc.stdout.readline, '')],
                              daemon=True)
    reader.start()
    try:   # the 120 s are a safety net (the old code printed nothing before the end), not a speed target
        printed = []
        while sum(line.startswith('seed ') for line in printed) < 3:   # three runs finished
            printed.append(lines.get(timeout=120))
        proc.send_signal(signum)
        proc.wait(timeout=120)
        reader.join(timeout=120)
        err = proc.stderr.read()
    finally:
        proc.kill()
    rest = ''.join(lines.get() for _ in range(lines.qsize()))
    assert proc.returncode == code, err
    assert err.startswith(f'fastep-sim: {said} after ') and len(err.splitlines()) == 1, err
    runs = json.loads(out.read_text())['runs']
    summaries = [line for line in printed + rest.splitlines() if line.startswith('seed ')]
    assert len(runs) >= len(summaries) >= 3 and [r['seed'] for r in runs] == list(range(len(runs)))
    assert printed[1] == f'wrote {figure}\n' and figure.read_bytes()[:4] == b'\x89PNG'   # once the first run ended
    assert rest.splitlines()[-1] == f'wrote {out}'


def test_ctrl_c_that_lands_in_a_destructor_still_stops_the_batch(tmp_path, monkeypatch, capsys):
    """Python's Ctrl-C raised KeyboardInterrupt wherever the main thread was; inside a destructor Python prints
    "Exception ignored" and runs on, so a batch of a million runs once ignored Ctrl-C (a make test under load)."""
    from msg_tools import sim_cli

    class SignalsWhenCollected:
        def __del__(self) -> None:
            signal.raise_signal(signal.SIGINT)   # its handler runs here, inside the destructor

    real = sim_cli.simulate

    def simulate_then_ctrl_c(*args, **kwargs):
        run = real(*args, **kwargs)
        if args[2] == 2:   # the third run
            SignalsWhenCollected()   # collected at once
        return run

    monkeypatch.setattr(sim_cli, 'simulate', simulate_then_ctrl_c)
    scenario, out = tmp_path / 'quick.yaml', tmp_path / 'r.json'
    scenario.write_text(QUICK)
    assert main([str(scenario), '--runs', '200', '--json', str(out)]) == 130
    assert [r['seed'] for r in json.loads(out.read_text())['runs']] == [0, 1, 2]
    assert capsys.readouterr().err == 'fastep-sim: interrupted after 3 of 200 runs; what finished is written\n'
