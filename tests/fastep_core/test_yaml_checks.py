"""Checked YAML values: the value in its type, or Invalid with a one-line message naming the key path."""

import math

import pytest

from fastep_core import bounded_yaml
from fastep_core import yaml_checks as check


def test_numbers_are_finite_reals_and_the_message_names_the_key_path():
    assert check.number(3, 'a.b') == 3.0 and check.positive(0.5, 'r') == 0.5 and check.non_negative(0, 'n') == 0.0
    for bad in (True, None, 'x', math.nan, math.inf, 10 ** 400):
        with pytest.raises(check.Invalid, match=r'^robots\[1\]\.radius must be a finite number'):
            check.number(bad, 'robots[1].radius')
    with pytest.raises(check.Invalid, match='must be > 0, got -1'):
        check.positive(-1, 'radius')


def test_text_that_looks_like_a_number_says_how_to_write_it():
    with pytest.raises(check.Invalid, match=r'write 1\.0e-3'):
        check.number('1e-3', 'noise')
    with pytest.raises(check.Invalid, match='drop the quotes'):
        check.number('0.5', 'noise')
    misread = bounded_yaml.load('v: 045')['v']
    with pytest.raises(check.Invalid, match='YAML 1.1 reads as'):
        check.number(misread, 'v')


def test_mappings_lists_and_keys():
    assert check.mapping({'a': 1}, 'top') == {'a': 1}
    with pytest.raises(check.Invalid, match='keys must be strings'):
        check.mapping({1: 2}, 'top')
    with pytest.raises(check.Invalid, match=r"unknown key 'c' \(allowed: a, b\)"):
        check.keys({'a': 1, 'c': 2}, 'top', ('a', 'b'), ('a',))
    with pytest.raises(check.Invalid, match="missing required key 'a'"):
        check.keys({'b': 1}, 'top', ('a', 'b'), ('a',))
    with pytest.raises(check.Invalid, match='must be a list'):
        check.as_list({'a': 1}, 'robots')
    assert check.point([1, 2.5], 'p') == (1.0, 2.5)
    with pytest.raises(check.Invalid, match=r'must be a list of 2 numbers \[x, y\]'):
        check.point([1, 2, 3], 'p')


def test_integers_booleans_and_text():
    assert check.integer(720, 'beams', 1, 4096) == 720 and check.boolean(False, 'known') is False
    for bad in (1.5, True, '7'):
        with pytest.raises(check.Invalid, match='beams must be'):
            check.integer(bad, 'beams', 1, 4096)
    with pytest.raises(check.Invalid, match=r'must be in \[1, 4096\], got 0'):
        check.integer(0, 'beams', 1, 4096)
    with pytest.raises(check.Invalid, match='must be true or false'):
        check.boolean('yes please', 'known')
    with pytest.raises(check.Invalid, match='single line'):
        check.text('a\nb', 'name')


def test_show_is_short_whatever_the_value():
    laughs: list = ['lol'] * 10
    for _ in range(9):
        laughs = [laughs] * 10   # 10^10 items sharing lists: a full repr would never end
    shown = check.show(laughs)
    assert len(shown) <= 60 and shown.endswith('...') and '\n' not in shown
    assert check.show(10 ** 5000).startswith('an integer of')
    assert check.show(None) == 'null'
