"""PlannerParams refuses bad values with a short message, whatever the value (issue "Hardening", item 3)."""

from __future__ import annotations

from typing import Any

import pytest

from fastep_core.errors import ParameterError
from fastep_core.planning.params import PlannerParams


def _alias_bomb() -> list[Any]:
    """What a YAML alias bomb loads as: 10^31 items sharing a few lists (its repr never ends)."""
    value: list[Any] = [1] * 10
    for _ in range(30):
        value = [value] * 10
    return value


@pytest.mark.parametrize('overrides,message', [
    ({'gamma': _alias_bomb()}, 'gamma must be a finite number, got [[...], [...], [...], ...]'),
    ({'n_fireflies': 10 ** 5000}, 'n_fireflies must be a finite number, got an integer of 16610 bits'),
    ({'gamma': 'x' * 10_000}, "gamma must be a finite number, got 'xxxxxxxxxxxxxxxxx...xxxxxxxxxxxxxxxxxx'"),
    ({'gamma': float('nan')}, 'gamma must be a finite number, got nan'),
    ({'gamma': True}, 'gamma must be a finite number, got True'),
    ({'n_fireflies': 2.5}, 'n_fireflies must be an integer, got 2.5'),
    ({'n_fireflies': 1}, 'n_fireflies=1 is outside [2, 10000]'),
])
def test_a_bad_value_is_one_short_line(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(ParameterError) as caught:
        PlannerParams().with_overrides(overrides)
    assert str(caught.value) == f'planner parameter {message}'


def test_good_values_are_taken() -> None:
    params = PlannerParams().with_overrides({'gamma': 2, 'n_fireflies': 20})
    assert (params.gamma, params.n_fireflies) == (2, 20)
