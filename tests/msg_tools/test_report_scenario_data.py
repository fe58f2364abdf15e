"""fastep-report on a recording's true world (metadata `scenario_data`) and on odometry that does not decode.

- scenario_data is held to the limits of a scenario file (fastep_core.bounded_yaml: MAX_BYTES, MAX_DEPTH):
  60,000 movers (6 MB) ended in MemoryError under a 1.5 GB address-space cap, 200,000 `[` in a RecursionError
  traceback. Beyond the limits, not JSON or not a scenario: one warning line saying it was ignored and why, and
  the run is judged against its /obstacles (as a scenario_data that does not parse always was, silently).
- Within the limits, movers and still obstacles are judged in chunks: 8,000 movers (or 15,000 still
  obstacles) x 6,000 odometry samples took one (samples x movers x 2) (or samples x obstacles) array, and
  MemoryError under the cap; now a few MiB at a time, the same numbers.
- A robot none of whose odometry decoded has no path length (null, `path none (no odometry decoded)`), not 0 m.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from nav_msgs.msg import Odometry

from fastep_core.dynamic_world import Motion, Movers, ObstacleSpec
from fastep_core.geometry import Circle, Obstacles, Segment
from fastep_core.metrics import trajectory_margins
from fastep_core.scenario import parse_scenario
from fastep_core.world import World
from msg_tools import convert, report
from msg_tools.interface import SCENARIO_DATA, scenario_metadata
from msg_tools.mcap_io import McapWriter

ROOT = Path(__file__).resolve().parents[2]
MEMORY_LIMIT = 1536 * 1024 * 1024   # bytes of address space for the fastep-report processes below
CUT_ODOM = b'\x00\x01\x00\x00' + bytes(26)   # CDR cut off inside the header: no odometry decodes from it
NEAR = {'circle': {'center': [5.0, 3.0], 'radius': 0.2}, 'motion': {'waypoints': [[5.5, 3.0]], 'speed': 0.5}}
ROBOT = {'name': 'r1', 'model': 'point_mass', 'start': [1.0, 1.0], 'goal': [9.0, 9.0], 'radius': 0.5}
LIMIT_LINE = 'more than a scenario file may have (1048576 bytes, 1 MiB)'


def odometry(x: float, y: float, t: float) -> Odometry:
    msg = Odometry()
    msg.header.stamp.sec, msg.header.stamp.nanosec = int(t), int(round((t % 1.0) * 1e9))
    msg.pose.pose.position.x, msg.pose.pose.position.y = float(x), float(y)
    msg.pose.pose.orientation.w = 1.0
    return msg


def track(samples: int) -> np.ndarray:
    """Rows (t, x, y): r1 from (1, 1) to (9, 9) in samples steps of 0.1 s (stamps and log times alike)."""
    t = 0.1 * np.arange(1, samples + 1)
    along = 8.0 * np.arange(samples) / samples
    return np.column_stack([t, 1.0 + along, 1.0 + along])


def scenario(movers: int, still: int = 0) -> dict[str, Any]:
    """A v2 scenario: r1, one mover (NEAR) 1.4 m beside its diagonal, movers - 1 more and `still` circles that
    are not on the map, all 90 m and further away."""
    far = [{'circle': {'center': [100.0 + k % 300, 100.0 + k // 300], 'radius': 0.2},
            'motion': {'waypoints': [[100.5 + k % 300, 100.0 + k // 300]], 'speed': 0.5}} for k in range(movers - 1)]
    unknown = [{'circle': {'center': [100.0 + k % 300, 400.0 + k // 300], 'radius': 0.2}, 'known': False}
               for k in range(still)]
    return {'name': 'movers', 'workspace': [0, 0, 1000, 1000], 'obstacles': [NEAR, *far, *unknown],
            'robots': [ROBOT]}


def recording(path: Path, meta: dict[str, str], samples: int = 50, odom: bool = True) -> Path:
    """r1 driving its diagonal among one still circle on /obstacles, the metadata `meta` (radius 0.5)."""
    with McapWriter(path) as w:
        w.add_metadata('fastep', {'robots': 'r1', 'radius/r1': '0.5', **meta})
        world = World.from_obstacles([0, 0, 10, 10], [Circle((8.0, 2.0), 1.0)])
        w.write('/obstacles', convert.obstacles_to_marker_array(world.obstacle_list), 0)
        w.write('/r1/goal_pose', convert.point_to_pose_stamped((9.0, 9.0)), 0)
        for t, x, y in track(samples):
            if odom:
                w.write('/r1/odom', odometry(x, y, t), int(round(t * 1e9)))
            else:
                w.write('/r1/odom', CUT_ODOM, int(round(t * 1e9)), type_name='nav_msgs/msg/Odometry')
    return path


def run_report(path: Path, capsys: pytest.CaptureFixture[str]) -> tuple[int, list[str], list[str], Any]:
    out = path.with_suffix('')
    code = report.main([str(path), '--out', str(out), '--no-figures'])
    captured = capsys.readouterr()
    doc = json.loads((out / 'report.json').read_text()) if code == 0 else None
    return code, captured.out.splitlines(), captured.err.splitlines(), doc


def limited_report(path: Path) -> subprocess.CompletedProcess[str]:
    """fastep-report --no-figures on path in a process of at most MEMORY_LIMIT bytes of address space."""
    code = (f'import resource, sys; resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_LIMIT}, {MEMORY_LIMIT})); '
            'from msg_tools.report import main; sys.exit(main(sys.argv[1:]))')
    # Address space, not memory, is limited: keep glibc's per-thread arenas and OpenBLAS's buffers out of it.
    env = {**os.environ, 'MALLOC_ARENA_MAX': '2', 'OPENBLAS_NUM_THREADS': '1', 'OMP_NUM_THREADS': '1'}
    return subprocess.run([sys.executable, '-c', code, str(path), '--out', str(path.with_suffix('')),
                           '--no-figures'], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)


def expected_clearance(samples: int) -> float:
    """r1's margin in the true world of scenario(): to NEAR (the other movers are 90 m away and more)."""
    near = Movers([Circle((5.0, 3.0), 0.2)], [Motion(((5.5, 3.0),), 0.5)])
    return float(trajectory_margins([track(samples)], [0.5], Obstacles(), near).obstacles[0])


