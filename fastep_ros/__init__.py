"""ROS 2 nodes of fastep: plant, map, planner-controller, clock, and the launcher."""
