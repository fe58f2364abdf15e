"""The world as a ROS occupancy grid (nav_msgs/OccupancyGrid, `/map`) and back: rasterising a World for Nav2's
map server conventions, and reading a map server's grid as the outline of its occupied cells (walls).

Cells are sized so the grid stays within MAX_GRID_CELLS whatever the workspace; occupied from OCCUPIED_THRESHOLD
(map_server's occupied_thresh 0.65); unknown cells (-1) are free. msg_tools.convert re-exports these.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose
from nav_msgs.msg import MapMetaData, OccupancyGrid
from numpy.typing import NDArray

from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.world import World

__all__ = ['DEFAULT_RESOLUTION', 'MAX_GRID_CELLS', 'OCCUPIED_THRESHOLD', 'CellLookup', 'GridCopy', 'GridWalls',
           'grid_copy', 'grid_resolution', 'grid_shape', 'grid_walls', 'occupancy_grid_lookup',
           'occupancy_grid_obstacles', 'occupancy_grid_workspace', 'world_to_occupancy_grid']

DEFAULT_RESOLUTION = 0.1
"""m: the /map cell size of a workspace small enough (200 m x 200 m) for it; larger ones get coarser cells."""
MAX_GRID_CELLS = 4_000_000
"""The most cells a /map grid may have (2000 x 2000; 4 MB on the wire, ~0.3 GB while it is rasterised): a 1 km
workspace at 0.1 m took 4 GB in `fastep-sim --mcap`, a 5 km one (or 1e-4 m cells) ended in MemoryError."""
_NICE_STEPS = ('1', '2', '2.5', '5')   # automatic cell sizes: 0.1, 0.2, 0.25, 0.5, 1, 2, 2.5, 5, 10, ... m


def grid_shape(workspace: Sequence[float], resolution: float) -> tuple[int, int]:
    """(width, height) in cells of a grid covering the workspace (cells rounded up at the far edges)."""
    xmin, ymin, xmax, ymax = workspace
    width = max(1, int(math.ceil((xmax - xmin) / resolution - 1e-9)))
    height = max(1, int(math.ceil((ymax - ymin) / resolution - 1e-9)))
    return width, height


def grid_resolution(workspace: Sequence[float], resolution: float | None = None) -> float:
    """The /map cell size (m) of a workspace, so that the grid has at most MAX_GRID_CELLS cells.

    None (automatic; what fastep-sim --mcap and fastep-map use by default): DEFAULT_RESOLUTION, or for a
    larger workspace the smallest of 0.2, 0.25, 0.5, 1, 2, 2.5, 5, 10, ... m that fits (exact in decimal, so
    it survives the float32 of MapMetaData.resolution). A given resolution: ValueError (one line, naming the
    smallest that fits) if it is not > 0 or its grid would have more cells."""
    if resolution is not None:
        if not (math.isfinite(resolution) and resolution > 0.0):
            raise ValueError(f'resolution must be > 0, got {resolution!r}')
        width, height = grid_shape(workspace, resolution)
        if width * height > MAX_GRID_CELLS:
            raise ValueError(f'resolution {resolution:g} m would make a {width} x {height} grid, more than '
                             f'{MAX_GRID_CELLS:,} cells; this workspace needs at least '
                             f'{grid_resolution(workspace):g} m (0 chooses it)')
        return float(resolution)
    xmin, ymin, xmax, ymax = workspace
    # Start one decade below what the area alone needs (a thin workspace needs less), then go up.
    needed = math.sqrt(max(xmax - xmin, 1e-300) * max(ymax - ymin, 1e-300) / MAX_GRID_CELLS)
    exponent = max(0, math.floor(math.log10(max(needed / DEFAULT_RESOLUTION, 1.0))) - 1)
    for k in range(exponent, exponent + 400):
        for step in _NICE_STEPS:
            candidate = float(f'{step}e{k - 1}')
            width, height = grid_shape(workspace, candidate)
            if width * height <= MAX_GRID_CELLS:
                if candidate > 3.0e38:   # MapMetaData.resolution is a float32
                    raise ValueError(f'workspace {tuple(workspace)} is too large for an occupancy grid')
                return candidate
    raise ValueError(f'workspace {tuple(workspace)} is too large for an occupancy grid')


def world_to_occupancy_grid(world: World, resolution: float | None = None, stamp: Time | None = None,
                            frame_id: str = 'map', thickness: float | None = None) -> OccupancyGrid:
    """Rasterise the world: 100 where a cell centre is inside a circle or within thickness / 2 of a segment
    (default thickness: one cell, so a wall has no gaps; a wall on a border between cells marks the cells on both
    sides), 0 elsewhere. The grid covers the workspace
    (origin at xmin, ymin; cells rounded up at the far edges). resolution: see grid_resolution (None:
    automatic; ValueError if the grid would exceed MAX_GRID_CELLS). Each obstacle is rasterised over the cells
    of its bounding box only."""
    resolution = grid_resolution(world.workspace, resolution)
    xmin, ymin, xmax, ymax = world.workspace
    width, height = grid_shape(world.workspace, resolution)
    half = 0.5 * (resolution if thickness is None else thickness)
    xs = xmin + (np.arange(width) + 0.5) * resolution
    ys = ymin + (np.arange(height) + 0.5) * resolution
    grid = np.zeros((height, width), dtype=bool)

    def cells(low: float, high: float, origin: float, count: int) -> slice:
        """The cells whose centres may lie in [low, high] (one cell of margin against rounding)."""
        first = math.floor((low - origin) / resolution - 0.5) - 1
        last = math.ceil((high - origin) / resolution - 0.5) + 2
        return slice(min(max(first, 0), count), min(max(last, 0), count))

    for obstacle in world.obstacle_list:
        if isinstance(obstacle, Circle):
            cx, cy = obstacle.center
            reach = obstacle.radius
            bx, by = (cx - reach, cx + reach), (cy - reach, cy + reach)
        else:
            reach = half
            bx = (min(obstacle.start[0], obstacle.end[0]) - reach, max(obstacle.start[0], obstacle.end[0]) + reach)
            by = (min(obstacle.start[1], obstacle.end[1]) - reach, max(obstacle.start[1], obstacle.end[1]) + reach)
        cols, rows = cells(*bx, xmin, width), cells(*by, ymin, height)
        if cols.start >= cols.stop or rows.start >= rows.stop:
            continue
        gx, gy = np.meshgrid(xs[cols], ys[rows])
        if isinstance(obstacle, Circle):
            grid[rows, cols] |= np.hypot(gx - cx, gy - cy) <= obstacle.radius
        else:
            d = Obstacles([obstacle]).distances(np.stack([gx, gy], axis=-1))[..., 0]
            # A wall exactly on a border between two rows of cells is half a cell from both rows' centres, give
            # or take a rounding: it marks both (strictly, both rounded away, and the wall was missing from /map).
            grid[rows, cols] |= d <= half + BORDER_SLACK * resolution
    msg = OccupancyGrid()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    info = MapMetaData()
    if stamp is not None:
        info.map_load_time = stamp
    info.resolution = float(resolution)
    info.width, info.height = width, height
    info.origin = Pose()
    info.origin.position = Point(x=float(xmin), y=float(ymin), z=0.0)
    info.origin.orientation.w = 1.0
    msg.info = info
    msg.data = np.where(grid, 100, 0).astype(np.int8).ravel().tolist()
    return msg


def occupancy_grid_workspace(msg: OccupancyGrid) -> tuple[float, float, float, float]:
    """The workspace (xmin, ymin, xmax, ymax) a grid covers (its orientation must be the identity)."""
    info = msg.info
    o = info.origin
    values = (o.position.x, o.position.y, info.resolution)
    if not all(math.isfinite(v) for v in values):
        raise ValueError('map metadata is not finite')
    if info.resolution <= 0.0 or info.width == 0 or info.height == 0:
        raise ValueError('map metadata: empty grid or resolution <= 0')
    if abs(o.orientation.z) > 1e-9 or abs(o.orientation.x) > 1e-9 or abs(o.orientation.y) > 1e-9:
        raise ValueError('map metadata: a rotated map origin is not supported')
    xmin, ymin = float(o.position.x), float(o.position.y)
    # The resolution is a float32 on the wire (0.1 arrives as 0.10000000149...): undo that rounding.
    resolution = float(f'{info.resolution:.7g}')
    return xmin, ymin, round(xmin + info.width * resolution, 9), round(ymin + info.height * resolution, 9)


BORDER_SLACK = 1e-9
"""Share of a cell by which a cell centre may lie beyond a wall's half thickness and still be the wall's
(world_to_occupancy_grid): far above the rounding of the centres' coordinates, far below any real gap."""

