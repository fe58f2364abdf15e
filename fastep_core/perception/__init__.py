"""Perception: what a robot makes of its own laser scans, the map it was given and the other robots' odometry.

One algorithm per module: scan points and their segmentation into clusters (segmentation.py), circles fitted
to clusters and straight walls drawn through the rest (shapes.py), fusion with the map (fusion.py: points a
believed surface explains, believed obstacles the scan sees through), tracking with a constant-velocity Kalman
filter (tracking.py), and the robot's Belief that puts them together (belief.py). Pure numpy/scipy.
"""
