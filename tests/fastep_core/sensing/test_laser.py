"""Tests for fastep_core.sensing.laser: exact ranges against hand-computed geometry, LaserScan semantics, noise."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from fastep_core.sensing.laser import LaserSpec, beam_angles, cast, fan_hits, hit_distances, main, scan


def test_circle_straight_ahead() -> None:
    # Beam along +x from the origin, circle at (5, 0) radius 1: the near surface at 4.
    assert cast((0, 0), [0.0], 10.0, [(5.0, 0.0)], [1.0])[0] == 4.0


def test_circle_behind_is_not_seen_and_inside_reads_zero() -> None:
    assert cast((0, 0), [0.0], 10.0, [(-5.0, 0.0)], [1.0])[0] == math.inf
    np.testing.assert_array_equal(cast((5, 0), [0.0, 2.0], 10.0, [(5.0, 0.0)], [1.0]), [0.0, 0.0])


def test_beam_tangent_to_a_circle_is_a_hit() -> None:
    # Circle at (5, 1) radius 1 touches the x axis at (5, 0): discriminant exactly 0.
    assert cast((0, 0), [0.0], 10.0, [(5.0, 1.0)], [1.0])[0] == 5.0
    assert cast((0, 0), [0.0], 10.0, [(5.0, 1.0 + 1e-9)], [1.0])[0] == math.inf


def test_segment_at_an_angle() -> None:
    # The wall x + y = 4 (from (4, 0) to (0, 4)); the 45-degree beam meets it at (2, 2): range 2 sqrt 2.
    got = cast((0, 0), [math.pi / 4], 10.0, starts=[(4.0, 0.0)], ends=[(0.0, 4.0)])[0]
    assert got == pytest.approx(2.0 * math.sqrt(2.0), abs=1e-12)
    # Vertical wall x = 3 from y = -1 to y = 1: the beam at angle a hits at 3 / cos a while |3 tan a| <= 1.
    angles = np.array([0.0, 0.2, 0.3, -0.3, 0.4])
    got = cast((0, 0), angles, 10.0, starts=[(3.0, -1.0)], ends=[(3.0, 1.0)])
    want = np.where(np.abs(3 * np.tan(angles)) <= 1.0, 3.0 / np.cos(angles), np.inf)
    np.testing.assert_allclose(got, want, rtol=1e-12)


def test_beam_along_a_segment_hits_its_near_end() -> None:
    assert cast((0, 0), [0.0], 10.0, starts=[(6.0, 0.0)], ends=[(3.0, 0.0)])[0] == 3.0
    assert cast((4, 0), [0.0], 10.0, starts=[(6.0, 0.0)], ends=[(3.0, 0.0)])[0] == 0.0


def test_the_nearest_surface_wins_and_range_max_cuts() -> None:
    ranges = cast((0, 0), [0.0], 10.0, [(5.0, 0.0), (8.0, 0.0)], [1.0, 1.0], [(2.0, -1.0)], [(2.0, 1.0)])
    assert ranges[0] == 2.0
    assert cast((0, 0), [0.0], 3.9, [(5.0, 0.0)], [1.0])[0] == math.inf
    assert cast((0, 0), [0.0], 4.0, [(5.0, 0.0)], [1.0])[0] == 4.0


def test_an_empty_world_reads_inf_everywhere() -> None:
    result = scan(LaserSpec(range=5.0, beams=36, noise=0.0), (1.0, 2.0, 0.3))
    assert np.isinf(result.ranges).all() and len(result.ranges) == 36


def test_beam_placement() -> None:
    full = LaserSpec(beams=360, noise=0.0)
    angle_min, increment, angles = beam_angles(full)
    assert angle_min == -math.pi and increment == pytest.approx(math.tau / 360)
    assert angles[-1] == pytest.approx(math.pi - increment)      # no beam twice: -pi and +pi are one direction
    assert np.any(angles == 0.0)
    part = LaserSpec(fov=math.pi / 2, beams=5, noise=0.0)
    _, increment, angles = beam_angles(part)
    np.testing.assert_allclose(angles, np.linspace(-math.pi / 4, math.pi / 4, 5))
    assert beam_angles(LaserSpec(beams=1, noise=0.0))[2].tolist() == [0.0]
    assert LaserSpec(fov=6.2832).full_turn and not LaserSpec(fov=6.2).full_turn
    s = scan(part, (0, 0, 0))
    assert (s.angle_min, s.angle_max, s.angle_increment) == pytest.approx((-math.pi / 4, math.pi / 4, math.pi / 8))
    assert s.range_min == 0.0 and s.range_max == part.range


def test_the_fan_turns_with_the_heading() -> None:
    spec = LaserSpec(fov=math.pi / 2, beams=3, noise=0.0)
    # Heading +y: the middle beam looks up at a circle at (0, 5), the left beam (+45 deg) looks up-left.
    ranges = scan(spec, (0.0, 0.0, math.pi / 2), circles=[(0.0, 5.0)], radii=[1.0]).ranges
    assert ranges[1] == pytest.approx(4.0) and np.isinf(ranges[0]) and np.isinf(ranges[2])


def world() -> dict[str, Any]:
    rng = np.random.default_rng(0)
    return {'circles': rng.uniform(-8, 8, (20, 2)), 'radii': rng.uniform(0.2, 1.0, 20),
            'starts': rng.uniform(-8, 8, (5, 2)), 'ends': rng.uniform(-8, 8, (5, 2))}


def test_noise_is_deterministic_per_seed_and_never_turns_misses_into_hits() -> None:
    spec = LaserSpec(range=6.0, beams=720, noise=0.05)
    first = scan(spec, (0.0, 0.0, 0.0), np.random.default_rng(1), **world())
    again = scan(spec, (0.0, 0.0, 0.0), np.random.default_rng(1), **world())
    other = scan(spec, (0.0, 0.0, 0.0), np.random.default_rng(2), **world())
    truth = scan(LaserSpec(range=6.0, beams=720, noise=0.0), (0.0, 0.0, 0.0), **world())
    np.testing.assert_array_equal(first.ranges, again.ranges)
    assert not np.array_equal(first.ranges, other.ranges)
    np.testing.assert_array_equal(np.isinf(first.ranges), np.isinf(truth.ranges))
    hits = np.isfinite(first.ranges)
    assert hits.sum() > 100
    assert (first.ranges[hits] >= 0.0).all() and (first.ranges[hits] <= 6.0).all()


def test_noise_statistics() -> None:
    spec = LaserSpec(range=20.0, beams=10_000, noise=0.1)
    result = scan(spec, (0.0, 0.0, 0.0), np.random.default_rng(5), circles=[(0.0, 0.0)], radii=[10.0])
    # Inside a circle every beam truly reads 0: with noise, never below 0 (clipped), about half exactly 0.
    assert (result.ranges >= 0.0).all() and result.ranges.max() < 0.5
    assert 0.4 < (result.ranges == 0.0).mean() < 0.6
    # A long wall x = 5: every true range is 5 / cos(angle) where the beam meets it.
    result = scan(spec, (0.0, 0.0, 0.0), np.random.default_rng(5), starts=[(5.0, -100.0)], ends=[(5.0, 100.0)])
    errors = result.ranges[np.isfinite(result.ranges)] - 5.0 / np.cos(result.angles()[np.isfinite(result.ranges)])
    assert len(errors) > 3000
    assert abs(errors.mean()) < 0.01 and 0.09 < errors.std() < 0.11


def test_bad_specs_are_refused() -> None:
    for bad in ({'range': 0.0}, {'fov': 0.0}, {'fov': 7.0}, {'beams': 0}, {'beams': 2.5}, {'noise': -1.0}):
        with pytest.raises(ValueError):
            LaserSpec(**bad)  # type: ignore[arg-type]  # deliberately wrong
    with pytest.raises(ValueError, match='needs a Generator'):
        scan(LaserSpec(noise=0.1), (0, 0, 0))


def test_main_prints_one_scan(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(['--beams', '8', '--noise', '0']) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith('angle_min') and len(lines) == 9
    assert lines[5].split() == ['0.00', 'deg', '4.000']


def _random_world(rng: np.random.Generator, grid: bool) -> dict[str, Any]:
    """Circles and segments; on a grid (integer coordinates, axis-aligned walls) scanners sit on their lines."""
    n_c, n_s = int(rng.integers(0, 20)), int(rng.integers(0, 20))
    if grid:
        starts = rng.integers(-5, 5, (n_s, 2)).astype(float)
        ends = starts.copy()
        ends[np.arange(n_s), rng.integers(0, 2, n_s)] += rng.integers(-3, 4, n_s)
        return {'circles': rng.integers(-5, 5, (n_c, 2)).astype(float), 'radii': rng.integers(0, 3, n_c) * 1.0,
                'starts': starts, 'ends': ends}
    starts = rng.uniform(-10, 10, (n_s, 2))
    return {'circles': rng.uniform(-10, 10, (n_c, 2)), 'radii': rng.uniform(-0.5, 2.0, n_c), 'starts': starts,
            'ends': starts + rng.uniform(-4, 4, (n_s, 2))}


def test_a_scan_reads_what_casting_every_beam_on_every_obstacle_reads_bit_for_bit() -> None:
    # scan() casts each obstacle on the beams within its angle only (fan_hits): the ranges must be cast()'s own,
    # bit for bit (even a zero's sign), from anywhere: on a wall's line, on a wall, in or on a circle.
    rng = np.random.default_rng(3)
    for trial in range(300):
        world = _random_world(rng, grid=trial % 2 == 1)
        origin = rng.integers(-5, 5, 2) * 1.0 if trial % 2 else rng.uniform(-6, 6, 2)
        if trial % 3 == 0 and len(world['starts']):
            origin = world['starts'][0] + rng.uniform(0, 1) * (world['ends'][0] - world['starts'][0])
        spec = LaserSpec(range=float(rng.choice([3.0, 10.0])), fov=float(rng.choice([math.tau, math.pi, 0.5])),
                         beams=int(rng.choice([1, 7, 90, 360])), noise=0.0)
        heading = float(rng.choice([0.0, math.pi / 2, rng.uniform(-7, 7)]))
        _, _, relative = beam_angles(spec)
        want = cast(origin, heading + relative, spec.range, **world)
        got = scan(spec, (origin[0], origin[1], heading), **world).ranges
        assert got.tobytes() == want.tobytes()


def test_fan_hits_are_hit_distances_where_a_beam_can_meet_the_obstacle() -> None:
    rng = np.random.default_rng(4)
    for trial in range(200):
        world = _random_world(rng, grid=trial % 2 == 1)
        origin = rng.uniform(-6, 6, 2)
        heading, angle_min, increment, beams = rng.uniform(-4, 4), -math.pi, math.tau / 360, 360
        full = hit_distances(origin, heading + (angle_min + increment * np.arange(beams, dtype=float)), **world)
        beam, obstacle, distance = fan_hits(origin, heading, angle_min, increment, beams, **world)
        assert len(set(zip(beam.tolist(), obstacle.tolist()))) == len(beam)           # each pair once
        rebuilt = np.full_like(full, np.inf)
        rebuilt[beam, obstacle] = distance
        assert rebuilt.tobytes() == full.tobytes()
        if full.size:
            assert len(beam) < 0.5 * full.size or len(full[0]) < 3                    # and far fewer pairs
