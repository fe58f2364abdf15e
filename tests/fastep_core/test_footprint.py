"""A robot's real outline (fastep_core/footprint.py): parsed as Nav2 writes it, checked, placed, and its signed
clearance to circles and walls, one pose or many at once."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fastep_core.footprint import Footprint
from fastep_core.geometry import Circle, Obstacles, Segment

JACKAL = [[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]
BOX = Footprint.parse(JACKAL)


def test_nav2s_string_form_and_a_list_of_pairs_give_the_same_footprint() -> None:
    text = Footprint.parse('[[0.254, 0.215], [-0.254, 0.215], [-0.254, -0.215], [0.254, -0.215]]')
    assert text == BOX and hash(text) == hash(BOX)
    assert Footprint.parse(' [ [.254,0.215],[-0.254 , 2.15e-1],[-0.254,-0.215],[+0.254,-0.215] ] ') == BOX
    assert Footprint.parse(np.array(JACKAL)) == BOX
    assert BOX.vertices.shape == (4, 2) and not BOX.vertices.flags.writeable
    assert BOX.to_list() == JACKAL


def test_radius_is_the_farthest_vertex_and_inscribed_the_nearest_edge() -> None:
    assert BOX.radius == pytest.approx(math.hypot(0.254, 0.215))
    assert BOX.inscribed == pytest.approx(0.215)
    offset = Footprint.parse([[0.5, 0.2], [-0.1, 0.2], [-0.1, -0.2], [0.5, -0.2]])   # base_link near the back
    assert offset.radius == pytest.approx(math.hypot(0.5, 0.2)) and offset.inscribed == pytest.approx(0.1)


def test_clockwise_vertices_are_reordered_counter_clockwise() -> None:
    clockwise = Footprint.parse(JACKAL[::-1])
    assert clockwise == Footprint.parse(JACKAL[::-1][::-1])   # the same outline, the same order
    x, y = clockwise.vertices[:, 0], clockwise.vertices[:, 1]
    assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0.0


@pytest.mark.parametrize('value, words', [
    ('[[0.1, 0.1], [-0.1, 0.1]]', 'at least 3 vertices, got 2'),
    ([[0.1, 0.1], [-0.1, 0.1], [math.nan, 0.0]], r'footprint\[2\] must be finite'),
    ('[[0.1, 0.1], [-0.1, 0.1], [inf, -0.1]]', r'footprint\[2\] must be finite'),
    ([[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]], 'zero area'),
    ([[-1.0, -1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, 1.0]], 'intersects itself'),           # a bow-tie
    ([[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]], 'base_link'),                         # base_link outside
    ([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], 'base_link'),                                     # on a corner
    ([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]], 'repeats a vertex'),
    ("__import__('os').system('true')", 'must be a list of'),                              # no eval
    ('[[0.1, 0.1], [-0.1, 0.1], [-0.1, x]]', "'x' is not a number"),
    ('[[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1, 0.0]]', 'must be a list of'),
    ('[[[0.1, 0.1]], [-0.1, 0.1], [-0.1, -0.1]]', 'must be a list of'),
    ([[0.1, 0.1], [-0.1, 0.1], [True, -0.1]], 'two numbers'),
    ([[0.1, 0.1], [-0.1, 0.1], ['-0.1', -0.1]], 'two numbers'),
    ([[0.1, 0.1], [-0.1, 0.1], [-0.1, 5000.0]], 'more than 1000 m'),
    (0.3, 'must be a list of'),
])
def test_a_bad_footprint_is_one_line_naming_what(value: object, words: str) -> None:
    with pytest.raises(ValueError, match=words) as caught:
        Footprint.parse(value, what='robots[0].footprint' if not isinstance(value, str) else 'footprint')
    assert '\n' not in str(caught.value)
    if not isinstance(value, str):
        assert str(caught.value).startswith('robots[0].footprint')


def test_placed_turns_about_base_link() -> None:
    placed = BOX.placed(1.0, 2.0, math.pi / 2)
    assert placed == pytest.approx(np.array([[0.785, 2.254], [0.785, 1.746], [1.215, 1.746], [1.215, 2.254]]))
    many = BOX.placed(np.array([0.0, 1.0]), np.array([0.0, 2.0]), np.array([0.0, math.pi / 2]))
    assert many.shape == (2, 4, 2) and many[1] == pytest.approx(placed) and many[0] == pytest.approx(BOX.vertices)


def test_clearance_to_circles_is_signed_and_counts_one_inside() -> None:
    obstacles = Obstacles([Circle((1.0, 0.0), 0.1)])
    assert float(BOX.clearance([0.0, 0.0, 0.0], obstacles)) == pytest.approx(1.0 - 0.1 - 0.254)
    assert float(BOX.clearance([0.0, 0.0, math.pi / 2], obstacles)) == pytest.approx(1.0 - 0.1 - 0.215)
    corner = Obstacles([Circle((0.254 + 0.3, 0.215 + 0.4), 0.1)])    # nearest the corner: 0.5 - 0.1
    assert float(BOX.clearance([0.0, 0.0, 0.0], corner)) == pytest.approx(0.4)
    inside = Obstacles([Circle((0.1, 0.0), 0.02)])                   # wholly inside the box
    assert float(BOX.clearance([0.0, 0.0, 0.0], inside)) == pytest.approx(-(0.154 + 0.02))
    crossing = Obstacles([Circle((0.3, 0.0), 0.075)])                # centre outside, disc over the front edge
    assert float(BOX.clearance([0.0, 0.0, 0.0], crossing)) == pytest.approx(0.046 - 0.075)


def test_a_box_touches_a_cylinder_its_022_m_circle_misses() -> None:
    # A cylinder beside the corner: 0.30 m from base_link, clear of a 0.22 m circle, but inside the box's corner.
    cylinder = Obstacles([Circle((0.3 * math.cos(0.7), 0.3 * math.sin(0.7)), 0.05)])
    assert float(cylinder.clearance(np.zeros(2))) - 0.22 > 0.0
    assert float(BOX.clearance([0.0, 0.0, 0.0], cylinder)) < 0.0
    # Turned a quarter of a turn, the cylinder's centre lies beside the box's side, 0.215 m out.
    assert float(BOX.clearance([0.0, 0.0, math.pi / 2], cylinder)) == pytest.approx(
        0.3 * math.cos(0.7) - 0.215 - 0.05)
    # Half a turn round, the (symmetric) box covers its centre again.
    assert float(BOX.clearance([0.0, 0.0, math.pi], cylinder)) < 0.0


def test_clearance_to_walls_is_signed_and_counts_a_wall_through_the_box() -> None:
    beside = Obstacles([Segment((-1.0, 0.5), (1.0, 0.5))])
    assert float(BOX.clearance([0.0, 0.0, 0.0], beside)) == pytest.approx(0.5 - 0.215)
    assert float(BOX.clearance([0.0, 0.0, math.pi / 2], beside)) == pytest.approx(0.5 - 0.254)
    through = Obstacles([Segment((0.0, -1.0), (0.0, 1.0))])          # across the middle: deepest at base_link
    assert float(BOX.clearance([0.0, 0.0, 0.0], through)) == pytest.approx(-0.215)
    poking = Obstacles([Segment((0.2, 0.0), (1.0, 0.0))])            # one end inside, 0.054 m from the front
    assert float(BOX.clearance([0.0, 0.0, 0.0], poking)) == pytest.approx(-0.054)
    within = Obstacles([Segment((-0.05, 0.1), (0.05, 0.1))])         # wholly inside, 0.115 m from the side
    assert float(BOX.clearance([0.0, 0.0, 0.0], within)) == pytest.approx(-0.115)
    diagonal = Obstacles([Segment((0.254 + 0.3, 0.0), (0.0, 0.215 + 0.3))])   # apart, beyond the corner
    assert float(BOX.clearance([0.0, 0.0, 0.0], diagonal)) > 0.0


def test_many_poses_at_once_equal_one_at_a_time() -> None:
    rng = np.random.default_rng(4)
    obstacles = Obstacles([*(Circle((float(x), float(y)), 0.075) for x, y in rng.uniform(-2, 2, (40, 2))),
                           Segment((-2.0, -1.5), (2.0, -1.2)), Segment((1.5, -2.0), (1.7, 2.0))])
    poses = np.column_stack([rng.uniform(-2, 2, (200, 2)), rng.uniform(-math.pi, math.pi, 200)])
    together = BOX.clearance(poses, obstacles)
    alone = np.array([float(BOX.clearance(p, obstacles)) for p in poses])
    assert together.shape == (200,) and np.array_equal(together, alone)
    assert BOX.clearance(poses.reshape(20, 10, 3), obstacles).shape == (20, 10)
    # The box lies between its inscribed and its circumscribed circle.
    centre = obstacles.clearance(poses[:, :2])
    assert (together <= centre - BOX.inscribed + 1e-12).all() and (together >= centre - BOX.radius - 1e-12).all()
    assert np.isinf(BOX.clearance(poses, Obstacles())).all()


def test_overlap_agrees_with_a_dense_sampling_of_the_box() -> None:
    rng = np.random.default_rng(9)
    obstacles = Obstacles([*(Circle((float(x), float(y)), 0.075) for x, y in rng.uniform(-1, 1, (30, 2))),
                           Segment((-1.0, 0.3), (1.0, -0.4))])
    poses = np.column_stack([rng.uniform(-1, 1, (300, 2)), rng.uniform(-math.pi, math.pi, 300)])
    u, w = np.meshgrid(np.linspace(-0.254, 0.254, 41), np.linspace(-0.215, 0.215, 35))
    body = np.column_stack([u.ravel(), w.ravel()])
    c, s = np.cos(poses[:, 2, None]), np.sin(poses[:, 2, None])
    points = np.stack([poses[:, 0, None] + c * body[:, 0] - s * body[:, 1],
                       poses[:, 1, None] + s * body[:, 0] + c * body[:, 1]], axis=-1)
    sampled_hit = (obstacles.clearance(points) < 0.0).any(axis=1)
    value = BOX.clearance(poses, obstacles)
    assert sampled_hit.any() and (~sampled_hit).any()
    assert (value[sampled_hit] < 0.0).all()                     # whatever a sample sees inside, the box overlaps
    assert (value[value > 0.02] > 0.0).all() and not sampled_hit[value > 0.02].any()


def test_a_concave_footprint_leaves_its_notch_free() -> None:
    # An L: a cylinder in the notch is clear of the outline, one in the arm overlaps it.
    ell = Footprint.parse([[-0.3, -0.3], [0.3, -0.3], [0.3, 0.1], [0.1, 0.1], [0.1, 0.3], [-0.3, 0.3]])
    assert float(ell.clearance([0.0, 0.0, 0.0], Obstacles([Circle((0.25, 0.25), 0.05)]))) == pytest.approx(0.1)
    assert float(ell.clearance([0.0, 0.0, 0.0], Obstacles([Circle((0.2, -0.15), 0.05)]))) < 0.0
    assert float(ell.clearance([0.0, 0.0, 0.0], Obstacles([Segment((0.15, 0.15), (0.3, 0.3))]))) == \
        pytest.approx(0.05)
    assert float(ell.clearance([0.0, 0.0, 0.0], Obstacles([Segment((0.2, 0.2), (0.2, -0.2))]))) < 0.0
