"""Time series of a run read from its bag(s), for the plots and the report: whatever of the
project's topics the bags hold (one pass per bag, only the topics asked for). A missing topic
leaves its series None, so the plots draw what is there: a real log without truth, a replay
whose bag holds the filter's outputs only (its input bag passed beside it)."""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from rclpy.serialization import deserialize_message
from scipy.spatial.transform import Rotation

from .. import state_layout, topics
from ..bag import BagReader
from ..convert import to_ns
from ..topics import msg_class

MAX_POINTS = 4000       # 100 Hz streams are thinned to about this many points

TOPICS = (topics.ALIGN_MISALIGNMENT, topics.ALIGN_STATE, topics.TRUTH_MISALIGNMENT, topics.DIAGNOSTICS,
          topics.SHIP_ODOM, topics.LDV_TWIST, topics.AIR_DATA_STATE, topics.AIR_DATA_VELOCITY,
          topics.TRUTH_AIR_DATA_STATE, topics.TRUTH_WIND)


@dataclass
class Labelled:
    """A labelled array stream: t_s (N,), labels (L,), rows name -> (N, L)."""
    t_s: np.ndarray
    labels: tuple[str, ...]
    rows: dict[str, np.ndarray]

    def column(self, row: str, label: str) -> np.ndarray | None:
        if row not in self.rows or label not in self.labels:
            return None
        return self.rows[row][:, self.labels.index(label)]


@dataclass
class Diagnostic:
    """One status name's messages: t_s (N,), levels (N,) 0/1/2, messages, key-values."""
    t_s: np.ndarray
    levels: np.ndarray
    messages: list[str]
    values: list[dict[str, str]]

    def number(self, key: str) -> np.ndarray:
        """The key's values as floats (NaN where absent or not a number)."""
        out = np.full(len(self.values), np.nan)
        for i, v in enumerate(self.values):
            try:
                out[i] = float(v[key])
            except (KeyError, ValueError):
                pass
        return out


@dataclass
class RunSeries:
    """What the plots draw; None: not in the bags."""
    misalignment: tuple[np.ndarray, np.ndarray] | None = None          # t_s (N,), rad (N, 3)
    truth_misalignment: tuple[np.ndarray, np.ndarray] | None = None    # t_s (M,), rad (M, 3)
    state: Labelled | None = None
    diagnostics: dict[str, Diagnostic] = field(default_factory=dict)
    ship: dict[str, np.ndarray] | None = None        # t_s, roll_rad, pitch_rad, heave_m
    ldv: dict[str, np.ndarray] | None = None         # t_s, v_mps (N, 3), valid (N,)
    air: Labelled | None = None                      # /air_data/state (rows value, sigma)
    air_truth: Labelled | None = None                # /truth/air_data/state (row value)
    topics_seen: set[str] = field(default_factory=set)
    scenario: dict | None = None        # the run's scenario.yaml when known (monitor settings)


