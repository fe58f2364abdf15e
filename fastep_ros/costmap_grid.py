"""The planner's belief drawn onto a grid of Nav2's costs, for Nav2's `get_costmap` services (costmap_services.py).

fastep keeps no costmap: it believes shapes (circles and wall segments, fastep_core/geometry.py). A grid of them is
drawn on request, each cell by the clearance of its centre (Obstacles.clearance), with Nav2's cost values:

- LETHAL (254): an obstacle reaches within half a cell of the cell's centre (its inside, and the cells a wall,
  which has no thickness, passes through);
- INSCRIBED (253): otherwise, the centre nearer an obstacle than the robot's radius (where a robot's centre
  collides: a goal there is refused as occupied);
- FREE (0): the rest. No inflation decay: fastep plans with exact clearances, not with a cost that falls off
  beyond the inscribed radius, so there are no costs between 1 and 252;
- NO_INFORMATION (255): cells whose centre is outside the workspace (a local window past the map's edge).

Cells are row-major from the origin (the lower-left corner of cell (0, 0), as Nav2's Costmap2D getOriginX/Y):
cell (x, y) is `costs[y, x]`, index `y * size_x + x` of the flattened grid, as nav2_msgs/Costmap's data. Pure
numpy: no rclpy here.

Cost: the grid is cut into TILE x TILE tiles; each tile's cells are measured against the obstacles whose bounding
box comes within reach of the tile (the radius, or half a cell), at most CLEARANCE_PAIRS cell-obstacle distances
at a time; a tile no obstacle reaches is free without a distance computed. So the work is about the cells near
obstacles times the obstacles near them, not every cell times every obstacle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.geometry import Obstacles

__all__ = ['CLEARANCE_PAIRS', 'DEFAULT_RESOLUTION', 'FREE', 'INSCRIBED', 'LETHAL', 'LOCAL_SIZE', 'MAX_CELLS',
           'NO_INFORMATION', 'TILE', 'Window', 'bounded_resolution', 'draw', 'global_window', 'local_window']

FREE, INSCRIBED, LETHAL, NO_INFORMATION = 0, 253, 254, 255   # nav2_costmap_2d/cost_values.hpp
DEFAULT_RESOLUTION = 0.05   # m a cell: Nav2's default (nav2_params.yaml, both costmaps)
# m, the local window's side: Nav2's stock local costmap is a rolling window 3 m x 3 m (nav2_params.yaml width 3,
# height 3) round the robot; a client that draws or checks it expects that much around the robot.
LOCAL_SIZE = 3.0
MAX_CELLS = 4_000_000       # cells a grid has at most (4 MB of costs); a finer request is drawn coarser
TILE = 32                   # cells a side of a tile (1.6 m at 0.05 m: measured the fastest of 16, 32, 64)
CLEARANCE_PAIRS = 1_000_000   # cell-obstacle distances computed at a time (a few tens of MB of temporaries)
_ROUND = 1e-4               # cells: an extent this close to a whole number of cells is that number (float32 slack)


@dataclass(frozen=True)
class Window:
    """Where a grid lies: the lower-left corner of cell (0, 0) (m, in the map frame), the cell side (m) and the
    cells along x and y; `coarsened`: the resolution asked for was raised to keep within MAX_CELLS."""

    origin_x: float
    origin_y: float
    resolution: float
    size_x: int
    size_y: int
    coarsened: bool = False

    @property
    def cells(self) -> int:
        return self.size_x * self.size_y


def _cells(extent: float, resolution: float) -> int:
    """Cells of `resolution` covering `extent` metres (at least one)."""
    return max(1, math.ceil(extent / resolution - _ROUND))


def bounded_resolution(width: float, height: float, resolution: float,
                       max_cells: int = MAX_CELLS) -> tuple[float, bool]:
    """The resolution to draw `width` x `height` metres at: `resolution`, or the finest coarser one keeping
    within `max_cells` (then True)."""
    cells = _cells(width, resolution) * _cells(height, resolution)
    if cells <= max_cells:
        return resolution, False
    coarser = resolution * math.sqrt(cells / max_cells)
    while _cells(width, coarser) * _cells(height, coarser) > max_cells:   # the ceilings: a step or two more
        coarser *= 1.0 + 1e-3
    return coarser, True


def global_window(workspace: Sequence[float], resolution: float, max_cells: int = MAX_CELLS) -> Window:
    """The global costmap's grid: the workspace (xmin, ymin, xmax, ymax), its origin the workspace's corner."""
    xmin, ymin, xmax, ymax = (float(v) for v in workspace)
    resolution, coarsened = bounded_resolution(xmax - xmin, ymax - ymin, resolution, max_cells)
    return Window(xmin, ymin, resolution, _cells(xmax - xmin, resolution), _cells(ymax - ymin, resolution),
                  coarsened)


def local_window(workspace: Sequence[float], centre: Sequence[float], resolution: float, side: float = LOCAL_SIZE,
                 max_cells: int = MAX_CELLS) -> Window:
    """The local costmap's grid: `side` x `side` metres round `centre` (the robot), its origin snapped to the
    global grid's cells (as Nav2's rolling window moves by whole cells), so its cells are the global one's."""
    xmin, ymin = float(workspace[0]), float(workspace[1])
    resolution, coarsened = bounded_resolution(side, side, resolution, max_cells)
    n = _cells(side, resolution)
    half = 0.5 * n * resolution
    ox = xmin + math.floor((float(centre[0]) - half - xmin) / resolution + 0.5) * resolution
    oy = ymin + math.floor((float(centre[1]) - half - ymin) / resolution + 0.5) * resolution
    return Window(ox, oy, resolution, n, n, coarsened)


