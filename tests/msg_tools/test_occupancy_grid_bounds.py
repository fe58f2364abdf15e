"""A /map within bounds (msg_tools.occupancy_grid): its cells copied once and refused beyond MAX_GRID_CELLS, its
walls at most a given number, merged cells beyond that, never less obstacle than the map."""

from __future__ import annotations

import array

import numpy as np
import pytest
from nav_msgs.msg import OccupancyGrid

from msg_tools import convert, occupancy_grid


def grid_message(occupied: np.ndarray, resolution: float = 0.05,
                 origin: tuple[float, float] = (-3.0, 2.0)) -> OccupancyGrid:
    msg = OccupancyGrid()
    msg.info.resolution = resolution
    msg.info.height, msg.info.width = occupied.shape
    msg.info.origin.position.x, msg.info.origin.position.y = origin
    msg.info.origin.orientation.w = 1.0
    msg.data = array.array('b', np.where(occupied, 100, 0).astype(np.int8).tobytes())
    return msg


@pytest.mark.parametrize('seed', range(6))
def test_merged_cells_cover_every_occupied_cell_and_are_the_fewest_that_fit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    height, width = (int(v) for v in rng.integers(20, 120, size=2))
    occupied = rng.random((height, width)) < rng.uniform(0.05, 0.6)
    grid = convert.grid_copy(grid_message(occupied))
    given = convert.grid_walls(grid, 65)
    bound = max(4, len(given.walls) // int(rng.integers(2, 20)))
    walls = convert.grid_walls(grid, 65, bound)
    assert len(walls.walls) <= bound < len(given.walls) and walls.merge > 1 and walls.given_walls == len(given.walls)
    assert len(convert.grid_walls(grid, 65, len(given.walls)).walls) == len(given.walls)   # at the bound: as given
    rows, cols = np.nonzero(occupied)
    centres = np.stack([-3.0 + (cols + 0.5) * 0.05, 2.0 + (rows + 0.5) * 0.05], axis=1)
    assert all(walls.occupied(p) for p in centres)   # never less obstacle than the map
    smaller = walls.merge - 1   # the fewest merged cells that fit: one fewer has more walls than the bound
    if smaller > 1:
        assert sum(len(line) for line, _, _ in occupancy_grid._runs(occupancy_grid._merged(occupied, smaller))) > bound
    xmin, ymin, xmax, ymax = grid.workspace
    ends = np.array([[*w.start, *w.end] for w in walls.walls])
    assert ends[:, [0, 2]].min() >= xmin and ends[:, [0, 2]].max() <= xmax + 1e-9
    assert ends[:, [1, 3]].min() >= ymin and ends[:, [1, 3]].max() <= ymax + 1e-9
    text = walls.coarsened(grid)
    assert text.startswith(f'coarsened: {width} x {height} cells of 0.05 m outline {len(given.walls):,} walls, more '
                           f'than {bound:,}; merged into') and f'{walls.merge} x {walls.merge}' in text, text


def test_without_a_bound_the_walls_are_the_outline_as_before() -> None:
    occupied = np.zeros((5, 6), dtype=bool)
    occupied[1:3, 2:4] = True
    walls = convert.occupancy_grid_obstacles(grid_message(occupied, 1.0, (0.0, 0.0)))
    assert sorted((w.start, w.end) for w in walls) == sorted([
        ((2.0, 1.0), (4.0, 1.0)), ((2.0, 3.0), (4.0, 3.0)), ((2.0, 1.0), (2.0, 3.0)), ((4.0, 1.0), (4.0, 3.0))])


def test_a_grid_over_the_cell_bound_is_refused_before_its_cells_are_copied() -> None:
    msg = OccupancyGrid()
    msg.info.resolution, msg.info.width, msg.info.height = 0.05, 2001, 2000
    msg.info.origin.orientation.w = 1.0
    with pytest.raises(ValueError, match=r'^2001 x 2000 = 4,002,000 cells, more than the 4,000,000 a map may have$'):
        convert.grid_copy(msg)   # no data at all: the size alone refuses it
    msg.info.width = 2000
    msg.data = array.array('b', bytes(10))
    with pytest.raises(ValueError, match=r'map data has 10 cells, width x height is 2000 x 2000 = 4000000'):
        convert.grid_copy(msg)
    copy = convert.grid_copy(grid_message(np.eye(3, dtype=bool)))
    assert copy.cells == 9 and not copy.data.flags.writeable and copy.workspace == (-3.0, 2.0, -2.85, 2.15)
