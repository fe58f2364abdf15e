"""The world of Nav2 BasicNavigator's script pattern (tests/fastep_ros/test_basic_navigator_pattern.py and
benchmarks/basic_navigator.py): a disc between the start and the goal, a closed box no goal inside is reachable,
one 0.4 m differential-drive robot, and the planner's parameters both run it with."""

from __future__ import annotations

__all__ = ['PARAMS', 'RADIUS', 'WORLD']

RADIUS = 0.4   # m: the robot's
WORLD = """\
name: basic_navigator_world
workspace: [0, 0, 20, 20]
obstacles:
  - circle: {center: [9, 10], radius: 1.5}
  - segment: {start: [15, 2], end: [19, 2]}
  - segment: {start: [19, 2], end: [19, 6]}
  - segment: {start: [19, 6], end: [15, 6]}
  - segment: {start: [15, 6], end: [15, 2]}
robots:
  - {name: r1, model: diff_drive, start: [3, 10, 0], goal: [14, 10], radius: 0.4}
"""
PARAMS = {'algorithm': 'fastep_route', 'robot_radius': RADIUS, 'max_speed': 1.5, 'planning_timeout': 10.0}
