"""What one planner's looks at the graph for other robots cost, with N announced robots on it.

    ROS_DOMAIN_ID=<yours> ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST python -m benchmarks.robot_discovery --robots 100

Builds, in this process, a planner in /me and N fake robots (a node in /r<k> publishing a latched footprint
and odometry), waits until the planner follows all of them, then times `looks` calls of its look at the graph
(fastep_ros.robots.RobotFollower.discover; the planner makes one every 0.25 s of wall time). Prints CPU time
(time.process_time) and wall time per look, and the load average.
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Sequence


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='robot_discovery', description=__doc__.splitlines()[0])
    p.add_argument('--robots', type=int, default=100)
    p.add_argument('--looks', type=int, default=400)
    args = p.parse_args(argv)

    import rclpy
    from geometry_msgs.msg import PolygonStamped
    from nav_msgs.msg import Odometry
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter

    from fastep_ros.planner import PlannerNode
    from msg_tools import convert
    from msg_tools.footprint import circle_footprint
    from msg_tools.interface import LATCHED, RELIABLE

    rclpy.init(args=[])
    executor = SingleThreadedExecutor()
    robots = []
    for k in range(args.robots):
        node = rclpy.create_node('planner', namespace=f'/r{k}')
        node.create_publisher(PolygonStamped, 'footprint', LATCHED).publish(circle_footprint(0.5, f'r{k}/base_link'))
        robots.append(node.create_publisher(Odometry, 'odom', RELIABLE))
        executor.add_node(node)
    planner = PlannerNode(namespace='/me', parameter_overrides=[Parameter('workspace', value=[0.0, 0.0, 50.0, 50.0])])
    executor.add_node(planner)
    deadline = time.monotonic() + 60.0
    while len(planner.robots.fleet.names(planner.now())) < args.robots:
        if time.monotonic() > deadline:
            print(f'followed only {len(planner.robots.fleet.names(planner.now()))} of {args.robots} robots')
            return 1
        for pub in robots:
            pub.publish(convert.state_to_odometry([1.0, 1.0]))
        executor.spin_once(timeout_sec=0.05)
    cpu, wall = time.process_time(), time.perf_counter()
    for _ in range(args.looks):
        planner.robots.discover()
    cpu, wall = (time.process_time() - cpu) / args.looks, (time.perf_counter() - wall) / args.looks
    print(f'{args.robots} robots: {cpu * 1e3:.3f} ms CPU ({wall * 1e3:.3f} ms wall) per look, '
          f'{4 * cpu * 1e3:.2f} ms CPU per wall second; load average {os.getloadavg()}')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
