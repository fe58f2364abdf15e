"""Manoeuvres for a tractor-trailer: a hybrid-A* search over short forward and reverse arcs.

Why: a forward-steered vehicle pinned in a tight corner must back up and turn, sometimes more than once, which pure
pursuit plus a fixed menu of backups does not always find; hybrid A* (Dolgov, Thrun, Montemerlo and Diebel 2008)
searches the vehicle's own motions. An expansion drives ten arcs (forward or reverse; straight, half or full lock
either way) for `arc_ticks` ticks, integrating eq. 13 (RK4, four sub-steps; the found arcs are replayed tick by tick,
parting by at most 2 cm and 0.02 rad). An arc is kept if the reference point stays `keep` from obstacles and border
and the hitch stays within `max_hitch`; a robot already nearer than `keep` may come at most a millimetre nearer, and
no replayed tick may end below `floor` while getting nearer (the guard would stop it there). States merge on a grid
of (x, y, theta0, hitch); cost is distance, reverse and direction changes costing extra. The heuristic is the grid
distance round the obstacles (Dijkstra, scipy.sparse.csgraph), so the search follows the corridor out of a trap. It
stops where plain driving arrives (goal within `reach`, or in clear sight ahead, trailer nearly straight) and returns
each tick's command and state, for the navigator to replay and check against odometry.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

from fastep_core.kinematics.tractor_trailer import MAX_STEER, TractorTrailer, hitch_angle, wrap_angle
from fastep_core.world import World

__all__ = ['DistanceField', 'Manoeuvre', 'plan_manoeuvre', 'main']

FloatArray = NDArray[np.float64]
REVERSE_COST = 2.0        # a metre in reverse costs this many metres forward
SWITCH_COST = 1.5         # metres added for each change between forward and reverse
STEER_COST = 0.1          # metres added per arc at full lock (prefers straight arcs among equals)
HEURISTIC_WEIGHT = 2.0    # weighted A*: a manoeuvre that works, found fast, rather than the shortest
XY_CELL = 0.3             # metres: states closer than this (and in the same angle cells) are one
HEADING_CELLS = 24        # 15 degrees
HITCH_CELL = 0.15         # rad
AHEAD = math.radians(30.0)  # the goal counts as straight ahead within this heading error ...
STRAIGHT_HITCH = 0.35       # ... with the trailer folded less than this (rad)
SUBSTEPS = 4              # RK4 sub-steps per arc in the search (the replay integrates every tick)
REPLAY_SLACK = 0.02       # m: the replay may come this much closer than `keep` between the search's sub-steps
HITCH_SLACK = 0.02        # rad: ... and fold the trailer this much further than `max_hitch` (it integrates every
                          # tick, the search 4 sub-steps per arc, and the two part by a few mrad over a manoeuvre)


@dataclass(frozen=True)
class Manoeuvre:
    """A found manoeuvre: commands[k] is the (v, omega) of tick k, states[k] the state before it."""

    commands: FloatArray   # (n, 2)
    states: FloatArray     # (n + 1, 4): the start, then the state after each tick
    arcs: int              # arcs driven
    reversals: int         # changes between forward and reverse
    expansions: int        # search nodes expanded

    @property
    def ticks(self) -> int:
        return len(self.commands)


class DistanceField:
    """Shortest distance to a goal round the obstacles, on a grid (the search's heuristic).

    A cell is free when its centre keeps `keep` minus a cell from every obstacle and the border: looser than the
    search's own test, so every state the search can reach lies in a free cell (within 0.71 cell of its centre).
    """

    def __init__(self, world: World, goal: Sequence[float] | FloatArray, keep: float, cell: float = 0.25) -> None:
        xmin, ymin, xmax, ymax = world.workspace
        self.origin = np.array([xmin, ymin])
        self.cell = cell
        self.shape = (max(1, int(math.ceil((ymax - ymin) / cell))), max(1, int(math.ceil((xmax - xmin) / cell))))
        ny, nx = self.shape
        xs = xmin + (np.arange(nx) + 0.5) * cell
        ys = ymin + (np.arange(ny) + 0.5) * cell
        centres = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
        free = world.room(centres) >= keep - cell
        goal_index = self.index(np.asarray(goal, dtype=float)[None, :])[0]
        free[goal_index] = True
        ids = np.arange(ny * nx).reshape(ny, nx)
        rows, cols, weights = [], [], []
        for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
            a = ids[max(0, -dy):ny - max(0, dy), max(0, -dx):nx - max(0, dx)]
            b = ids[max(0, dy):ny + min(0, dy) or None, max(0, dx):nx + min(0, dx) or None]
            a, b = a.ravel(), b.ravel()
            both = free[a] & free[b]
            rows.append(a[both])
            cols.append(b[both])
            weights.append(np.full(int(both.sum()), cell * math.hypot(dx, dy)))
        # Imported here: scipy.sparse costs ~0.15 s of import, and every planner process imports this module
        # while only a tractor-trailer's manoeuvre (a reverse out of a trap) ever builds the field.
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import dijkstra
        graph = coo_matrix((np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))),
                           shape=(ny * nx, ny * nx)).tocsr()
        self.distance = dijkstra(graph, directed=False, indices=goal_index)

    def index(self, points: FloatArray) -> NDArray[np.intp]:
        ny, nx = self.shape
        ij = np.floor((points - self.origin) / self.cell).astype(np.intp)
        flat: NDArray[np.intp] = np.clip(ij[:, 1], 0, ny - 1) * nx + np.clip(ij[:, 0], 0, nx - 1)
        return flat

    def __call__(self, points: FloatArray) -> FloatArray:
        """Distance to the goal from each point (n, 2); inf where the goal cannot be reached."""
        return self.distance[self.index(points)]


def _rates(model: TractorTrailer, s: FloatArray, v: FloatArray, omega: FloatArray) -> FloatArray:
    """Eq. 13 for many states at once (TractorTrailer.derivative, vectorised over rows)."""
    th0, th1 = s[:, 2], s[:, 3]
    lat = 0.5 * model.length * omega
    c0, s0 = np.cos(th0), np.sin(th0)
    rel = th0 - th1
    return np.stack([v * c0 - lat * s0, v * s0 + lat * c0, omega,
                     (v * np.sin(rel) - model.hitch_offset * omega * np.cos(rel)) / model.trailer_length], axis=1)


def _drive(model: TractorTrailer, state: FloatArray, v: FloatArray, omega: FloatArray, duration: float,
           substeps: int) -> FloatArray:
    """Every arc from one state: the states after each sub-step, shape (substeps, n_arcs, 4)."""
    h = duration / substeps
    s = np.repeat(state[None, :], len(v), axis=0)
    out = np.empty((substeps, len(v), 4))
    for k in range(substeps):
        k1 = _rates(model, s, v, omega)
        k2 = _rates(model, s + 0.5 * h * k1, v, omega)
        k3 = _rates(model, s + 0.5 * h * k2, v, omega)
        k4 = _rates(model, s + h * k3, v, omega)
        s = s + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        out[k] = s
    return out


def _hitch(states: FloatArray) -> FloatArray:
    """hitch_angle for an array of states (..., 4)."""
    return np.arctan2(np.sin(states[..., 3] - states[..., 2]), np.cos(states[..., 3] - states[..., 2]))


def plan_manoeuvre(model: TractorTrailer, world: World, state: Sequence[float] | FloatArray,
                   goal: Sequence[float] | FloatArray,
                   keep: float, dt: float, *, floor: float | None = None, clear_within: float | None = None,
                   speed: float = 0.5, arc_ticks: int = 30, reach: float = 1.0, max_hitch: float = 1.0,
                   max_expansions: int = 6000) -> Manoeuvre | None:
    """A manoeuvre from `state` to where kinematic driving reaches `goal`, or None if the search finds none.

    keep: clearance of the reference point from obstacles and border along the way, or from a start nearer
    than that, no nearer than it already is (less a millimetre); floor: a clearance no tick may end below while
    getting nearer (the robot's radius: what the guard enforces; default none); clear_within: how far the
    straight run to the goal must stay from every obstacle for the goal to count as in sight (default keep;
    inf: only the goal within reach ends a manoeuvre); speed: m/s of every arc; arc_ticks: control ticks of dt
    per arc; max_hitch: the trailer may not fold further than this (rad), or than it already is, at the
    search's sub-steps; the replayed ticks may fold HITCH_SLACK more.
    """
    start = np.asarray(state, dtype=float)
    goal = np.asarray(goal, dtype=float)
    clear_within = keep if clear_within is None else clear_within
    start_room = float(world.room(start[None, :2])[0])
    kept = min(keep, start_room - 1e-3)   # what the whole manoeuvre keeps: keep, or a millimetre less than now
    lowest = -math.inf if floor is None else floor
    field = DistanceField(world, goal, kept)
    if not math.isfinite(float(field(start[None, :2])[0])):
        return None
    lock = np.array([-MAX_STEER, -0.5 * MAX_STEER, 0.0, 0.5 * MAX_STEER, MAX_STEER])
    v = np.concatenate([np.full(5, speed), np.full(5, -speed)])
    omega = v * np.tan(np.concatenate([lock, lock])) / model.length
    duration = arc_ticks * dt
    arc_cost = speed * duration * np.where(v > 0, 1.0, REVERSE_COST) + \
        STEER_COST * np.abs(np.concatenate([lock, lock])) / MAX_STEER
    hitch_limit = max(max_hitch, abs(hitch_angle(start)) + 1e-6)
    obstacles = world.obstacles

    def key(s: FloatArray) -> tuple[int, int, int, int]:
        return (int(math.floor(s[0] / XY_CELL)), int(math.floor(s[1] / XY_CELL)),
                int(round(wrap_angle(float(s[2])) / (2 * math.pi / HEADING_CELLS))) % HEADING_CELLS,
                int(round(hitch_angle(s) / HITCH_CELL)))

    def arrives(s: FloatArray) -> bool:
        to_goal = goal - s[:2]
        distance = math.hypot(*to_goal)
        ahead = abs(hitch_angle(s)) <= STRAIGHT_HITCH and \
            abs(wrap_angle(math.atan2(to_goal[1], to_goal[0]) - float(s[2]))) <= AHEAD
        if distance <= reach and ahead:
            # Near, but ahead too: a goal near the tractor's side or behind it lies inside its turning circle,
            # which the steering law orbits for ever (a goal 1 m behind was "reached" by an empty manoeuvre).
            return True
        if clear_within == math.inf or not ahead:
            return False
        return not len(obstacles) or float(obstacles.path_clearance(s[:2], goal)) >= clear_within

    # Nodes: state, parent index, arc index (-1 for the start), cost so far, room (clearance) at the state.
    states: list[FloatArray] = [start]
    parents: list[int] = [-1]
    arcs_of: list[int] = [-1]
    costs: list[float] = [0.0]
    rooms: list[float] = [start_room]
    best: dict[tuple[int, int, int, int], float] = {key(start): 0.0}
    frontier = [(HEURISTIC_WEIGHT * float(field(start[None, :2])[0]), 0)]
    expansions = 0
    found = 0 if arrives(start) else -1
    while frontier and found < 0 and expansions < max_expansions:
        _, node = heapq.heappop(frontier)
        s, g = states[node], costs[node]
        if best.get(key(s), math.inf) < g - 1e-9:
            continue   # a cheaper way into this cell was found after this entry was queued
        expansions += 1
        path = _drive(model, s, v, omega, duration, SUBSTEPS)      # (SUBSTEPS, 10, 4)
        room = world.room(path[..., :2])                             # (SUBSTEPS, 10)
        need = min(keep, max(lowest, rooms[node] - 1e-3))
        ok = (room >= need).all(axis=0) & (np.abs(_hitch(path)) <= hitch_limit).all(axis=0)
        ends = path[-1]
        h = field(ends[:, :2])
        switch = SWITCH_COST * (np.sign(v) != np.sign(v[arcs_of[node]])) if arcs_of[node] >= 0 else np.zeros(10)
        for arc in np.flatnonzero(ok & np.isfinite(h)):
            end = ends[arc]
            cost = g + float(arc_cost[arc] + switch[arc])
            k = key(end)
            if best.get(k, math.inf) <= cost:
                continue
            best[k] = cost
            states.append(end)
            parents.append(node)
            arcs_of.append(int(arc))
            costs.append(cost)
            rooms.append(float(room[-1, arc]))
            if arrives(end):
                found = len(states) - 1
                break
            heapq.heappush(frontier, (cost + HEURISTIC_WEIGHT * float(h[arc]), len(states) - 1))
    if found < 0:
        return None
    chain = []
    node = found
    while arcs_of[node] >= 0:
        chain.append(arcs_of[node])
        node = parents[node]
    chain.reverse()
    # Replayed tick by tick with the plant's own integrator: these are the states the robot will pass.
    commands = np.array([[v[a], omega[a]] for a in chain for _ in range(arc_ticks)]).reshape(-1, 2)
    replay = [start]
    for command in commands:
        replay.append(model.integrate(replay[-1], command, dt))
    replayed = np.array(replay)
    # The search checked each arc at a few sub-steps; the replay is what the robot drives, so it must keep
    # the clearance too (a corner passed between two sub-steps), never get nearer below the floor, and not
    # fold the trailer further than the search allowed.
    room = world.room(replayed[:, :2])
    if float(room.min()) < kept - REPLAY_SLACK or \
            bool(np.any((room[1:] < lowest) & (room[1:] < room[:-1]))) or \
            float(np.abs(_hitch(replayed)).max()) > hitch_limit + HITCH_SLACK:
        return None
    reversals = sum(1 for a, b in zip(chain, chain[1:]) if np.sign(v[a]) != np.sign(v[b]))
    return Manoeuvre(commands, replayed, len(chain), reversals, expansions)


def main() -> None:
    """A tractor-trailer facing the back wall of a U-shaped pocket turns round and drives out to its goal."""
    from fastep_core.geometry import Segment
    world = World((0.0, 0.0, 20.0, 20.0), (Segment((8.0, 8.0), (12.0, 8.0)), Segment((12.0, 8.0), (12.0, 12.0)),
                                           Segment((12.0, 12.0), (8.0, 12.0))))
    found = plan_manoeuvre(TractorTrailer(), world, [10.5, 10.0, 0.0, 0.0], [2.0, 10.0], keep=0.6, dt=0.05)
    if found is None:
        print('no manoeuvre found')
        return
    print(f'{found.arcs} arcs, {found.reversals} reversals, {found.ticks * 0.05:.1f} s, '
          f'{found.expansions} expansions; ends at ({found.states[-1][0]:.2f}, {found.states[-1][1]:.2f})')


if __name__ == '__main__':
    main()
