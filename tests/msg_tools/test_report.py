"""fastep-report: the metrics measured from a recording equal what the simulator measured during the run."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from msg_tools import report, sim_cli
from msg_tools.mcap_io import copy_recording, open_recording

ROOT = Path(__file__).resolve().parents[2]
BAGS = ROOT / 'bags'
BUILTINS = ('case_study_1', 'case_study_2', 'application', 'table2_s1', 'table2_s2', 'table2_s3')

# Two point masses crossing near a circle and a wall: obstacle clearance and robot gaps both matter.
SCENARIO = """\
name: crossing_wall
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [10, 10], radius: 1.5}
  - segment: {start: [4, 15], end: [8, 17]}
robots:
  - name: r1
    model: point_mass
    start: [2, 10]
    goal: [18, 10.5]
    radius: 0.5
  - name: r2
    model: point_mass
    start: [10, 2]
    goal: [10.5, 18]
    radius: 0.4
planner: {alpha1: 0.5, alpha2: 0.5, max_speed: 2.0}
"""


@pytest.fixture(scope='module')
def run(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    folder = tmp_path_factory.mktemp('report')
    (folder / 'scenario.yaml').write_text(SCENARIO)
    mcap = folder / 'run.mcap'
    assert sim_cli.main([str(folder / 'scenario.yaml'), '--seed', '3', '--mcap', str(mcap),
                     '--json', str(folder / 'run.json')]) == 0
    return {'folder': folder, 'mcap': mcap, 'sim': json.loads((folder / 'run.json').read_text())['runs'][0]}


def test_report_matches_the_simulated_run(run: dict[str, Any], capsys: pytest.CaptureFixture[str]) -> None:
    out = run['folder'] / 'out'
    assert report.main([str(run['mcap']), '--out', str(out)]) == 0
    printed = capsys.readouterr().out
    doc = json.loads((out / 'report.json').read_text())
    assert doc['scenario'] == 'crossing_wall' and doc['algorithm'] == 'fastep' and not doc['truncated']
    assert doc['obstacles'] == 2 and doc['workspace'] == [0, 0, 20, 20]
    sim = {r['name']: r for r in run['sim']['robots']}
    assert [r['name'] for r in doc['robots']] == ['r1', 'r2']
    for row in doc['robots']:
        expected = sim[row['name']]
        assert row['reached'] == expected['reached']
        assert row['path_length'] == pytest.approx(expected['path_length'], rel=0.01)
        if expected['reached']:
            assert row['time_to_goal'] == pytest.approx(expected['sim_time'], abs=1e-6)
        assert row['activations'] == expected['activations'] and row['activations_source'] == 'status'
        assert row['radius_source'] == 'metadata'
        # The simulator's min_clearance is over obstacles and the other robots, at the same positions.
        assert min(row['min_clearance'], row['min_robot_gap']) == pytest.approx(expected['min_clearance'], abs=1e-6)
        assert row['collided'] == expected['collided']
        assert f'{row["name"]}: arrived' in printed or not row['reached']
    assert {r['radius'] for r in doc['robots']} == {0.5, 0.4}
    for name in ('paths.png', 'cost.png', 'velocity.png'):
        assert (out / name).read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


def test_report_figures_show_the_recorded_odometry_and_series(run: dict[str, Any]) -> None:
    recorded = report.load_run(open_recording(run['mcap']))
    figures = report.figures(recorded)
    assert list(figures) == ['paths.png', 'cost.png', 'velocity.png']
    paths = figures['paths.png'].axes[0]
    assert paths.get_title() == 'crossing_wall: FAStep-Kinematic'
    assert len(paths.patches) == 1                                   # the circle; the wall is a line
    for name, robot in recorded.robots.items():
        (line,) = [line for line in paths.get_lines() if line.get_label().startswith(f'{name} (')]
        assert np.column_stack([line.get_xdata(), line.get_ydata()]).tolist() == [list(r[1:3]) for r in robot.odom]
    costs = figures['cost.png'].axes[0].get_lines()
    assert [line.get_label() for line in costs] == ['r1', 'r2']
    assert costs[0].get_xdata()[0] == pytest.approx(recorded.robots['r1'].cost[0][0] - recorded.t0)
    assert [ax.get_ylabel() for ax in figures['velocity.png'].axes] == ['r1: cmd_vel', 'r2: cmd_vel']


def test_report_without_metadata_uses_status_radius(run: dict[str, Any], tmp_path: Path) -> None:
    """A live recording has no `fastep` metadata unless fastep-record knew the scenario."""
    stripped = tmp_path / 'live_like.mcap'
    recording = open_recording(run['mcap'])
    recording.metadata_records.clear()   # copy_recording copies every metadata record
    copy_recording(recording, stripped)
    doc, files = report.write_report(stripped, tmp_path / 'out', radius=0.3, figures=False)
    assert [f.name for f in files] == ['report.json']
    assert doc['scenario'] == '' and doc['algorithm'] == 'fastep'  # the algorithm is in the status values
    assert {r['radius_source'] for r in doc['robots']} == {'status'}


def test_report_of_a_truncated_file(run: dict[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    chunked = tmp_path / 'chunked.mcap'
    copy_recording(open_recording(run['mcap']), chunked, chunk_size=8192)
    data = chunked.read_bytes()
    cut = tmp_path / 'cut.mcap'
    cut.write_bytes(data[:len(data) // 2])
    assert report.main([str(cut), '--out', str(tmp_path / 'cut_report'), '--no-figures']) == 0
    err = capsys.readouterr().err
    assert err.startswith('fastep-report: warning:') and 'recovered' in err and err.count('\n') == 1
    doc = json.loads((tmp_path / 'cut_report' / 'report.json').read_text())
    assert doc['truncated'] and doc['messages'] > 0
    assert not all(r['reached'] for r in doc['robots'])  # the arrivals were in the lost half

    nothing = tmp_path / 'nothing.mcap'
    nothing.write_bytes(data[:200])
    garbage = tmp_path / 'garbage.mcap'
    garbage.write_text('{"not": "mcap"}\n')
    for path in (nothing, garbage, tmp_path / 'missing.mcap'):
        assert report.main([str(path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith('fastep-report: error:') and err.count('\n') == 1 and 'Traceback' not in err


@pytest.mark.parametrize('name', BUILTINS)
def test_example_bags(name: str) -> None:
    """bags/ holds one small recording per built-in scenario (see bags/README.md)."""
    path = BAGS / f'{name}.mcap'
    assert path.is_file(), f'missing {path}: regenerate with fastep-sim {name} --mcap {path}'
    assert path.stat().st_size < 2 * 1024 * 1024
    recording = open_recording(path)
    assert not recording.truncated and recording.metadata['fastep']['scenario'] == name
    assert name in (BAGS / 'README.md').read_text()




def test_a_figure_that_cannot_be_drawn_leaves_no_figure_open(run: dict[str, Any], monkeypatch: pytest.MonkeyPatch,
                                                             tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    from msg_tools import plots

    def broken(*_: Any) -> None:
        raise ValueError('cannot draw')

    recorded = report.load_run(open_recording(run['mcap']))
    plt.close('all')
    monkeypatch.setattr(plots, 'velocity_figure', broken)
    with pytest.raises(ValueError, match='cannot draw'):
        report.write_figures(recorded, tmp_path)
    assert plt.get_fignums() == []          # the paths and cost figures drawn before it were closed
