"""The robot harness's worlds: rooms with walls a laser sees, one differential-drive robot, a start and a goal.

Each is a format-v2 scenario (fastep_core.scenario): the truth is every obstacle, the planner's /map only the
known ones (`known: false`: in the truth and the laser, not on the map). The room's walls are segments 0.1 m
inside the workspace, so the map's border cells are free and the laser has walls to see. Sized for 10-40 s of
wall time at 1 m/s. The shortest, `open_room`, is the end-to-end test's.
"""

from __future__ import annotations

from typing import Any

from fastep_core.scenario import Scenario, parse_scenario

__all__ = ['RADIUS', 'WORLDS', 'world']

RADIUS = 0.3   # m: a TurtleBot-class base
INSET = 0.1    # m: the room's walls inside the workspace


def _room(width: float, height: float) -> list[dict[str, Any]]:
    a, b, c, d = (INSET, INSET), (width - INSET, INSET), (width - INSET, height - INSET), (INSET, height - INSET)
    return [{'segment': {'start': list(p), 'end': list(q)}} for p, q in ((a, b), (b, c), (c, d), (d, a))]


def _box(cx: float, cy: float, side: float, known: bool) -> list[dict[str, Any]]:
    h = side / 2.0
    corners = [(cx - h, cy - h), (cx + h, cy - h), (cx + h, cy + h), (cx - h, cy + h)]
    return [{'segment': {'start': list(corners[k]), 'end': list(corners[(k + 1) % 4])}, 'known': known}
            for k in range(4)]


def _scenario(name: str, description: str, size: tuple[float, float], obstacles: list[dict[str, Any]],
              start: tuple[float, float, float], goal: tuple[float, float]) -> Scenario:
    return parse_scenario({
        'name': name, 'description': description, 'workspace': [0.0, 0.0, size[0], size[1]],
        'obstacles': _room(*size) + obstacles,
        'robots': [{'name': 'r1', 'model': 'diff_drive', 'start': list(start), 'goal': list(goal),
                    'radius': RADIUS}]})


def _office() -> list[dict[str, Any]]:
    """A 24 m x 16 m floor: a corridor along y 7-9, four 6 m x 6.9 m rooms on each side with a 1 m door onto it,
    a desk (1.2 m x 0.6 m) and a cabinet (0.5 m square) in each room: a map of some hundred wall runs."""
    walls: list[dict[str, Any]] = []

    def wall(a: tuple[float, float], b: tuple[float, float]) -> None:
        walls.append({'segment': {'start': list(a), 'end': list(b)}})
    for side, y, far in ((-1, 7.0, INSET), (1, 9.0, 16.0 - INSET)):
        for k in range(4):
            x0, x1 = INSET + 6.0 * k, min(INSET + 6.0 * (k + 1), 24.0 - INSET)
            if k:
                wall((x0, y), (x0, far))                       # between two rooms
            wall((x0, y), (x0 + 2.5, y))                       # the corridor wall, the door from x0 + 2.5 to 3.5
            wall((x0 + 3.5, y), (x1, y))
            desk_y = y + side * 4.5
            walls.extend(_rectangle(x0 + 1.0, desk_y, 1.2, 0.6))
            walls.extend(_rectangle(x0 + 4.5, y + side * 2.0, 0.5, 0.5))
    return walls


def _rectangle(cx: float, cy: float, width: float, height: float) -> list[dict[str, Any]]:
    w, h = width / 2.0, height / 2.0
    corners = [(cx - w, cy - h), (cx + w, cy - h), (cx + w, cy + h), (cx - w, cy + h)]
    return [{'segment': {'start': list(corners[k]), 'end': list(corners[(k + 1) % 4])}} for k in range(4)]


def _worlds() -> dict[str, Scenario]:
    poles = [{'circle': {'center': [x, y], 'radius': 0.05}}
             for x, y in ((5.0, 4.6), (6.5, 3.3), (8.0, 4.2), (9.5, 3.5), (11.0, 4.8), (7.2, 5.6))]
    return {w.name: w for w in (
        _scenario('open_room', 'an empty 10 m x 6 m room, 7 m straight ahead', (10.0, 6.0), [],
                  (1.5, 3.0, 0.0), (8.5, 3.0)),
        _scenario('wall_ahead', 'a 9 m x 6 m room, the goal 7.45 m straight ahead and 0.45 m before its far wall',
                  (9.0, 6.0), [], (1.0, 3.0, 0.0), (8.45, 3.0)),
        _scenario('behind_wall', 'a 14 m x 10 m room halved by a wall with a 2.5 m gap at the bottom; the goal is '
                  'behind it', (14.0, 10.0), [{'segment': {'start': [7.0, 2.6], 'end': [7.0, 9.9]}}],
                  (3.0, 6.0, 0.0), (11.0, 6.0)),
        _scenario('unmapped_box', 'a 16 m x 4 m corridor with a 0.6 m box on its axis that the map lacks',
                  (16.0, 4.0), _box(8.0, 2.0, 0.6, known=False), (1.5, 2.0, 0.0), (14.5, 2.2)),
        _scenario('thin_cylinders', 'a 14 m x 8 m room with six poles of 0.1 m diameter across the way',
                  (14.0, 8.0), poles, (1.5, 4.0, 0.0), (12.5, 4.0)),
        _scenario('office', 'a 24 m x 16 m floor of eight furnished rooms off a corridor; from a room on one side '
                  'to the far room on the other', (24.0, 16.0), _office(), (3.0, 3.0, 1.57), (21.0, 13.0)),
    )}


WORLDS: dict[str, Scenario] = _worlds()


def world(name: str) -> Scenario:
    """A world by name (KeyError naming the known ones)."""
    if name not in WORLDS:
        raise KeyError(f'no harness world {name!r} (known: {", ".join(WORLDS)})')
    return WORLDS[name]
