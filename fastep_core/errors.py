"""Exceptions raised by fastep_core. Every error a user can cause is a FastepError with a one-line message."""

from __future__ import annotations

__all__ = ['FastepError', 'ScenarioError', 'ParameterError', 'GoalError']


class FastepError(Exception):
    """Base class of every error fastep raises on purpose."""


class ScenarioError(FastepError):
    """A scenario file or mapping is malformed or describes an impossible setup."""


class ParameterError(FastepError, ValueError):
    """A planner, model or function parameter is unknown or out of range.

    Also a ValueError, what Python code raises for a bad argument value, so a caller written against that
    convention still catches it.
    """


class GoalError(FastepError):
    """A goal cannot be accepted: outside the workspace, inside an obstacle, or not finite."""
