"""Values of loaded YAML, checked: each a function returning the value in its Python type, or raising Invalid
with a one-line message naming the key path (`robots[1].radius must be > 0, got -1`).

Scenario files (scenario.py) read every value through these. Offending values are shown short (`show`): never the
repr of a whole value, since a "billion laughs" list has a repr that takes hours.
"""

from __future__ import annotations

import math
import re
from typing import Any, Mapping, Sequence

from fastep_core import bounded_yaml

__all__ = ['Invalid', 'as_list', 'boolean', 'finite', 'integer', 'key_path', 'keys', 'mapping', 'non_negative',
           'number', 'numbers', 'one_line', 'point', 'positive', 'show', 'text', 'text_number_hint']

# Numbers PyYAML (YAML 1.1) leaves as text: an exponent without a dot in the mantissa or a sign ('1e-3', '5.0e1').
TEXT_EXPONENT = re.compile(r'([-+]?)([0-9]+\.?[0-9]*|\.[0-9]+)[eE]([-+]?)([0-9]+)')
SHOW_DEPTH = 8   # `show` renders a value at most this deep (and cuts it at its length limit), whatever its size


class Invalid(Exception):
    """A value that is not what its key needs; scenario.py turns it into a ScenarioError naming the file."""


def one_line(text: str) -> str:
    return ' '.join(text.split())


def show(value: Any, limit: int = 60) -> str:
    """A short, single-line rendering of an offending value: its repr, cut at ``limit`` characters.

    Never the repr of the whole value: a "billion laughs" list (10^9 items sharing a few lists) has a repr
    that takes hours and more memory than the machine has; this walks only as far as the limit.
    """
    text = 'null' if value is None else one_line(_bounded_repr(value, limit + 1))
    return text if len(text) <= limit else text[:limit - 3] + '...'


def _bounded_repr(value: Any, budget: int) -> str:
    """repr(value) up to about ``budget`` characters (as repr writes it, for the values YAML gives)."""
    parts: list[str] = []
    used = 0

    def emit(text: str) -> None:
        nonlocal used
        parts.append(text)
        used += len(text)

    def items(opening: str, entries: Any, closing: str, depth: int, pairs: bool = False) -> None:
        emit(opening)
        for i, entry in enumerate(entries):
            if used > budget:
                return
            if i:
                emit(', ')
            if pairs:
                walk(entry[0], depth + 1)
                emit(': ')
                walk(entry[1], depth + 1)
            else:
                walk(entry, depth + 1)
        emit(closing)

    def walk(item: Any, depth: int) -> None:
        if used > budget:
            return
        if depth > SHOW_DEPTH:
            emit('...')
        elif isinstance(item, dict):
            items('{', item.items(), '}', depth, pairs=True)
        elif isinstance(item, list):
            items('[', item, ']', depth)
        elif isinstance(item, tuple):
            items('(', item, ',)' if len(item) == 1 else ')', depth)
        elif isinstance(item, (set, frozenset)) and item:
            items('{', item, '}', depth)
        elif isinstance(item, (str, bytes)):
            emit(repr(item[:budget]))
        elif isinstance(item, int) and not isinstance(item, bool) and item.bit_length() > 4 * budget:
            emit(f'an integer of {_digit_count(item)} digits')
        else:
            emit(repr(item))

    walk(value, 0)
    return ''.join(parts)


def _digit_count(value: int) -> str:
    """'400', or 'about 5000' beyond the digits Python converts (repr raises ValueError there)."""
    try:
        return str(len(str(abs(value))))
    except ValueError:
        return f'about {int(value.bit_length() * math.log10(2)) + 1}'


def key_path(path: str, key: str) -> str:
    return f'{path}.{key}' if path else key


def mapping(value: Any, path: str) -> Mapping[str, Any]:
    if not isinstance(value, dict):
        raise Invalid(f'{path} must be a mapping, got {show(value)}')
    for key in value:
        if not isinstance(key, str):
            raise Invalid(f'{path}: keys must be strings, got {show(key)}')
    return value


