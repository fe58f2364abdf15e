"""A test-style publisher: N fake robots publishing odom (nav_msgs/Odometry) and cost (std_msgs/Float64).

    python -m fastep_testing.fake_robots [--robots 8] [--rate 50] [--count 500] [--wait-subscribers 1] [--prefix r]

Why: to measure the recorder (benchmarks.recorder_throughput) and to test it (tests/fastep_ros/test_recorder.py)
with a known number of messages. Robot k publishes /<prefix><k>/odom and /<prefix><k>/cost (prefix `r`:
/r1/odom ...) `count` times at `rate` Hz
(wall time): message i has header.stamp = wall time, pose.position.x = i, y = k, and cost data = i, so a
recording can be checked for losses and order. Before the first message it waits (up to --wait-timeout s)
until every publisher has --wait-subscribers matched subscriptions (a recorder), so discovery does not eat the
first messages. When done (or on Ctrl-C / SIGTERM) it prints one JSON line: {"published": {topic: count}}.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Sequence

__all__ = ['main']


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog='fake_robots', description=__doc__.splitlines()[0])
    p.add_argument('--robots', type=int, default=8)
    p.add_argument('--rate', type=float, default=50.0, help='messages per second per topic (wall time)')
    p.add_argument('--count', type=int, default=500, help='messages per topic (0: until stopped)')
    p.add_argument('--wait-subscribers', type=int, default=0)
    p.add_argument('--wait-timeout', type=float, default=30.0)
    p.add_argument('--prefix', default='r', help='robot names are <prefix><k>, k = 1..robots (default r)')
    args = p.parse_args(argv)

    import rclpy
    from nav_msgs.msg import Odometry
    from rclpy.executors import ExternalShutdownException
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from std_msgs.msg import Float64

    rclpy.init(args=[])
    node = rclpy.create_node('fake_robots')
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    names = [f'{args.prefix}{k}' for k in range(1, args.robots + 1)]
    pubs = [(f'/{name}', node.create_publisher(Odometry, f'/{name}/odom', qos),
             node.create_publisher(Float64, f'/{name}/cost', qos)) for name in names]
    published = {f'{ns}/{what}': 0 for ns, _, _ in pubs for what in ('odom', 'cost')}
    try:
        deadline = time.monotonic() + args.wait_timeout
        while args.wait_subscribers and time.monotonic() < deadline and not all(
                o.get_subscription_count() >= args.wait_subscribers and c.get_subscription_count() >=
                args.wait_subscribers for _, o, c in pubs):
            rclpy.spin_once(node, timeout_sec=0.05)
        # Our writer sees the match before the reader has matched our writer; samples sent in between are
        # dropped on a volatile topic (seen once in a full test run: 98 of 100 recorded). Let discovery settle.
        settle = time.monotonic() + (0.5 if args.wait_subscribers else 0.0)
        while time.monotonic() < settle:
            rclpy.spin_once(node, timeout_sec=0.05)
        period = 1.0 / args.rate
        start = time.monotonic()
        i = 0
        while rclpy.ok() and (args.count <= 0 or i < args.count):
            now = node.get_clock().now().to_msg()
            for k, (ns, odom_pub, cost_pub) in enumerate(pubs, start=1):
                odom = Odometry()
                odom.header.stamp = now
                odom.header.frame_id = 'map'
                odom.child_frame_id = f'{ns[1:]}/base_link'
                odom.pose.pose.position.x = float(i)
                odom.pose.pose.position.y = float(k)
                odom.pose.pose.orientation.w = 1.0
                odom_pub.publish(odom)
                published[f'{ns}/odom'] += 1
                cost_pub.publish(Float64(data=float(i)))
                published[f'{ns}/cost'] += 1
            i += 1
            delay = start + i * period - time.monotonic()
            if delay > 0:
                time.sleep(delay)
        time.sleep(0.5)  # reliable delivery of the last messages before the publishers go away
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        print(json.dumps({'published': published}), flush=True)
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