# ----------------------------------------------------------------------------------------------- item 1: memory

def test_a_scenario_data_beyond_a_scenario_files_size_is_ignored_in_one_line(tmp_path: Path) -> None:
    """60,000 movers (6 MB of JSON) x 2,000 samples: MemoryError under 1.5 GB before; now refused unparsed."""
    text = json.dumps(scenario(60_000), separators=(',', ':'))
    path = recording(tmp_path / 'huge.mcap', {SCENARIO_DATA: text}, samples=2000)
    result = limited_report(path)
    assert result.returncode == 0, result.stderr[-2000:]
    (line,) = result.stderr.splitlines()
    assert line == (f'fastep-report: warning: {SCENARIO_DATA} in the metadata ignored (the run is judged against '
                    f'its /obstacles), it is not a scenario: it has {len(text)} bytes, {LIMIT_LINE}')
    doc = json.loads((path.with_suffix('') / 'report.json').read_text())
    # judged against /obstacles: the circle of radius 1 at (8, 2), 6 / sqrt(2) m from the diagonal
    assert doc['robots'][0]['min_clearance'] == pytest.approx(6.0 / np.sqrt(2.0) - 1.0 - 0.5, abs=0.01)


@pytest.mark.parametrize('movers,still', [(8000, 0), (1, 15_000)])
def test_many_movers_or_obstacles_are_judged_in_bounded_memory(tmp_path: Path, movers: int, still: int) -> None:
    """8,000 movers or 15,000 still obstacles (within 1 MiB) x 6,000 samples: a (6000 x 8000 x 2) or
    (6000 x 15000) array and MemoryError under 1.5 GB before; now judged in chunks, with the same margin as
    fastep_core.metrics measures."""
    meta = scenario_metadata(parse_scenario(scenario(movers, still)))
    assert len(meta[SCENARIO_DATA]) < 1024 * 1024
    path = recording(tmp_path / 'movers.mcap', meta, samples=6000)
    result = limited_report(path)
    assert result.returncode == 0 and result.stderr == '', result.stderr[-2000:]
    doc = json.loads((path.with_suffix('') / 'report.json').read_text())
    assert doc['robots'][0]['min_clearance'] == pytest.approx(expected_clearance(6000), abs=1e-6)


def test_judge_measures_what_trajectory_margins_measures_in_any_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    """Chunks of samples and groups of movers (tiny here: 1 to 2 movers, 1 to 9 samples at a time) change no number:
    still circles and walls, movers with 1 to 4 waypoints, two robots on their own clocks."""
    rng = np.random.default_rng(5)
    specs = [ObstacleSpec(Circle((float(x), float(y)), 0.3)) for x, y in rng.uniform(0, 10, (5, 2))]
    specs += [ObstacleSpec(Segment((1.0, 9.0), (4.0, 9.5)))]
    movers = []
    for k in range(7):
        centre = rng.uniform(0, 10, 2)
        points = tuple((float(x), float(y)) for x, y in rng.uniform(0, 10, (1 + k % 4, 2)))
        movers.append(ObstacleSpec(Circle((float(centre[0]), float(centre[1])), 0.25), Motion(points, 0.7)))
    specs += movers
    tracks = [np.column_stack([np.sort(rng.uniform(0, 20, n)), rng.uniform(0, 10, (n, 2))]) for n in (37, 23)]
    radii = [0.5, 0.4]
    still = Obstacles(s.shape for s in specs if s.motion is None)
    all_movers = Movers([s.shape for s in movers if isinstance(s.shape, Circle)],
                        [s.motion for s in movers if s.motion is not None])
    expected = trajectory_margins(tracks, radii, still, all_movers)
    for elements in (9, 40, 1 << 20):
        monkeypatch.setattr(report, 'JUDGE_ELEMENTS', elements)
        got = report.judge(tracks, radii, still, specs)
        assert np.array_equal(got.obstacles, expected.obstacles) and np.array_equal(got.robots, expected.robots)


