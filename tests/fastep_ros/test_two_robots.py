"""Two robots whose straight runs cross, each a plant + planner process pair, finding each other on the graph."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from diagnostic_msgs.msg import DiagnosticStatus
from nav_msgs.msg import Odometry

from fastep_core.geometry import Obstacles
from fastep_core.metrics import trajectory_margins
from fastep_testing.graph import CROSSING, FAST, Graph, Helper, distance, odom_xy, stamp, write
from msg_tools.convert import diagnostic_to_dict

ROBOTS = {'r1': ((3.0, 3.0), (17.0, 17.0)), 'r2': ((17.0, 3.0), (3.0, 17.0))}
RADIUS = 0.5


def test_two_robots_cross_without_collision(tmp_path: Path) -> None:
    g = Graph(tmp_path)
    try:
        scenario = write(tmp_path / 'crossing.yaml', CROSSING)
        g.start('map', 'map_server', scenario=str(scenario))
        for name, (start, _) in ROBOTS.items():
            g.start(f'plant_{name}', 'plant', f'/{name}', model='point_mass', start=list(start), use_sim_time=True)
            g.start(f'planner_{name}', 'planner', f'/{name}', model='point_mass', robot_radius=RADIUS,
                    use_sim_time=True, seed_stream=int(name[1]) - 1, **FAST)
        # The clock holds time 0 until the four nodes and the helper (last) follow it, then runs in lock step
        # with them (as fastep-launch does).
        g.start('clock', 'clock', rtf=10.0, step=0.05, wait_for_subscribers=5,
                sync_topics=[f'/{name}/{topic}' for name in ROBOTS for topic in ('cmd_vel', 'odom')])
        h = g.helper = Helper(g.domain)
        for name in ROBOTS:
            h.record_status(f'/{name}')
            h.record(f'/{name}/odom', Odometry)
        for name in ROBOTS:
            other = 'r2' if name == 'r1' else 'r1'
            h.wait_status(f'/{name}', lambda s, o=other: s['message'] == 'idle' and o in s['others'].split()
                          and int(s.get('cmd_vel_readers', 0)) >= 2 and int(s.get('odom_heard', 0)) >= 1, 60.0,
                          f'{name} to know the world and {other}, and its plant and the clock to hear its commands')
        for name in ROBOTS:   # and this helper, which judges the run, hears both robots from the start
            h.wait_heard(f'/{name}/odom')
        for name, (_, goal) in ROBOTS.items():
            h.send_goal(f'/{name}', goal)
        for name in ROBOTS:
            h.wait_status(f'/{name}', lambda s: s['message'] == 'kinematic', 20.0, f'{name} to take its goal')
        h.follow_clock()
        final = {}
        for name in ROBOTS:
            final[name] = h.wait_status(f'/{name}', lambda s: s['message'] in ('arrived', 'failed'), 120.0,
                                        f'{name} to finish')
            assert final[name]['message'] == 'arrived', final[name]
        for name in ROBOTS:
            h.wait_recorded_through(f'/{name}/odom', float(final[name]['t']))
        h.spin_for(0.2)

        tracks = {name: {round(stamp(m), 6): odom_xy(m) for m in h.records[f'/{name}/odom']} for name in ROBOTS}
        for name in ROBOTS:   # REP-105: each plant's odometry is odom -> base_link in its namespace
            assert {(m.header.frame_id, m.child_frame_id) for m in h.records[f'/{name}/odom']} == \
                {(f'{name}/odom', f'{name}/base_link')}
        for name, (_, goal) in ROBOTS.items():
            last = max(tracks[name])
            assert distance(tracks[name][last], goal) <= 0.12
            # The plants integrate in whole steps (1/50 s) of the one simulated clock.
            assert all(abs(t * 50.0 - round(t * 50.0)) < 1e-6 for t in tracks[name]), name
        # The two odometry streams need not share every stamp (a node late under load lets the lock step tick on
        # without it for a while): compare them as fastep-launch and fastep-report do, by the one margin function.
        rows = [np.array([[t, *tracks[name][t]] for t in sorted(tracks[name])]) for name in ROBOTS]
        closest = float(trajectory_margins(rows, [RADIUS, RADIUS], Obstacles(())).robots[0]) + 2 * RADIUS
        assert closest >= 2 * RADIUS, f'robots came {closest:.3f} m close (sum of radii {2 * RADIUS} m)'
        # they really did meet: the straight runs cross at (10, 10) at about the same time (when they did not, it
        # was this helper that had not heard a robot from the start: say what it heard first, and the planners)
        off = {name: next((t for t in sorted(tracks[name]) if distance(tracks[name][t], ROBOTS[name][0]) > 0.05), None)
               for name in ROBOTS}
        stale = {name: sum(m.message == 'stale' for m in h.records[f'/{name}/status']) for name in ROBOTS}
        said = {name: _first_statuses(h.records[f'/{name}/status']) for name in ROBOTS}
        first_odom = {name: sorted(tracks[name])[:3] for name in ROBOTS}
        assert closest < 4.0, (f'the robots never met: closest {closest:.2f} m; set off at {off}; stale {stale}; '
                               f'first odometry stamps {first_odom}; statuses (planner time: status) {said}')
        # and it was planned: on their straight runs, at the same speed, they would reach (10, 10) together, so
        # at least one planner must have planned a step around the other
        assert max(int(final[name]['activations']) for name in ROBOTS) >= 1, final
    finally:
        g.close()


def _first_statuses(statuses: list[DiagnosticStatus]) -> list[str]:
    """The first eight distinct statuses, each with the planner time it was first sent at."""
    seen: dict[str, str] = {}
    for d in map(diagnostic_to_dict, statuses):
        seen.setdefault(f"{d['message']}: {d.get('reason', '')}", d.get('t', '?'))
    return [f'{t}: {key}' for key, t in list(seen.items())[:8]]
