"""fastep_core.cli, what every command line shares: one-line errors with exit 2, the main() guard, types."""

from __future__ import annotations

import argparse
import subprocess
import sys

import pytest

from fastep_core.cli import INTERRUPTED, Parser, guard, positive_int, progress_bar, seed
from fastep_core.errors import FastepError, ScenarioError


def parser() -> Parser:
    p = Parser(prog='tool')
    p.add_argument('--seed', type=seed, default=0)
    p.add_argument('--runs', type=positive_int, default=1)
    return p


@pytest.mark.parametrize('argv, words', [
    (['--bogus'], 'unrecognized arguments: --bogus'),
    (['--seed', '-1'], 'a seed must be >= 0, got -1'),
    (['--seed', 'x'], "invalid seed value: 'x'"),
    (['--runs', '0'], 'must be at least 1, got 0'),
    (['--runs', '2.5'], "invalid positive_int value: '2.5'"),
])
def test_bad_flags_are_one_line_and_exit_2(capsys: pytest.CaptureFixture[str], argv: list[str],
                                           words: str) -> None:
    with pytest.raises(SystemExit) as stop:
        parser().parse_args(argv)
    assert stop.value.code == 2
    captured = capsys.readouterr()
    assert captured.out == '' and captured.err.startswith('tool: error: ') and words in captured.err
    assert len(captured.err.splitlines()) == 1


def test_good_flags_parse() -> None:
    assert vars(parser().parse_args(['--seed', '0', '--runs', '3'])) == {'seed': 0, 'runs': 3}


def test_guard_turns_a_fastep_error_into_one_line_and_2(capsys: pytest.CaptureFixture[str]) -> None:
    def body() -> int:
        raise ScenarioError("scenario 'x': robots[0].radius must be > 0, got -1")
    assert guard('tool', body) == 2
    assert capsys.readouterr().err == "tool: error: scenario 'x': robots[0].radius must be > 0, got -1\n"


def test_guard_turns_ctrl_c_into_one_line_and_130(capsys: pytest.CaptureFixture[str]) -> None:
    def body() -> int:
        raise KeyboardInterrupt
    assert guard('tool', body) == INTERRUPTED == 130
    assert capsys.readouterr().err == 'tool: interrupted\n'


def test_guard_passes_the_exit_code_and_other_errors_through() -> None:
    assert guard('tool', lambda: 7) == 7

    def bug() -> int:
        raise ZeroDivisionError('a bug is not a user error: its traceback must show')
    with pytest.raises(ZeroDivisionError):
        guard('tool', bug)


def test_guard_ends_quietly_when_the_reader_of_stdout_goes_away() -> None:
    # A real closed pipe: the child prints until the write fails; no traceback, no "Exception ignored" at exit.
    script = ('import sys\nfrom fastep_core.cli import guard\n'
              'def body():\n    while True:\n        print("line " * 100)\n'
              'sys.exit(guard("tool", body))\n')
    child = subprocess.Popen([sys.executable, '-c', script], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert child.stdout is not None and child.stderr is not None
    child.stdout.read(10)
    child.stdout.close()
    err = child.stderr.read().decode()
    assert child.wait(timeout=60) == 1
    assert err == ''


def test_every_error_the_packages_define_is_a_fastep_error() -> None:
    from fastep_core import errors as core
    from fastep_ros import errors as ros
    from msg_tools import errors as tools
    for module in (core, ros, tools):
        for name in module.__all__:
            assert issubclass(getattr(module, name), FastepError), f'{module.__name__}.{name}'


def test_argparse_types_refuse_what_they_should() -> None:
    assert seed('0') == 0 and positive_int('1') == 1
    with pytest.raises(argparse.ArgumentTypeError):
        seed('-3')
    with pytest.raises(argparse.ArgumentTypeError):
        positive_int('0')


def test_progress_bar_is_off_when_stderr_is_not_a_terminal_unless_asked(capsys: pytest.CaptureFixture[str]) -> None:
    for show in (None, False):   # pytest's captured stderr is not a terminal
        with progress_bar(3, 'batch', show) as bar:
            bar.update(3)
        assert capsys.readouterr() == ('', '')
    with progress_bar(3, 'batch', True) as bar:
        bar.update(3)
    captured = capsys.readouterr()
    assert captured.out == '' and 'batch' in captured.err and '3/3' in captured.err
