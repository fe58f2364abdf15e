"""fastep_ros: the rclpy nodes (plant, map, planner, clock) and the fastep-launch launcher."""
