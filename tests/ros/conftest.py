"""Fixtures of the tests/ros CLI tests: a ROS domain of their own and an rclpy context on it."""
from __future__ import annotations

import pytest
import rclpy
from rclpy.context import Context


@pytest.fixture
def domain_id(monkeypatch: pytest.MonkeyPatch) -> int:
    """A ROS_DOMAIN_ID of its own (claimed by lock), exported to the subprocesses of the test."""
    from alignment_ros import domain
    dom = domain.claim()
    monkeypatch.setenv('ROS_DOMAIN_ID', str(dom))
    monkeypatch.setenv('ROS_AUTOMATIC_DISCOVERY_RANGE', 'SYSTEM_DEFAULT')   # the loopback profile decides
    yield dom
    domain.release(dom)


@pytest.fixture
def ros_context(domain_id: int):
    """An rclpy context of its own on the test's domain."""
    ctx = Context()
    rclpy.init(context=ctx, domain_id=domain_id)
    yield ctx
    rclpy.try_shutdown(context=ctx)