OCCUPIED_THRESHOLD = 65
"""A cell is occupied from this value (of 0-100) on: Nav2's map_server default (occupied_thresh 0.65)."""


def occupancy_grid_obstacles(msg: OccupancyGrid, occupied_threshold: int = OCCUPIED_THRESHOLD) -> list[Segment]:
    """The obstacles of an occupancy grid (as Nav2's map_server publishes one): the outline of its occupied
    cells (value >= occupied_threshold; unknown, -1, counts as free), as wall segments on the cell borders, each
    run of border along a row or a column one segment. A robot outside an occupied region keeps its distance to
    the region's outline, which is its surface. Vectorised over the cells (a 4000 x 4000 grid: a fraction of a
    second; the walls are Python objects, ~10 us each). ValueError (one line) for a grid whose data does not fill
    width x height, or bad metadata. No bound on the walls: the planner takes a map through grid_walls."""
    grid = grid_copy(msg, max_cells=None)
    _check_threshold(occupied_threshold)
    return grid_walls(grid, occupied_threshold, max_walls=None).walls


def occupancy_grid_lookup(msg: OccupancyGrid,
                          occupied_threshold: int = OCCUPIED_THRESHOLD) -> Callable[[Sequence[float]], bool]:
    """A function telling whether a map point lies in an occupied cell of the grid (outside it: False)."""
    grid = grid_copy(msg, max_cells=None)
    _check_threshold(occupied_threshold)
    return grid_walls(grid, occupied_threshold, max_walls=None).occupied


