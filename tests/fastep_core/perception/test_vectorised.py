"""Perception's vectorised helpers against simple references (one cluster, one obstacle, one call at a time) on
random inputs: the same answers, bit for bit (issue 31: the time of one scan's perception)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import NDArray

from fastep_core.geometry import Circle, Obstacle, Obstacles, Segment
from fastep_core.perception.belief import MERGE_GAP, MERGE_TOLERANCE, Perception
from fastep_core.perception.fusion import (
    END_SLACK,
    EXPLAINED,
    explained,
    explained_by_belief,
    nearest_surfaces,
    seen_through,
    seen_through_and_nearest,
    seen_through_circles,
)
from fastep_core.perception.shapes import cluster_sums, extend_ends
from fastep_core.sensing.laser import LaserSpec, Scan, fan_directions, fan_hits, scan
from fastep_core.world import World

FloatArray = NDArray[np.float64]
SEEDS = range(20)


def random_world(rng: np.random.Generator, circles: int, segments: int) -> list[Obstacle]:
    """Circles and segments about the origin, some beyond an 8 m range, a few segments of zero length."""
    items: list[Obstacle] = [Circle((float(x), float(y)), float(r)) for (x, y), r in
                             zip(rng.uniform(-9.0, 9.0, (circles, 2)), rng.uniform(0.05, 1.5, circles))]
    for a, run in zip(rng.uniform(-9.0, 9.0, (segments, 2)), rng.normal(0.0, 2.0, (segments, 2))):
        b = a if rng.random() < 0.1 else a + run
        items.append(Segment((float(a[0]), float(a[1])), (float(b[0]), float(b[1]))))
    rng.shuffle(items)   # type: ignore[arg-type]   # a list of obstacles, shuffled in place
    return items


@pytest.mark.parametrize('seed', SEEDS)
def test_cluster_sums_are_bincount_of_each_row(seed: int) -> None:
    rng = np.random.default_rng(seed)
    clusters = int(rng.integers(1, 12))
    labels = rng.integers(0, clusters, int(rng.integers(0, 300)))
    weights = rng.normal(0.0, 10.0, (int(rng.integers(1, 9)), len(labels)))
    sums = cluster_sums(labels, weights, clusters)
    reference = np.array([np.bincount(labels, weights=row, minlength=clusters) for row in weights])
    assert sums.shape == reference.shape and np.array_equal(sums, reference)


@pytest.mark.parametrize('seed', SEEDS)
def test_extend_ends_is_the_loop_over_polylines(seed: int) -> None:
    rng = np.random.default_rng(seed)
    polylines = [rng.normal(0.0, 3.0, (int(rng.integers(2, 6)), 2)) for _ in range(int(rng.integers(1, 6)))]
    for vertices in polylines:
        if rng.random() < 0.2:
            vertices[1] = vertices[0]       # a zero-length end: not extended
    origin, gap = rng.normal(0.0, 1.0, 2), float(rng.uniform(0.0, 0.02))
    expected = []
    for polyline in polylines:              # shapes' loop as it was: one polyline, one end at a time
        vertices = polyline.copy()
        for end, inner in ((0, 1), (-1, -2)):
            run = vertices[end] - vertices[inner]
            length = float(np.hypot(*run))
            if length > 0.0:
                reach = float(np.hypot(*(vertices[end] - origin))) * gap
                vertices[end] = vertices[end] + run * (reach / length)
        expected.append(vertices)
    last = np.cumsum([len(v) for v in polylines]) - 1
    first = np.concatenate([[0], last[:-1] + 1])
    out = extend_ends(np.concatenate(polylines), first, last, origin, gap)
    assert np.array_equal(out, np.concatenate(expected))


def random_scan(rng: np.random.Generator, items: list[Obstacle]) -> tuple[FloatArray, Scan]:
    """A scan of 8 m and 360 beams of a random world with some of its obstacles (the rest: ghosts), a few nan."""
    spec = LaserSpec(range=8.0, beams=360, noise=0.01, fov=float(rng.choice([2.0 * math.pi, 1.5 * math.pi])))
    pose = np.array([*rng.uniform(-1.0, 1.0, 2), rng.uniform(-math.pi, math.pi)])
    truth = Obstacles(item for item in items if rng.random() < 0.7)
    reading = scan(spec, pose, rng, circles=truth.centers, radii=truth.radii, starts=truth.starts, ends=truth.ends)
    reading.ranges[rng.random(len(reading.ranges)) < 0.03] = np.nan
    return pose, reading


@pytest.mark.parametrize('seed', SEEDS)
def test_one_cast_for_seen_through_and_nearest_surfaces(seed: int) -> None:
    rng = np.random.default_rng(seed)
    believed = Obstacles(random_world(rng, int(rng.integers(0, 15)), int(rng.integers(0, 15))))
    pose, reading = random_scan(rng, list(believed.items))
    directions = fan_directions(pose[2], reading.angle_min, reading.angle_increment, len(reading.ranges))
    through, nearest = seen_through_and_nearest(reading, pose, believed, directions)
    assert np.array_equal(through, seen_through(reading, pose, believed))
    # nearest_surfaces: each beam's nearest hit ahead, from fan_hits without directions given.
    reference = np.full(len(reading.ranges), np.inf)
    beam, _, hit = fan_hits(pose[:2], pose[2], reading.angle_min, reading.angle_increment, len(reading.ranges),
                            believed.centers, believed.radii, believed.starts, believed.ends)
    np.minimum.at(reference, beam, np.where(hit > 0.0, hit, np.inf))
    if len(believed):
        assert np.array_equal(nearest, reference)
        assert np.array_equal(nearest_surfaces(reading, pose, believed), reference)


@pytest.mark.parametrize('seed', SEEDS)
def test_seen_through_circles_is_seen_through_of_their_obstacles(seed: int) -> None:
    rng = np.random.default_rng(seed)
    k = int(rng.integers(0, 12))
    centres, radii = rng.uniform(-9.0, 9.0, (k, 2)), rng.uniform(0.05, 2.0, k)
    pose, reading = random_scan(rng, random_world(rng, 8, 4))
    circles = Obstacles(Circle((float(c[0]), float(c[1])), float(r)) for c, r in zip(centres, radii))
    through = float(rng.choice([0.03, 0.3]))
    assert np.array_equal(seen_through_circles(reading, pose, centres, radii, through),
                          seen_through(reading, pose, circles, through))


@pytest.mark.parametrize('seed', SEEDS)
def test_explained_by_belief_is_explained_by_the_seen_and_the_map(seed: int) -> None:
    rng = np.random.default_rng(seed)
    on_map = random_world(rng, int(rng.integers(0, 6)), int(rng.integers(0, 10)))
    seen = random_world(rng, int(rng.integers(0, 6)), int(rng.integers(0, 10)))
    points = rng.uniform(-9.0, 9.0, (int(rng.integers(0, 400)), 2))
    # Points near the segments' ends, where END_SLACK decides.
    for item in on_map + seen:
        if isinstance(item, Segment):
            points = np.concatenate([points, np.array(item.end) + rng.normal(0.0, 0.08, (5, 2))])
    map_obstacles = Obstacles(on_map)
    reference = explained(points, Obstacles(seen), np.zeros((0, 2)), np.zeros(0), EXPLAINED,
                          map_obstacles=map_obstacles)
    believed = Obstacles(on_map + seen)
    assert np.array_equal(explained_by_belief(points, believed, len(map_obstacles.starts)), reference)
    # Obstacles.near with a slack per segment: each segment as near with its own slack alone.
    slack = rng.choice([END_SLACK, 0.0, np.inf], len(believed.starts))
    alone = [Obstacles([s]).near(points, EXPLAINED, None if math.isinf(v) else float(v))
             for s, v in zip(believed.items[believed.n_circles:], slack)]
    circles = Obstacles(believed.items[:believed.n_circles]).near(points, EXPLAINED)
    assert np.array_equal(believed.near(points, EXPLAINED, slack), np.logical_or.reduce([circles, *alone]))


def add_walls_reference(seen: list[Obstacle], starts: FloatArray, ends: FloatArray) -> list[Obstacle]:
    """Perception._add_walls as it was: each piece's candidate walls found anew on the table as it is."""
    seen = list(seen)
    walls = [(k, item) for k, item in enumerate(seen) if isinstance(item, Segment)]
    index = [k for k, _ in walls]
    table = np.array([(item.start, item.end) for _, item in walls], dtype=np.float64).reshape(-1, 2, 2)
    for new in np.stack([starts, ends], axis=1):
        for row in np.flatnonzero(Perception._wall_candidates(new[None], table)[0]):
            a, b = table[row, 0], table[row, 1]
            run = b - a
            length = math.hypot(run[0], run[1])
            if length <= 0.0:
                continue
            unit = run / length
            offset = new - a
            off_line = np.abs(unit[0] * offset[:, 1] - unit[1] * offset[:, 0])
            along = offset @ unit
            if off_line.max() > MERGE_TOLERANCE or along.max() < -MERGE_GAP or along.min() > length + MERGE_GAP:
                continue
            low, high = min(0.0, float(along.min())), max(length, float(along.max()))
            p, q = a + low * unit, a + high * unit
            seen[index[row]] = Segment((float(p[0]), float(p[1])), (float(q[0]), float(q[1])))
            table[row] = (p, q)
            break
        else:
            seen.append(Segment((float(new[0, 0]), float(new[0, 1])), (float(new[1, 0]), float(new[1, 1]))))
            index.append(len(seen) - 1)
            table = np.concatenate([table, new[None]])
    return seen


