"""Exceptions raised by the fastep_ros nodes and launcher. Both are FastepErrors: one line, no traceback."""

from __future__ import annotations

from fastep_core.errors import FastepError

__all__ = ['GraphConflict', 'LaunchError', 'StartupError']


class StartupError(FastepError):
    """A node cannot start with the parameters it was given: one line, exit code 2, no traceback."""


class LaunchError(FastepError):
    """Something went wrong while bringing the graph up (not the robots' fault): one line, exit code 1."""


class GraphConflict(FastepError):
    """fastep-launch found another graph on its ROS domain (another launch, a replay, nodes of its robots' names):
    one line, exit code 2. Two launches on one domain corrupted each other's runs silently."""
