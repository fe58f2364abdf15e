"""Conversions between fastep_core types and ROS messages, recordings, reports and the paper's figures."""