# ------------------------------------------------------------------------------------------ bounded maps
@dataclass(frozen=True)
class GridCopy:
    """An occupancy grid's cells and where they lie, copied out of its message (one copy of width x height bytes:
    what a node's executor does with a /map before the walls are made elsewhere; grid_copy)."""

    xmin: float
    ymin: float
    resolution: float   # m, the float32 rounding of the wire undone
    width: int
    height: int
    data: NDArray[np.int8] = field(repr=False)   # row-major, width x height values (-1 unknown, 0-100)

    @property
    def cells(self) -> int:
        return self.width * self.height

    @property
    def workspace(self) -> tuple[float, float, float, float]:
        return (self.xmin, self.ymin, round(self.xmin + self.width * self.resolution, 9),
                round(self.ymin + self.height * self.resolution, 9))


def grid_copy(msg: OccupancyGrid, max_cells: int | None = MAX_GRID_CELLS) -> GridCopy:
    """The grid of a message, its data copied (ValueError in one line for bad metadata, data that does not fill
    width x height, or more than max_cells cells: refused before anything is copied; None: no bound)."""
    xmin, ymin, _, _ = occupancy_grid_workspace(msg)
    width, height = int(msg.info.width), int(msg.info.height)
    if max_cells is not None and width * height > max_cells:
        raise ValueError(f'{width} x {height} = {width * height:,} cells, more than the {max_cells:,} a map may have')
    if len(msg.data) != width * height:
        raise ValueError(f'map data has {len(msg.data)} cells, width x height is {width} x {height} = '
                         f'{width * height}')
    data = np.array(msg.data, dtype=np.int8)   # from the message's array.array: one copy of its buffer
    data.flags.writeable = False
    return GridCopy(xmin, ymin, float(f'{msg.info.resolution:.7g}'), width, height, data)


class CellLookup:
    """Whether a map point lies in an occupied cell of a grid of `cell`-sized cells from (xmin, ymin)."""

    def __init__(self, occupied: NDArray[np.bool_], xmin: float, ymin: float, cell: float) -> None:
        self.occupied, self.xmin, self.ymin, self.cell = occupied, xmin, ymin, cell

    def __call__(self, point: Sequence[float]) -> bool:
        col = math.floor((float(point[0]) - self.xmin) / self.cell)
        row = math.floor((float(point[1]) - self.ymin) / self.cell)
        height, width = self.occupied.shape
        return bool(0 <= row < height and 0 <= col < width and self.occupied[row, col])


@dataclass(frozen=True)
class GridWalls:
    """The walls made of a grid (grid_walls): of its cells as given (merge 1), or of merged cells."""

    walls: list[Segment]
    occupied: CellLookup   # the cells the walls outline (merged ones where merge > 1)
    merge: int             # cells merged along each side (1: the grid as given)
    cell: float            # m: the size of the cells outlined
    given_walls: int       # walls of the grid as given (more than max_walls when merged)
    max_walls: int | None  # the bound it was made within

    def coarsened(self, grid: GridCopy) -> str:
        """What merging did to the grid, in a line ('' when nothing was merged)."""
        if self.merge == 1:
            return ''
        height, width = self.occupied.occupied.shape
        return (f'coarsened: {grid.width} x {grid.height} cells of {grid.resolution:g} m outline '
                f'{self.given_walls:,} walls, more than {self.max_walls:,}; merged into {width} x {height} cells of '
                f'{self.cell:g} m, each occupied where any of its {self.merge} x {self.merge} is '
                f'({len(self.walls):,} walls)')