def _boxes(obstacles: Obstacles) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Each obstacle's bounding box, lows and highs (n, 2), in the order of obstacles.items (circles first)."""
    size = np.abs(obstacles.radii)[:, None]
    lows = np.concatenate([obstacles.centers - size, np.minimum(obstacles.starts, obstacles.ends)])
    highs = np.concatenate([obstacles.centers + size, np.maximum(obstacles.starts, obstacles.ends)])
    return lows, highs


def _clearance(obstacles: Obstacles, xy: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each point's distance to the nearest obstacle surface, at most CLEARANCE_PAIRS distances at a time."""
    step = max(1, CLEARANCE_PAIRS // max(1, len(obstacles)))
    return np.concatenate([np.atleast_1d(obstacles.clearance(xy[i:i + step])) for i in range(0, len(xy), step)])


def draw(window: Window, workspace: Sequence[float], radius: float,
         obstacle_sets: Sequence[Obstacles]) -> NDArray[np.uint8]:
    """The costs (size_y, size_x) of the window's cells (module docstring): lethal, inscribed within `radius`,
    free, no information outside `workspace`; the obstacles of every set drawn."""
    res, nx, ny = window.resolution, window.size_x, window.size_y
    xs = window.origin_x + (np.arange(nx) + 0.5) * res   # cell centres
    ys = window.origin_y + (np.arange(ny) + 0.5) * res
    costs = np.zeros((ny, nx), dtype=np.uint8)
    lethal, reach = 0.5 * res, max(float(radius), 0.5 * res)
    for obstacles in obstacle_sets:
        if not len(obstacles):
            continue
        lows, highs = _boxes(obstacles)
        items = obstacles.items
        for y0 in range(0, ny, TILE):
            tile_ys = ys[y0:y0 + TILE]
            in_y = (highs[:, 1] >= tile_ys[0] - reach) & (lows[:, 1] <= tile_ys[-1] + reach)
            if not in_y.any():
                continue
            for x0 in range(0, nx, TILE):
                tile_xs = xs[x0:x0 + TILE]
                near = np.flatnonzero(in_y & (highs[:, 0] >= tile_xs[0] - reach) &
                                      (lows[:, 0] <= tile_xs[-1] + reach))
                if not len(near):
                    continue   # no obstacle within reach of any of its cells: free
                # Exactly the obstacles that can come within reach (those left out are farther from every cell).
                tile = Obstacles(items[k] for k in near) if len(near) < len(items) else obstacles
                gx, gy = np.meshgrid(tile_xs, tile_ys)
                room = _clearance(tile, np.column_stack([gx.ravel(), gy.ravel()])).reshape(gx.shape)
                cost = np.where(room <= lethal, LETHAL, np.where(room < radius, INSCRIBED, FREE)).astype(np.uint8)
                view = costs[y0:y0 + TILE, x0:x0 + TILE]
                np.maximum(view, cost, out=view)
    xmin, ymin, xmax, ymax = (float(v) for v in workspace)
    outside_x, outside_y = (xs < xmin) | (xs > xmax), (ys < ymin) | (ys > ymax)
    costs[outside_y[:, None] | outside_x[None, :]] = NO_INFORMATION
    return costs