# ----------------------------------------------------------------------------------------------- items 2 and 4

@pytest.mark.parametrize('text,why', [
    ('[' * 200_000, 'collections nested deeper than a scenario file may have them (64 levels)'),
    ('[' * 65 + ']' * 65, 'collections nested deeper than a scenario file may have them (64 levels)'),
    ('{"a":' * 65 + '1' + '}' * 65, 'collections nested deeper than a scenario file may have them (64 levels)'),
    ('not json', 'not JSON: Expecting value: line 1 column 1 (char 0)'),
    ('{"workspace": [0, 0, 10, 10', 'not JSON: Expecting'),
    ('1' * 5000, 'not JSON: Exceeds the limit (4300 digits) for integer string conversion'),
    ('{"workspace": [0, 0, 10, 10]}', "scenario 'scenario_data': missing required top-level key 'robots'"),
    ('[]', "scenario 'scenario_data': "),
])
def test_a_scenario_data_that_is_not_a_scenario_is_ignored_with_one_warning(
        tmp_path: Path, text: str, why: str, capsys: pytest.CaptureFixture[str]) -> None:
    """As before, the report goes on without it (judged against /obstacles); now one line says so and why.
    200,000 `[` were a RecursionError traceback, the others silently ignored."""
    path = recording(tmp_path / 'bad.mcap', {SCENARIO_DATA: text})
    code, out, err, doc = run_report(path, capsys)
    assert code == 0 and len(err) == 1
    prefix = (f'fastep-report: warning: {SCENARIO_DATA} in the metadata ignored (the run is judged against its '
              f'/obstacles), it is not a scenario: ')
    assert err[0].startswith(prefix + why) and len(err[0]) < 500, err[0]
    _, reference_out, reference_err, reference = run_report(recording(tmp_path / 'v1.mcap', {}), capsys)
    assert reference_err == [] and reference['robots'] == doc['robots']   # the same report as without it
    assert out[:-1] == reference_out[:-1] and out[0].startswith('r1: NOT arrived, path 11.09 m,')


def test_a_valid_scenario_data_is_the_truth_without_a_warning(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    """The mover beside the path (not on /obstacles) is what r1 came closest to."""
    path = recording(tmp_path / 'v2.mcap', scenario_metadata(parse_scenario(scenario(3))))
    code, _, err, doc = run_report(path, capsys)
    assert code == 0 and err == []
    assert doc['robots'][0]['min_clearance'] == pytest.approx(expected_clearance(50), abs=1e-6)


def test_read_scenario_data_states_the_limits_of_a_scenario_file() -> None:
    from fastep_core import bounded_yaml

    good = json.dumps(scenario(2))
    assert report.read_scenario_data(good)[0] is not None and report.read_scenario_data(good)[1] == ''
    padded = good[:-1] + ', "description": "' + 'x' * (bounded_yaml.MAX_BYTES - len(good)) + '"}'
    assert report.read_scenario_data(padded) == (None, f'it has {len(padded)} bytes, {LIMIT_LINE}')
    nested = '{"x_deep": ' + '[' * 63 + ']' * 63 + ', ' + good[1:]   # 64 levels: a scenario file's most
    assert report.read_scenario_data(nested)[1] == ''


# ----------------------------------------------------------------------------------------------- item 3

def test_a_robot_whose_odometry_all_failed_to_decode_has_no_path_length(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    path = recording(tmp_path / 'cut.mcap', {}, odom=False)
    code, out, err, doc = run_report(path, capsys)
    row = doc['robots'][0]
    assert code == 0 and row['odom_messages'] == 0 and row['path_length'] is None
    assert out[0] == 'r1: NOT arrived, path none (no odometry decoded), time -, min clearance -, activations 0'
    assert len(err) == 1 and '50 message(s) on /r1/odom left out (CdrError' in err[0]


def test_one_decoded_odometry_is_a_path_of_0_m(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = recording(tmp_path / 'one.mcap', {}, samples=1)
    code, out, _, doc = run_report(path, capsys)
    assert code == 0 and doc['robots'][0]['path_length'] == 0.0 and ', path 0.00 m,' in out[0]
