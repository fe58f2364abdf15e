"""Helpers shared by the tests (tests/) and the benchmarks (benchmarks/): nothing in the product imports them.

- `graph`: isolated DDS domains (a free ROS_DOMAIN_ID per graph, file-locked), starting and stopping node
  processes, and a helper rclpy node in the calling process (goals, status, recorded topics).
- `fake_robots`: a publisher process (`python -m fastep_testing.fake_robots`) of N fake robots' odom and cost.
- `fastep_loop`: FAStep written with plain Python loops, the reference the vectorised optimizer must match
  bit for bit (a test) and is timed against (a benchmark).
- `objectives`: small vectorised objectives for the optimizer tests.

Not installed with the project (setup.py lists only the product packages): it imports from the repository
root, which is on sys.path when tests run as `python -m pytest` (what `make test` does) and benchmarks as
`python -m benchmarks.NAME`, both from the root. Node processes started through `graph.isolated_env` get the
root on PYTHONPATH, so `python -m fastep_testing.fake_robots` works there too. Tests and benchmarks both import
this package; neither imports the other.
"""
