"""The /map grid stays bounded (issue "Hardening", item 11).

It was always rasterised at 0.1 m: a 1 km workspace took 4 GB in `fastep-sim --mcap`, a 5 km workspace or
`-p resolution:=1e-4` ended fastep-map in MemoryError. Now the cell size is chosen so that the grid has at most
convert.MAX_GRID_CELLS cells, the same by fastep-map (its default) and fastep-sim --mcap, and a resolution
whose grid would be larger is refused with one line. The runs here are limited to 2 GB of address space.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from rclpy.parameter import Parameter

from fastep_core.geometry import Circle, Segment
from fastep_core.world import World
from fastep_ros.map_server import MapNode
from fastep_testing.graph import ROOT, free_domain, isolated_env, without_dds_noise
from msg_tools import convert
from msg_tools.mcap_io import open_recording

BIG = """\
name: big_{side}
workspace: [0, 0, {side}, {side}]
obstacles:
  - circle: {{center: [500, 500], radius: 20}}
  - segment: {{start: [100, 900], end: [300, 950]}}
robots:
  - name: r1
    model: point_mass
    start: [10, 10]
    goal: [12, 10]
    radius: 0.5
"""
MEMORY_LIMIT = 2048 * 1024 * 1024   # bytes of address space for the child processes below (they peak at 0.9 GB)


def scenario_file(folder: Path, side: int) -> Path:
    path = folder / f'big_{side}.yaml'
    path.write_text(BIG.format(side=side))
    return path


@pytest.mark.parametrize('workspace,expected', [
    ((0, 0, 20, 20), 0.1), ((0, 0, 200, 200), 0.1), ((0, 0, 200.1, 200), 0.2), ((0, 0, 1000, 1000), 0.5),
    ((0, 0, 5000, 5000), 2.5), ((-3e6, 0, 3e6, 1), 2.0), ((0, 0, 1e12, 1e12), 5e8), ((0, 0, 1e6, 0.01), 0.25),
])
def test_the_automatic_resolution_keeps_the_grid_bounded(workspace: tuple[float, ...], expected: float) -> None:
    resolution = convert.grid_resolution(workspace)
    width, height = convert.grid_shape(workspace, resolution)
    assert resolution == expected and width * height <= convert.MAX_GRID_CELLS
    assert resolution == float(f'{resolution:.7g}')   # survives MapMetaData's float32 (occupancy_grid_workspace)


def test_a_resolution_that_would_exceed_the_cap_is_refused() -> None:
    world = World.from_obstacles([0, 0, 200, 200], [])
    assert convert.world_to_occupancy_grid(world, 0.1).info.width == 2000   # the cap's own size is fine
    with pytest.raises(ValueError, match=r'resolution 0.0001 m would make a 2000000 x 2000000 grid, more than '
                                         r'4,000,000 cells; this workspace needs at least 0.1 m'):
        convert.world_to_occupancy_grid(world, 1e-4)


def test_a_1_km_grid_is_rasterised_over_bounding_boxes() -> None:
    world = World.from_obstacles([0, 0, 1000, 1000], [Circle((500.0, 500.0), 20.0),
                                                       Segment((100.0, 900.0), (300.0, 950.0))])
    grid = convert.world_to_occupancy_grid(world)
    info = grid.info
    assert (info.width, info.height, round(info.resolution, 6)) == (2000, 2000, 0.5)
    assert convert.occupancy_grid_workspace(grid) == (0.0, 0.0, 1000.0, 1000.0)
    occupied = sum(1 for v in grid.data if v == 100)
    assert 5000 < occupied < 6000   # the circle: pi 20^2 / 0.25 = 5027 cells, and a 206 m wall of 1 cell
    assert grid.data[1000 * 2000 + 1000] == 100 and grid.data[0] == 0


def test_fastep_sim_mcap_of_a_5_km_workspace_stays_small(tmp_path: Path) -> None:
    out = tmp_path / 'big.mcap'
    scenario = scenario_file(tmp_path, 5000)
    code = (f'import resource, sys; resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_LIMIT}, {MEMORY_LIMIT})); '
            'from msg_tools import sim_cli; sys.exit(sim_cli.main(sys.argv[1:]))')
    result = subprocess.run([sys.executable, '-c', code, str(scenario), '--mcap', str(out)], cwd=ROOT,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    grid = next(open_recording(out).messages(['/map'])).message
    assert (grid.info.width, grid.info.height, round(grid.info.resolution, 6)) == (2000, 2000, 2.5)


def make(context: Any, **params: Any) -> MapNode:
    return MapNode(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in params.items()])


def test_the_map_node_chooses_as_fastep_sim_and_refuses_too_fine_a_grid(context: Any, tmp_path: Path) -> None:
    from fastep_ros.errors import StartupError
    scenario = scenario_file(tmp_path, 1000)
    node = make(context, scenario=str(scenario))
    try:
        info = node.map_msg.info
        assert (info.width, info.height, round(info.resolution, 6)) == (2000, 2000, 0.5)
    finally:
        node.destroy_node()
    with pytest.raises(StartupError, match='parameter resolution 0.0001 m would make a 10000000 x 10000000 grid'):
        make(context, scenario=str(scenario), resolution=1e-4)


@pytest.mark.parametrize('params', [['resolution:=0.0001'], []])
def test_fastep_map_of_a_5_km_workspace_is_one_line_or_a_bounded_grid(tmp_path: Path, params: list[str]) -> None:
    """The node as a process: a resolution over the cap is one line and exit 2 (was MemoryError); the default
    gives a 2000 x 2000 grid within the memory limit (stopped after it published, by a timeout)."""
    scenario = scenario_file(tmp_path, 5000)
    env = isolated_env(free_domain(), tmp_path / 'roslog')
    # Address space, not memory, is limited: glibc reserves up to 64 MB of it per malloc arena, one per thread up
    # to 8 per core, and DDS starts threads; two arenas make the reservation independent of the thread count.
    env['MALLOC_ARENA_MAX'] = '2'
    code = (f'import resource, sys; resource.setrlimit(resource.RLIMIT_AS, ({MEMORY_LIMIT}, {MEMORY_LIMIT})); '
            'from fastep_ros.map_server import main; sys.exit(main(sys.argv[1:]))')
    args = [sys.executable, '-c', code, '--ros-args', '-p', f'scenario:={scenario}']
    for p in params:
        args += ['-p', p]
    log = tmp_path / 'map.log'
    with open(log, 'w') as sink:
        proc = subprocess.Popen(args, env=env, cwd=ROOT, stdout=sink, stderr=subprocess.STDOUT, text=True)
    try:
        deadline = time.monotonic() + 90.0
        while proc.poll() is None and time.monotonic() < deadline and 'cells of' not in log.read_text():
            time.sleep(0.2)
        if proc.poll() is None:   # published (or still starting, on a loaded machine): stop it
            proc.send_signal(signal.SIGINT)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    text = without_dds_noise(log.read_text())
    assert 'Traceback' not in text and 'MemoryError' not in text, text
    if params:
        assert proc.returncode == 2 and text.count('\n') == 1 and 'more than 4,000,000 cells' in text, text
    else:
        assert proc.returncode == 0 and 'map 2000x2000 cells of 2.5 m' in text, text
