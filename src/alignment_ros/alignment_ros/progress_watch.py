"""The launcher's eyes on a running graph, for its progress line: a small node in the launcher's
process (its own rclpy context and executor thread, so the launcher's other rclpy use is
untouched) reading /alignment/misalignment and /alignment/state (the estimate and its 1-sigma),
and /air_data/state (Mach and alpha) in air-data runs. The simulation time reached is the
latest of the filter's output stamps and the recorder's progress lines (the caller's, with its
count of messages so far). Not /clock: a replay's player sends its bag's /clock far ahead of what
the filter has processed, and in a run of the graph a reader of /clock (100 messages per
simulated second) cost the launcher 0.4 CPU s of a default run, on the cores the nodes use.
Out of the data path: BEST_EFFORT subscriptions keeping the newest message, so no publisher ever waits
for them (a reliable writer neither blocks on nor resends to a best-effort reader; a node's
end-of-run acknowledgements count reliable readers only), and it publishes nothing. The nodes
hold their messages until the recorder itself has matched (named in ``hold_until_matched``), so
this extra subscriber cannot make the recorder miss any."""
from __future__ import annotations

import math
import sys
import threading
import time

import numpy as np
from geometry_msgs.msg import Vector3Stamped
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from std_msgs.msg import Float64MultiArray

from . import qos, state_layout, topics
from .convert import to_ns
from .progress import Progress

POLL_S = 0.25
"""The watcher takes its subscriptions' newest messages this often (wall seconds): between two
looks the middleware replaces the older ones, and no Python runs for them. Woken by every
message instead, it cost the launcher 0.2-0.4 CPU s of a default run."""


class GraphWatcher:
    """Feeds a Progress from the graph while started (start() / stop())."""

    def __init__(self, progress: Progress, node_name: str = 'progress_watch') -> None:
        self.progress = progress
        self.node_name = node_name
        self._sigma: np.ndarray | None = None   # the latest misalignment 1-sigma (3,) rad, if any
        self._ctx: Context | None = None
        self._thread: threading.Thread | None = None

    def start(self) -> GraphWatcher:
        if self.progress.mode == 'quiet':
            return self                          # nothing to show: no node at all
        import rclpy
        self._ctx = Context()
        rclpy.init(context=self._ctx, signal_handler_options=rclpy.signals.SignalHandlerOptions.NO)
        node = Node(self.node_name, context=self._ctx, start_parameter_services=False,
                    enable_rosout=False)
        subs = [node.create_subscription(Vector3Stamped, topics.ALIGN_MISALIGNMENT, self._on_estimate, qos.NEWEST),
                node.create_subscription(Float64MultiArray, topics.ALIGN_STATE, self._on_state, qos.NEWEST),
                node.create_subscription(Float64MultiArray, topics.AIR_DATA_STATE, self._on_air_data, qos.NEWEST)]
        executor = SingleThreadedExecutor(context=self._ctx)
        executor.add_node(node)

        def spin() -> None:
            try:
                while self._ctx is not None and self._ctx.ok():
                    time.sleep(POLL_S)                   # meanwhile the newest replaces the older
                    for _ in subs:                       # each subscription's newest, if any
                        executor.spin_once(timeout_sec=0.0)
            except (ExternalShutdownException, RuntimeError):
                pass
            finally:
                executor.shutdown()
                node.destroy_node()
        self._thread = threading.Thread(target=spin, name='progress_watch', daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        ctx, self._ctx = self._ctx, None
        if ctx is not None:
            ctx.try_shutdown()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None

    def _on_estimate(self, m: Vector3Stamped) -> None:
        mu = (m.vector.x, m.vector.y, m.vector.z)
        self.progress.update(to_ns(m.header.stamp) * 1e-9, estimate=(mu, self._sigma))

    def _on_air_data(self, m: Float64MultiArray) -> None:
        try:
            self.progress.update(note=air_data_note(state_layout.from_msg(m)))
        except ValueError:
            pass

    def _on_state(self, m: Float64MultiArray) -> None:
        try:
            self._sigma = state_layout.from_msg(m).misalignment_sigma()
        except ValueError:
            self._sigma = None


def air_data_note(st: state_layout.StateRecord) -> str | None:
    """'Mach M \u00b1 s, alpha A \u00b1 s deg' of an /air_data/state record (None without them)."""
    value, sigma = st.rows.get('value'), st.rows.get('sigma')
    if value is None or sigma is None or 'mach' not in st.labels or 'alpha_rad' not in st.labels:
        return None
    i, j = st.labels.index('mach'), st.labels.index('alpha_rad')
    return (f'Mach {value[i]:.3f} \u00b1 {sigma[i]:.3f}, alpha {math.degrees(value[j]):.2f} '
            f'\u00b1 {math.degrees(sigma[j]):.2f} deg')


class LiveProgress:
    """A launcher's progress: a Progress fed by a GraphWatcher (simulation time, estimate) and by
    the recorder's progress lines (messages recorded); closed with the run's summary, so the
    final line states the simulation time the summary reports."""

    def __init__(self, label: str, total_s: float, start_s: float, quiet: bool = False) -> None:
        self.progress = Progress(label, total_s, start_s, quiet=quiet)
        self.watcher = GraphWatcher(self.progress)

    def start(self) -> None:
        try:
            self.watcher.start()
        except Exception as e:      # progress is a convenience: never the reason a run fails
            print(f'{self.progress.label}: no live progress ({e})', file=sys.stderr)

    def recorded(self, messages: int, stamp_ns: int) -> None:
        """A recorder progress line: messages so far (and its latest stamp)."""
        self.progress.update(stamp_ns * 1e-9 if stamp_ns else None, messages=messages)

    def close(self, summary: dict | None) -> None:
        """The final line with the summary's simulated time; none without a summary (a run
        stopped by a signal, or without a bag, says so in its own line)."""
        self.watcher.stop()
        if summary is None or summary.get('sim_time_s') is None:
            self.progress.abandon()
            return
        self.progress.close(self.progress.start_s + summary['sim_time_s'])
