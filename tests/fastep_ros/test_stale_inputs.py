"""What went quiet is kept (issue "Faults", items 1 and 2), on a live graph on wall time.

A robot forgot an obstacle because the process that reported it went quiet, and drove through it: another robot
whose plant was stalled (SIGSTOP) was dropped after other_robot_timeout, a known mover once /movers stopped for
odom_timeout. Both are now kept where they were last seen, reported stale, and driven around.
"""

from __future__ import annotations

import signal

from nav_msgs.msg import Odometry

from fastep_testing.graph import Graph, Helper, distance, odom_xy, write

FAST = {'alpha1': 1.0, 'alpha2': 1.0, 'max_speed': 3.0, 'algorithm': 'fastep'}
RADIUS = 0.5
ARRIVE = 120.0   # wall seconds at most for a run (normally 10-20)
BLOCKER = (10.0, 10.0)   # where the stalled robot stands, or the mover stood when /movers stopped
START, GOAL = (5.0, 10.0), (15.0, 10.0)
EMPTY = """\
name: open_field
workspace: [0, 0, 20, 20]
obstacles: []
robots:
  - name: r2
    model: point_mass
    start: [5, 10]
    goal: [15, 10]
    radius: 0.5
"""


def start_robot(g: Graph, ns: str, start: tuple[float, float]) -> None:
    g.start(f'{ns}/plant', 'plant', ns, model='point_mass', start=list(start))
    # Stale after 1 s rather than 3 s: the test waits for it.
    g.start(f'{ns}/planner', 'planner', ns, model='point_mass', robot_radius=RADIUS, other_robot_timeout=1.0, **FAST)


def drive_and_judge(h: Helper, clearance: float) -> float:
    """Send r2 to GOAL, wait for its arrival; its smallest distance to BLOCKER over the run."""
    h.send_goal('/r2', GOAL)
    h.wait_status('/r2', lambda s: s['message'] == 'arrived', ARRIVE, 'r2 to arrive')
    nearest = min(distance(odom_xy(m), BLOCKER) for m in h.records['/r2/odom'])
    assert nearest >= clearance, f'r2 came within {nearest:.2f} m of what went quiet (needs {clearance:.2f} m)'
    return nearest


def test_a_robot_whose_plant_stalls_is_driven_around_not_through(graph: Graph) -> None:
    """r1 parked on r2's way; r1's plant frozen (SIGSTOP) before r2 starts: r1 stops being fresh after
    other_robot_timeout, stays in r2's status as stale, and r2 goes round it."""
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', EMPTY)))
    start_robot(graph, '/r1', BLOCKER)
    start_robot(graph, '/r2', START)
    h = graph.helper = Helper(graph.domain)
    h.record_status('/r2')
    h.record('/r2/odom', Odometry)
    h.wait_status('/r2', lambda s: s['message'] == 'idle' and s['others'] == 'r1', 60.0, 'r2 to follow r1')
    plant = graph.procs['/r1/plant']
    plant.send_signal(signal.SIGSTOP)
    try:
        h.wait_status('/r2', lambda s: s['stale'] == 'r1' and s['others'] == '', 30.0, 'r1 to be stale for r2')
        drive_and_judge(h, 2 * RADIUS)
    finally:
        plant.send_signal(signal.SIGCONT)


def test_a_known_mover_is_kept_where_last_seen_when_movers_stop(graph: Graph) -> None:
    """/movers (here from the test, standing for the map node) gives a mover standing at BLOCKER, then stops: the
    planner keeps it (stale) and drives around it, instead of dropping it after odom_timeout."""
    from visualization_msgs.msg import MarkerArray

    from fastep_core.planning.others import OtherRobot
    from msg_tools import convert, interface
    graph.start('map', 'map_server', scenario=str(write(graph.tmp / 'world.yaml', EMPTY)))
    start_robot(graph, '/r2', START)
    h = graph.helper = Helper(graph.domain)
    h.record_status('/r2')
    h.record('/r2/odom', Odometry)
    movers = h.node.create_publisher(MarkerArray, interface.MOVERS, interface.RELIABLE)
    mover = OtherRobot('mover 0', BLOCKER, (0.0, 0.0), 0.6, mover=True)

    def told() -> bool:
        movers.publish(convert.movers_to_marker_array([mover], h.node.get_clock().now().to_msg()))
        return movers.get_subscription_count() > 0
    h.spin_until(told, 60.0, 'the planner to match /movers')
    h.wait_status('/r2', lambda s: s['message'] == 'idle', 60.0, 'r2 to know the world')
    for _ in range(10):   # what a map node would send in half a second
        told()
        h.spin_for(0.05)
    h.wait_status('/r2', lambda s: s['stale'] == '/movers', 30.0, 'r2 to report /movers stale')
    drive_and_judge(h, 0.6 + RADIUS)
