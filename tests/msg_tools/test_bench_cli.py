"""fastep-bench as users run it: the table and figures it writes, one-line errors with exit 2."""

import subprocess
import sys

import pytest

from msg_tools.bench_cli import main as bench_main


def test_fastep_bench_writes_the_table_and_figures(tmp_path, capsys):
    assert bench_main(['--runs', '2', '--scenarios', 'table2_s3', '--workers', '1', '--out', str(tmp_path)]) == 0
    text = (tmp_path / 'table2.md').read_text()
    assert 'FAStep-Kinematic against ACO-Kinematic' in text and 'Optimal-Kinematic' in text
    for figure in ('path_length', 'compute_time', 'paths'):
        assert (tmp_path / 'figures' / f'table2_{figure}.png').stat().st_size > 1000


@pytest.mark.parametrize('args', [['--runs', '0'], ['--algorithms', 'nope'], ['--scenarios', 'no_such_scenario'],
                                  ['--report', 'a/b'], ['--bogus']])
def test_bad_input_exits_2_with_one_line(args):
    done = subprocess.run([sys.executable, '-m', 'msg_tools.bench_cli', *args], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 2
    assert len(done.stderr.strip().splitlines()) == 1 and 'Traceback' not in done.stderr
    assert done.stdout == ''