def keys(data: Mapping[str, Any], path: str, allowed: Sequence[str], required: Sequence[str]) -> None:
    for key in data:
        if key not in allowed:
            raise Invalid(f'{path}: unknown key {show(key)} (allowed: {", ".join(allowed)})')
    for key in required:
        if key not in data:
            raise Invalid(f'{path}: missing required key {key!r}')


def as_list(value: Any, path: str) -> list[Any]:
    if not isinstance(value, list):
        raise Invalid(f'{path} must be a list, got {show(value)}')
    return value


def finite(value: Any) -> float | None:
    """value as a float if it is a real, finite number (not a bool, a string, null, .nan or .inf), else None."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            number = float(value)
        except OverflowError:   # an integer beyond 1.8e308
            return None
        if math.isfinite(number):
            return number
    return None


def number(value: Any, path: str) -> float:
    """A real, finite number (bool, strings, null, .nan and .inf are rejected)."""
    number = finite(value)
    if isinstance(value, bounded_yaml.MisreadNumber):
        raise Invalid(f'{path} is {show(str(value)).strip(chr(39))}, which YAML 1.1 reads as {value.reading}: '
                      f'{value.fix}')
    if number is None:
        raise Invalid(f'{path} must be a finite number, got {show(value)}{text_number_hint(value)}')
    return number


def text_number_hint(value: Any) -> str:
    """Why a number-looking string is text: YAML 1.1 wants 1.0e-3 (a dot and a signed exponent), or quotes;
    045 and 50:00 mean 37 and 3000 in YAML 1.1, and 08 is text (bounded_yaml.MisreadNumber)."""
    if isinstance(value, bounded_yaml.MisreadNumber):
        return f' ({value.advice})'   # number has its own message for these; other callers use the hint
    if not isinstance(value, str) or len(value) > 100:
        return ''
    match = TEXT_EXPONENT.fullmatch(value.strip())
    if match:
        sign, mantissa, exp_sign, digits = match.groups()
        fixed = f'{sign}{mantissa if "." in mantissa else mantissa + ".0"}e{exp_sign or "+"}{digits}'
        if fixed.lower() != value.strip().lower():
            return f' (YAML 1.1 reads exponents without a dot and a sign as text: write {fixed})'
    try:
        float(value)
    except ValueError:
        return ''
    return ' (text, not a number: drop the quotes)'


def positive(value: Any, path: str) -> float:
    checked = number(value, path)
    if checked <= 0.0:
        raise Invalid(f'{path} must be > 0, got {show(value)}')
    return checked


def non_negative(value: Any, path: str) -> float:
    checked = number(value, path)
    if checked < 0.0:
        raise Invalid(f'{path} must be >= 0, got {show(value)}')
    return checked


def numbers(value: Any, path: str, count: int, what: str) -> tuple[float, ...]:
    if not isinstance(value, list) or len(value) != count:
        raise Invalid(f'{path} must be a list of {count} numbers {what}, got {show(value)}')
    return tuple(number(v, f'{path}[{i}]') for i, v in enumerate(value))


def point(value: Any, path: str) -> tuple[float, float]:
    x, y = numbers(value, path, 2, '[x, y]')
    return x, y


def text(value: Any, path: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise Invalid(f'{path} must be a non-empty string, got {show(value)}')
    if '\n' in value or '\r' in value:
        raise Invalid(f'{path} must be a single line, got {show(value)}')
    return str(value)   # a plain str, also for a MisreadNumber (name: 045 is the text '045')


def boolean(value: Any, path: str) -> bool:
    """true or false (YAML 1.1's yes/no/on/off load as booleans too); text, numbers and null are refused."""
    if not isinstance(value, bool):
        raise Invalid(f'{path} must be true or false, got {show(value)}')
    return value


def integer(value: Any, path: str, low: int, high: int) -> int:
    if isinstance(value, bounded_yaml.MisreadNumber) or (isinstance(value, str) and text_number_hint(value)):
        number(value, path)   # a misread or quoted number: its own message
    if isinstance(value, bool) or not isinstance(value, int):
        raise Invalid(f'{path} must be a whole number in [{low}, {high}], got {show(value)}')
    if not low <= value <= high:
        raise Invalid(f'{path} must be in [{low}, {high}], got {show(value)}')
    return int(value)
