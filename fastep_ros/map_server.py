"""fastep-map: publishes a scenario's world once, latched, for every planner and for visualisation.

    fastep-map --ros-args -p scenario:=table2_s2 [-p resolution:=0.1]

Publishes `obstacles` and `map` (relative names: `/obstacles` and `/map` in the root namespace):
visualization_msgs/MarkerArray with a CYLINDER per circle and one LINE_LIST for all segments, and a
nav_msgs/OccupancyGrid covering the workspace (100 in obstacles, 0 free). Both are reliable +
transient-local in the `map` frame, so nodes that start later still receive them.
The grid has at most msg_tools.convert.MAX_GRID_CELLS cells (4 million): `resolution` 0 (the default) is 0.1 m,
or coarser for a workspace larger than 200 m x 200 m (what `fastep-sim --mcap` writes too); a resolution whose
grid would be larger is refused. A bad scenario or resolution logs one line and exits with code 2.
"""

from __future__ import annotations

from typing import Any, Sequence

from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from visualization_msgs.msg import MarkerArray

from fastep_core.errors import FastepError
from fastep_core.scenario import load_scenario
from fastep_ros.common import StartupError, declare, guard_clock, node_main
from fastep_ros.limits import graph_problem
from msg_tools import convert, interface
from msg_tools.interface import offered_qos

__all__ = ['MapNode', 'main']


class MapNode(Node):
    """Latched /obstacles and /map of one scenario."""

    def __init__(self, node_name: str = 'map', **kwargs: Any) -> None:
        super().__init__(node_name, **kwargs)
        guard_clock(self)   # a bad /clock message is ignored, never the end of the node
        source = declare(self, 'scenario', '', 'scenario YAML file or built-in name whose world is published')
        resolution = declare(self, 'resolution', 0.0, 'occupancy grid cell size (m); 0: 0.1 m, coarser for a '
                             f'workspace that would need more than {convert.MAX_GRID_CELLS:,} cells',
                             constraints=f'>= 0, at most {convert.MAX_GRID_CELLS:,} cells')
        thickness = declare(self, 'segment_thickness', 0.0, 'width a wall (segment) is rasterised with in the '
                            'occupancy grid (m); 0 means one cell')
        self.frame_id = declare(self, 'frame_id', interface.MAP_FRAME, 'frame of /obstacles and /map')
        if not source:
            raise StartupError('parameter scenario is required (a YAML file or a built-in name)')
        if resolution < 0.0:
            raise StartupError(f'parameter resolution must be >= 0 (0: automatic), got {resolution:g}')
        try:
            self.scenario = load_scenario(source)
        except FastepError as exc:
            raise StartupError(str(exc)) from None
        problem = graph_problem(self.scenario, robots=False)
        if problem:
            raise StartupError(f'scenario {source!r}: {problem}')
        world = self.scenario.world
        try:
            resolution = convert.grid_resolution(world.workspace, resolution or None)
        except ValueError as exc:
            raise StartupError(f'parameter {exc}') from None
        stamp = self.get_clock().now().to_msg()
        self.obstacles_msg = convert.obstacles_to_marker_array(world.obstacle_list, stamp, self.frame_id)
        self.map_msg = convert.world_to_occupancy_grid(world, resolution, stamp, self.frame_id,
                                                       thickness if thickness > 0.0 else None)
        # Relative names: a map node started in a namespace publishes there; in the root one they are the shared
        # /obstacles and /map.
        self.obstacles_pub = self.create_publisher(MarkerArray, interface.OBSTACLES.lstrip('/'),
                                                   offered_qos(interface.OBSTACLES))
        self.map_pub = self.create_publisher(OccupancyGrid, interface.MAP.lstrip('/'), offered_qos(interface.MAP))
        self.obstacles_pub.publish(self.obstacles_msg)
        self.map_pub.publish(self.map_msg)
        info = self.map_msg.info
        self.get_logger().info(f'scenario {self.scenario.name}: {len(world.obstacle_list)} obstacles, '
                               f'map {info.width}x{info.height} cells of {info.resolution:g} m')


def main(args: Sequence[str] | None = None) -> int:
    return node_main('fastep-map', MapNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
