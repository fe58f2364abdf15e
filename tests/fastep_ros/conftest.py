"""Fixtures shared by the tests that build nodes in this process (context) or run node processes (graph)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Iterator

import pytest

from fastep_testing.graph import Graph, free_domain


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


@pytest.fixture
def graph(tmp_path: Path) -> Iterator[Graph]:
    """Node processes on a domain of their own (fastep_testing.graph.Graph), every one stopped at the end."""
    g = Graph(tmp_path)
    try:
        yield g
    finally:
        g.close()