def _thin(n: int) -> int:
    return max(1, n // MAX_POINTS)


def read(bags: Iterable[Path], wanted: Iterable[str] | None = None) -> RunSeries:
    """The series of the bags (the first bag holding a topic gives it)."""
    want = set(TOPICS if wanted is None else wanted)
    raw: dict[str, list] = {}
    for bag in bags:
        reader = BagReader(bag)
        here = [t for t in reader.topics() if t in want and t not in raw]
        counts = reader.counts()
        for t in here:
            raw[t] = []
        step = {t: (_thin(counts.get(t, 0)) if t in (topics.SHIP_ODOM, topics.LDV_TWIST) else 1) for t in here}
        seen = dict.fromkeys(here, 0)
        for m in reader.messages(here):
            k = seen[m.topic]
            seen[m.topic] = k + 1
            if k % step[m.topic] == 0:
                raw[m.topic].append(deserialize_message(m.data, msg_class(m.type_name)))
    s = RunSeries(topics_seen={t for t, v in raw.items() if v})
    if raw.get(topics.ALIGN_MISALIGNMENT):
        s.misalignment = _vectors(raw[topics.ALIGN_MISALIGNMENT])
    if raw.get(topics.TRUTH_MISALIGNMENT):
        s.truth_misalignment = _vectors(raw[topics.TRUTH_MISALIGNMENT])
    if raw.get(topics.ALIGN_STATE):
        s.state = _states(raw[topics.ALIGN_STATE])
    if raw.get(topics.DIAGNOSTICS):
        s.diagnostics = _diagnostics(raw[topics.DIAGNOSTICS])
    if raw.get(topics.SHIP_ODOM):
        s.ship = _ship(raw[topics.SHIP_ODOM])
    if raw.get(topics.LDV_TWIST):
        s.ldv = _ldv(raw[topics.LDV_TWIST])
    s.air = _stamped_labelled(raw.get(topics.AIR_DATA_STATE), raw.get(topics.AIR_DATA_VELOCITY))
    s.air_truth = _stamped_labelled(raw.get(topics.TRUTH_AIR_DATA_STATE), raw.get(topics.TRUTH_WIND))
    return s


def _vectors(msgs: list) -> tuple[np.ndarray, np.ndarray]:
    t = np.array([to_ns(m.header.stamp) for m in msgs]) * 1e-9
    return t, np.array([[m.vector.x, m.vector.y, m.vector.z] for m in msgs]).reshape(-1, 3)


def _states(msgs: list) -> Labelled | None:
    """/alignment/state by its labels; messages of another layout than the first are skipped."""
    recs = []
    for m in msgs:
        try:
            recs.append(state_layout.from_msg(m))
        except ValueError:
            continue
    if not recs:
        return None
    first = recs[0]
    recs = [r for r in recs if r.labels == first.labels and r.rows.keys() == first.rows.keys()]
    t = np.array([r.t_s if r.t_s is not None else np.nan for r in recs])
    rows = {name: np.array([r.rows[name] for r in recs]) for name in first.rows}
    return Labelled(t, first.labels, rows)


def _diagnostics(msgs: list) -> dict[str, Diagnostic]:
    by: dict[str, tuple[list, list, list, list]] = {}
    for m in msgs:
        t = to_ns(m.header.stamp) * 1e-9
        for st in m.status:
            d = by.setdefault(st.name, ([], [], [], []))
            d[0].append(t)
            d[1].append(int.from_bytes(st.level, 'little') if isinstance(st.level, bytes) else int(st.level))
            d[2].append(st.message)
            d[3].append({kv.key: kv.value for kv in st.values})
    return {n: Diagnostic(np.array(d[0]), np.array(d[1]), d[2], d[3]) for n, d in by.items()}


def _ship(msgs: list) -> dict[str, np.ndarray]:
    t = np.array([to_ns(m.header.stamp) for m in msgs]) * 1e-9
    q = np.array([[m.pose.pose.orientation.x, m.pose.pose.orientation.y, m.pose.pose.orientation.z,
                   m.pose.pose.orientation.w] for m in msgs])
    ypr = Rotation.from_quat(q).as_euler('ZYX')          # body FLU w.r.t. ENU: yaw, pitch, roll
    z = np.array([m.pose.pose.position.z for m in msgs])
    return {'t_s': t, 'roll_rad': ypr[:, 2], 'pitch_rad': ypr[:, 1], 'heave_m': z}


def _ldv(msgs: list) -> dict[str, np.ndarray]:
    t = np.array([to_ns(m.header.stamp) for m in msgs]) * 1e-9
    v = np.array([[m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.linear.z] for m in msgs])
    valid = np.array([m.twist.covariance[0] >= 0.0 for m in msgs])
    return {'t_s': t, 'v_mps': v.reshape(-1, 3), 'valid': valid}


def _stamped_labelled(arrays: list | None, stamped: list | None) -> Labelled | None:
    """A stampless labelled array stream, each message paired with the stamped message its node
    published with it (same order, same count)."""
    if not arrays or not stamped:
        return None
    n = min(len(arrays), len(stamped))
    first = arrays[0]
    rows = first.layout.dim[0].label.split('|')
    labels = tuple(first.layout.dim[1].label.split(','))
    keep = [i for i in range(n) if tuple(arrays[i].layout.dim[1].label.split(',')) == labels]
    data = np.array([np.asarray(arrays[i].data, dtype=float).reshape(len(rows), len(labels)) for i in keep])
    t = np.array([to_ns(stamped[i].header.stamp) for i in keep]) * 1e-9
    return Labelled(t, labels, {r: data[:, k] for k, r in enumerate(rows)})
