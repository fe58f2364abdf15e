"""Fixtures shared by the tests that build nodes in this process."""

from __future__ import annotations

import os
from typing import Any, Iterator

import pytest

from fastep_testing.graph import free_domain


@pytest.fixture
def context() -> Iterator[Any]:
    """An rclpy context of its own on a free DDS domain, localhost only, without rclpy's signal handlers."""
    import rclpy
    from rclpy.signals import SignalHandlerOptions
    saved = os.environ.get('ROS_AUTOMATIC_DISCOVERY_RANGE')
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    ctx = rclpy.Context()
    try:
        rclpy.init(args=[], context=ctx, domain_id=free_domain(), signal_handler_options=SignalHandlerOptions.NO)
    finally:
        if saved is None:
            os.environ.pop('ROS_AUTOMATIC_DISCOVERY_RANGE', None)
        else:
            os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = saved
    try:
        yield ctx
    finally:
        rclpy.try_shutdown(context=ctx)
