"""QoS profiles: simulation streams are RELIABLE + KEEP_ALL so that no message is lost.

KEEP_ALL is back-pressure: a writer holds at most Fast DDS's resource_limits.max_samples (5000)
messages its slowest reader has not acknowledged; then a publish waits (max_blocking_time,
config/dds/fastdds.xml) and CountingNode.send publishes it again until it is taken."""
from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

STREAM = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
"""Every simulation and estimate stream, and /clock."""

DIAGNOSTICS = QoSProfile(
    history=HistoryPolicy.KEEP_ALL,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)

WATCH = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=5, reliability=ReliabilityPolicy.BEST_EFFORT)
"""A watcher of a stream's progress (the ship's lead, the recorder's progress topic): best
effort, the latest few only; it never holds a writer back."""
NEWEST = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
"""The live progress line's reader (progress_watch.py): best effort, the newest message only."""