def _check_threshold(occupied_threshold: int) -> None:
    if not 1 <= occupied_threshold <= 100:
        raise ValueError(f'occupied_threshold must be in [1, 100], got {occupied_threshold}')


def _borders(occupied: NDArray[np.bool_]) -> tuple[NDArray[np.int8], NDArray[np.int8]]:
    """Where a border of the occupied cells begins (+1) and ends (-1) along each line: between rows (runs along
    x), then between columns (runs along y)."""
    padded = np.pad(occupied, 1)   # a free border all round
    # Borders between a row and the one below it (y = ymin + i * cell), runs along x; and between a column and
    # the one left of it (x = xmin + j * cell), runs along y.
    across_rows = padded[1:, 1:-1] != padded[:-1, 1:-1]           # (height + 1, width)
    across_cols = (padded[1:-1, 1:] != padded[1:-1, :-1]).T       # (width + 1, height)
    steps = tuple(np.diff(np.pad(b.view(np.int8), ((0, 0), (1, 1))), axis=1) for b in (across_rows, across_cols))
    return steps[0], steps[1]


def _run_count(occupied: NDArray[np.bool_]) -> int:
    """The walls the outline of the occupied cells is (no index arrays: a merge is counted before it is made)."""
    return sum(int(np.count_nonzero(step == 1)) for step in _borders(occupied))


def _runs(occupied: NDArray[np.bool_]) -> list[tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]]:
    """The outline of the occupied cells as runs of border, in cells: (line, first, last) for the borders between
    rows (runs along x) and then between columns (runs along y)."""
    out = []
    for step in _borders(occupied):
        line, first = np.nonzero(step == 1)    # row-major: the starts and the ends of each line pair up
        _, last = np.nonzero(step == -1)
        out.append((line, first, last))
    return out


def _merged(occupied: NDArray[np.bool_], merge: int) -> NDArray[np.bool_]:
    """Blocks of merge x merge cells (from the first row and column; the far edges padded free), each occupied
    where any of its cells is."""
    height, width = occupied.shape
    rows, cols = -(-height // merge), -(-width // merge)
    padded = np.zeros((rows * merge, cols * merge), dtype=bool)
    padded[:height, :width] = occupied
    return np.asarray(padded.reshape(rows, merge, cols, merge).any(axis=(1, 3)))


def grid_walls(grid: GridCopy, occupied_threshold: int = OCCUPIED_THRESHOLD,
               max_walls: int | None = None) -> GridWalls:
    """The outline of a grid's occupied cells as walls (occupancy_grid_obstacles), at most max_walls of them
    (None: no bound): beyond it the cells are merged, 2 x 2, 3 x 3, ..., the fewest that fit, a merged cell
    occupied where any of its cells is, so the walls never leave out an occupied cell (the free space shrinks
    by less than a merged cell at each wall). Counting the walls of a merge is vectorised (no wall is made
    until one fits); the walls are clipped to the grid's extent."""
    occupied = grid.data.reshape(grid.height, grid.width) >= occupied_threshold
    merge, cells = 1, occupied
    given = count = _run_count(occupied)
    while max_walls is not None and count > max_walls and max(cells.shape) > 1:
        merge += 1
        cells = _merged(occupied, merge)
        count = _run_count(cells)
    runs = _runs(cells)
    cell = grid.resolution * merge
    xmin, ymin, xmax, ymax = grid.workspace
    walls: list[Segment] = []
    for (line, first, last), along_x in zip(runs, (True, False)):
        fixed = (ymin if along_x else xmin) + line * cell
        lo = (xmin if along_x else ymin) + first * cell
        hi = (xmin if along_x else ymin) + last * cell
        if merge > 1:   # merged cells at the far edges reach past the grid
            far, far_along = (ymax, xmax) if along_x else (xmax, ymax)
            fixed, lo, hi = np.minimum(fixed, far), np.minimum(lo, far_along), np.minimum(hi, far_along)
        if along_x:
            walls.extend(Segment((a, f), (b, f)) for f, a, b in zip(fixed.tolist(), lo.tolist(), hi.tolist()))
        else:
            walls.extend(Segment((f, a), (f, b)) for f, a, b in zip(fixed.tolist(), lo.tolist(), hi.tolist()))
    return GridWalls(walls, CellLookup(cells, xmin, ymin, cell), merge, cell, given, max_walls)
