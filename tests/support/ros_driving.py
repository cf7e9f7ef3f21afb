"""Driving nodes from a test: spin an in-process rclpy node until a condition holds."""
from __future__ import annotations

import time


def spin_until(node, cond, timeout: float = 30.0) -> None:
    """Spin `node` until cond() holds; fail after `timeout` seconds."""
    import rclpy
    deadline = time.monotonic() + timeout
    while not cond():
        rclpy.spin_once(node, timeout_sec=0.05)
        assert time.monotonic() < deadline, 'timed out'
