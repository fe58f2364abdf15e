"""Dense clutter: random worlds shaped like a robot test course (the BARN benchmark's), for a Jackal-class base.

A field of 0.15 m cells, each filled or not with a 0.075 m-radius cylinder: filled at random, then grown by a
cellular automaton (a cell is filled when at least BIRTH of its 8 neighbours are, stays filled with at least
SURVIVE) into walls and pockets; a corridor CORRIDOR cells wide is then cut through it along a random walk from the
start's side to the goal's, so a way a few robot widths wide exists. The robot (a differential-drive base of
radius 0.22 m, up to 2 m/s, a 270-degree 720-beam laser) starts in a box closed on three sides below the field and
its goal lies 10 m ahead, beyond it. Three families: `dense_clutter` (the cylinders on the map),
`dense_clutter_laser` (only in the laser: known: false) and `dense_clutter_jackal` (dense_clutter_laser's worlds,
seed for seed, with the robot declared as what BARN drives: a Jackal's 0.508 m x 0.430 m box, JACKAL_FOOTPRINT,
its radius the box's circumscribed 0.333 m). Same seed, same world; solvable from the truth for the 0.22 m circle
(every world is checked with exact_path.solvable, and drawn again, from the next draws of the same Generator, if
not); the Jackal's worlds are not checked again for its larger circle, so they stay dense_clutter_laser's.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import convolve

from fastep_core.planning.shortest_path.exact_path import solvable
from fastep_core.scenario import parse_scenario

__all__ = ['CELL', 'DENSE_FAMILIES', 'JACKAL_FOOTPRINT', 'MAX_SPEED', 'ROBOT_RADIUS', 'dense_clutter_data']

DENSE_FAMILIES: tuple[str, ...] = ('dense_clutter', 'dense_clutter_laser', 'dense_clutter_jackal')
CELL = 0.15             # m: a cell of the field, and a cylinder's diameter
COLUMNS, ROWS = 30, 30  # the field: 4.5 m across, 4.5 m deep
FIELD_Y = 2.0           # m: where the field begins, beyond the start box
AHEAD = 10.0            # m from the start to the goal
ROBOT_RADIUS = 0.22     # a Jackal-class base
JACKAL_FOOTPRINT = ((0.254, 0.215), (-0.254, 0.215), (-0.254, -0.215), (0.254, -0.215))   # m, base_link centred
MAX_SPEED = 2.0
SENSOR: dict[str, Any] = {'range': 10.0, 'fov': round(1.5 * math.pi, 9), 'beams': 720, 'noise': 0.01}
FILL = (0.40, 0.55)     # share of cells filled at first, drawn per world
STEPS = (1, 3)          # cellular automaton steps, drawn per world
BIRTH, SURVIVE = 5, 4
CORRIDOR = 7            # cells: the corridor cut through the field (1.05 m, more than two robot widths)
_ATTEMPTS = 50
_NEIGHBOURS = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1]])


def _field(rng: np.random.Generator) -> NDArray[np.bool_]:
    """Filled cells (ROWS, COLUMNS), row 0 nearest the start."""
    cells = rng.random((ROWS, COLUMNS)) < rng.uniform(*FILL)
    for _ in range(int(rng.integers(STEPS[0], STEPS[1] + 1))):
        around = convolve(cells.astype(np.int64), _NEIGHBOURS, mode='constant', cval=0)
        cells = np.where(cells, around >= SURVIVE, around >= BIRTH)
    # The corridor: a random walk of its centre column from the first row to the last.
    centre = int(rng.integers(CORRIDOR // 2, COLUMNS - CORRIDOR // 2))
    steps = rng.integers(-1, 2, ROWS)
    for row in range(ROWS):
        centre = int(np.clip(centre + steps[row], CORRIDOR // 2, COLUMNS - 1 - CORRIDOR // 2))
        cells[row, centre - CORRIDOR // 2:centre + CORRIDOR // 2 + 1] = False
    return cells


def dense_clutter_data(seed: int, on_map: bool = True, footprint: bool = False) -> dict[str, Any]:
    """The scenario mapping of dense-clutter world `seed` (the cylinders on the map, or only in the laser), the
    robot a 0.22 m circle or (footprint) the Jackal's box: the same world either way."""
    rng = np.random.default_rng(70_000 + seed)
    width = COLUMNS * CELL
    start = [round(width / 2.0, 3), 1.0, round(np.pi / 2.0, 6)]
    goal = [round(width / 2.0, 3), round(1.0 + AHEAD, 3)]
    height = goal[1] + 1.5
    box = [{'segment': {'start': [0.0, 0.0], 'end': [width, 0.0]}},              # behind the start
           {'segment': {'start': [0.0, 0.0], 'end': [0.0, height]}},            # the two sides
           {'segment': {'start': [width, 0.0], 'end': [width, height]}}]
    for _ in range(_ATTEMPTS):
        cells = _field(rng)
        rows, columns = np.nonzero(cells)
        centres = np.column_stack([(columns + 0.5) * CELL, FIELD_Y + (rows + 0.5) * CELL])
        cylinders = [{'circle': {'center': [round(float(x), 3), round(float(y), 3)], 'radius': CELL / 2.0},
                      **({} if on_map else {'known': False})} for x, y in centres]
        data: dict[str, Any] = {
            'workspace': [0.0, 0.0, round(width, 3), round(height, 3)], 'obstacles': [*box, *cylinders],
            'robots': [{'name': 'r1', 'model': 'diff_drive', 'start': start, 'goal': goal, 'radius': ROBOT_RADIUS,
                        'sensor': dict(SENSOR)}],
            'planner': {'max_speed': MAX_SPEED}}
        if solvable(parse_scenario(data)):   # its world is the truth, known or not
            if footprint:
                robot = data['robots'][0]
                del robot['radius']
                robot['footprint'] = [list(v) for v in JACKAL_FOOTPRINT]
            return data
    raise RuntimeError(f'no solvable dense-clutter world in {_ATTEMPTS} draws for seed {seed}')