@pytest.mark.parametrize('seed', range(40))
def test_add_walls_is_the_piece_by_piece_loop(seed: int) -> None:
    rng = np.random.default_rng(seed)
    # Pieces along a few lines (so that they continue each other and believed walls), some off them.
    lines = [(rng.uniform(-5.0, 5.0, 2), rng.uniform(-math.pi, math.pi)) for _ in range(3)]

    def piece() -> FloatArray:
        origin, angle = lines[int(rng.integers(len(lines)))]
        u = np.array([math.cos(angle), math.sin(angle)])
        s = float(rng.uniform(-4.0, 4.0))
        off = np.array([-u[1], u[0]]) * float(rng.choice([0.0, 0.01, 0.2]))
        return np.stack([origin + s * u + off, origin + (s + float(rng.uniform(0.0, 1.0))) * u + off])

    seen: list[Obstacle] = [Circle((0.0, 0.0), 0.5)]
    seen += [Segment(tuple(p[0]), tuple(p[1])) for p in (piece() for _ in range(int(rng.integers(0, 6))))]
    pieces = np.array([piece() for _ in range(int(rng.integers(1, 8)))])
    perception = Perception(LaserSpec(), World((-10.0, -10.0, 10.0, 10.0)))
    perception.seen_items = list(seen)
    perception._add_walls(pieces[:, 0], pieces[:, 1])
    assert perception.seen_items == add_walls_reference(seen, pieces[:, 0], pieces[:, 1])
    # _may_continue: _wall_candidates' verdict for one piece and one wall.
    table = np.array([(s.start, s.end) for s in perception.seen_items if isinstance(s, Segment)]).reshape(-1, 2, 2)
    for new in pieces:
        expected = Perception._wall_candidates(new[None], table)[0]
        assert [Perception._may_continue(new.tolist(), wall.tolist()) for wall in table] == \
            [bool(e) and float(np.hypot(*(w[1] - w[0]))) > 0.0 for e, w in zip(expected, table)]
