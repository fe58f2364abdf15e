"""Exceptions raised by the fastep_ros nodes and launcher. Both are FastepErrors: one line, no traceback."""

from __future__ import annotations

from fastep_core.errors import FastepError

__all__ = ['LaunchError', 'StartupError']


class StartupError(FastepError):
    """A node cannot start with the parameters it was given: one line, exit code 2, no traceback."""


class LaunchError(FastepError):
    """Something went wrong while bringing the graph up (not the robots' fault): one line, exit code 1."""
