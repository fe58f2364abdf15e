"""What a navigator is doing: the mode the ROS status topic reports (fastep_ros) and the simulator records.

Its own module so that the navigator (navigator.py) and its behaviours (planning/behaviours/) both name it without
importing each other.
"""

from __future__ import annotations

from enum import Enum

__all__ = ['Mode']


class Mode(str, Enum):
    """What a navigator is doing; the value is what the ROS status topic reports."""

    IDLE = 'idle'            # no goal yet
    KINEMATIC = 'kinematic'  # driving straight to the goal by the kinematic equations
    AVOIDING = 'avoiding'    # driving to a waypoint planned by the swarm (or escaping, manoeuvring)
    ARRIVED = 'arrived'
    FAILED = 'failed'
