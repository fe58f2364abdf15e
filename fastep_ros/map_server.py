"""fastep-map: publishes a scenario's world once, latched, for every planner and for visualisation.

    fastep-map --ros-args -p scenario:=table2_s2 [-p resolution:=0.1] [-p seed:=0]

Publishes `obstacles` (visualization_msgs/MarkerArray) and `map` (nav_msgs/OccupancyGrid, 100 in obstacles,
0 free) in the root namespace, reliable + transient-local in the `map` frame, so nodes that start later still
receive them. The grid has at most msg_tools.convert.MAX_GRID_CELLS cells: `resolution` 0 (the default) is 0.1 m
or coarser for a large workspace; a finer one that would exceed it is refused. A bad scenario or resolution logs
one line and exits with code 2.

A format-v2 world is published as the robots' map knows it, as fastep-sim gives its planners: known still
obstacles only, misplaced ones where the map puts them (errors drawn from `seed`); the known movers go on
`/movers` `movers_rate_hz` times a second of the node clock. Nodes that need the truth (a plant's scanner)
compute it from the scenario at their own clock's time.
"""

from __future__ import annotations

from typing import Any, Sequence

from nav_msgs.msg import OccupancyGrid
from rclpy.node import Node
from visualization_msgs.msg import MarkerArray

from fastep_core.dynamic_world import DynamicWorld, map_generator
from fastep_core.errors import FastepError
from fastep_core.scenario import load_scenario
from fastep_ros.common import StartupError, declare, guard_clock, node_main, quiet_at_stop
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
        resolution = declare(self, 'resolution', 0.0, 'occupancy grid cell size; 0: 0.1 m, coarser for a '
                             f'workspace that would need more than {convert.MAX_GRID_CELLS:,} cells',
                             constraints=f'>= 0, at most {convert.MAX_GRID_CELLS:,} cells', unit='m')
        thickness = declare(self, 'segment_thickness', 0.0, 'width a wall (segment) is rasterised with in the '
                            'occupancy grid; 0 means one cell', unit='m')
        self.frame_id = declare(self, 'frame_id', interface.MAP_FRAME, 'frame of /obstacles and /map')
        seed = declare(self, 'seed', 0, 'the run\'s seed: a v2 world\'s map errors (position_sigma) are drawn from '
                       'it as fastep-sim draws them')
        movers_rate = declare(self, 'movers_rate_hz', 20.0, 'how often the known movers are published on /movers '
                              '(node clock)', value_range=(10.0, 1000.0), unit='Hz')
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
        if seed < 0:
            raise StartupError(f'parameter seed must be >= 0, got {seed}')
        # The map the robots are given (a v1 world: the world itself): known still obstacles, misplaced where
        # the map says, and the known movers with their map errors.
        truth = DynamicWorld(self.scenario.world.workspace, self.scenario.obstacle_specs)
        self.known = truth.planner_map(map_generator(seed))
        world = self.scenario.world if self.scenario.is_static else self.known.world
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
        self.movers_pub = None
        if len(self.known.movers):
            self.movers_pub = self.create_publisher(MarkerArray, interface.MOVERS.lstrip('/'),
                                                    interface.RELIABLE)
            self.movers_timer = self.create_timer(1.0 / movers_rate, self.publish_movers)
            self.publish_movers()
        info = self.map_msg.info
        self.get_logger().info(f'scenario {self.scenario.name}: {len(world.obstacle_list)} obstacles, '
                               f'{len(self.known.movers)} known movers, '
                               f'map {info.width}x{info.height} cells of {info.resolution:g} m')


    @quiet_at_stop
    def publish_movers(self) -> None:
        """The known movers where the map puts them at this node clock's time."""
        assert self.movers_pub is not None
        now = self.get_clock().now()
        t = max(0.0, now.nanoseconds * 1e-9)
        self.movers_pub.publish(convert.movers_to_marker_array(self.known.others(t), now.to_msg(), self.frame_id))


def main(args: Sequence[str] | None = None) -> int:
    return node_main('fastep-map', MapNode, args)


if __name__ == '__main__':
    raise SystemExit(main())
