"""Run summary from bags: truth vs estimate of the misalignment, 1-sigma, counts, losses.

The mounting misalignment is defined while the aircraft rides the deck (/truth/misalignment
is published only then); the estimate scored is the filter's output at the last such stamp
(the release, or the end of a deck run), or the latest output before it.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from rclpy.serialization import deserialize_message

from alignment_core.units import ARCMIN

from . import topics
from .bag import read_bag, topic_counts
from .convert import to_ns
from .topics import msg_class


def _read(bag: Path, names: tuple[str, ...]) -> dict[str, list]:
    out: dict[str, list] = {n: [] for n in names}
    for m in read_bag(bag, names):
        out[m.topic].append(deserialize_message(m.data, msg_class(m.type_name)))
    return out


def estimates_from_bag(bag: Path) -> dict[str, np.ndarray]:
    """t_ns (N,), misalignment (N, 3), sigma (N, 3) from a bag of filter outputs."""
    d = _read(bag, (topics.ALIGN_MISALIGNMENT, topics.ALIGN_STATE))
    t = np.array([to_ns(m.header.stamp) for m in d[topics.ALIGN_MISALIGNMENT]], dtype=np.int64)
    mu = np.array([[m.vector.x, m.vector.y, m.vector.z] for m in d[topics.ALIGN_MISALIGNMENT]])
    sig = []
    for m in d[topics.ALIGN_STATE]:
        n = m.layout.dim[1].size
        sig.append(np.asarray(m.data[3 * n:3 * n + 3]))
    return {'t_ns': t, 'misalignment': mu.reshape(-1, 3), 'sigma': np.array(sig).reshape(-1, 3)}


def truth_from_bag(bag: Path) -> tuple[int, np.ndarray]:
    d = _read(bag, (topics.TRUTH_MISALIGNMENT,))[topics.TRUTH_MISALIGNMENT]
    if not d:
        raise ValueError(f'{bag}: no {topics.TRUTH_MISALIGNMENT} messages')
    m = d[-1]
    return to_ns(m.header.stamp), np.array([m.vector.x, m.vector.y, m.vector.z])


def summarise(truth_bag: Path, estimate_bag: Path, sim_time_s: float, wall_time_s: float,
              published: dict[str, int] | None = None) -> dict:
    t_rel, mu = truth_from_bag(truth_bag)
    est = estimates_from_bag(estimate_bag)
    if len(est['t_ns']) == 0:
        raise ValueError(f'{estimate_bag}: no filter outputs')
    i = int(np.searchsorted(est['t_ns'], t_rel, side='right')) - 1
    if i < 0:
        raise ValueError('no filter output before the end of deck matching')
    counts = topic_counts(estimate_bag)
    if Path(truth_bag) != Path(estimate_bag):
        counts = {**topic_counts(truth_bag), **counts}
    lost = {k: published[k] - counts.get(k, 0) for k in sorted(published or {})}
    return {
        'misalignment_truth_rad': mu.tolist(),
        'misalignment_estimate_rad': est['misalignment'][i].tolist(),
        'misalignment_sigma_rad': est['sigma'][i].tolist(),
        'misalignment_error_rad': (est['misalignment'][i] - mu).tolist(),
        'scored_at_s': t_rel * 1e-9,
        'estimate_stamp_s': int(est['t_ns'][i]) * 1e-9,
        'sim_time_s': sim_time_s,
        'wall_time_s': wall_time_s,
        'real_time_factor': sim_time_s / wall_time_s if wall_time_s > 0 else None,
        'topics': counts,
        'published': published or {},
        'lost': lost,
        'lost_total': int(sum(v for v in lost.values() if v > 0)),
    }


def table(s: dict) -> str:
    mu, est = np.array(s['misalignment_truth_rad']), np.array(s['misalignment_estimate_rad'])
    sig = np.array(s['misalignment_sigma_rad'])
    lines = [f"misalignment at t = {s['scored_at_s']:.2f} s (aircraft FLU axes, arcmin)",
             f"{'axis':<10}{'truth':>10}{'estimate':>10}{'error':>10}{'1 sigma':>10}"]
    for k, name in enumerate(('x (roll)', 'y (pitch)', 'z (yaw)')):
        lines.append(f"{name:<10}{mu[k] / ARCMIN:>10.3f}{est[k] / ARCMIN:>10.3f}"
                     f"{(est[k] - mu[k]) / ARCMIN:>10.3f}{sig[k] / ARCMIN:>10.3f}")
    rtf = s.get('real_time_factor')
    lines.append(f"sim time {s['sim_time_s']:.2f} s, wall time {s['wall_time_s']:.2f} s"
                 + (f", real-time factor {rtf:.2f}" if rtf else ''))
    lines.append('messages recorded (lost):')
    for k, v in sorted(s['topics'].items()):
        lost = s['lost'].get(k)
        lines.append(f"  {k:<28}{v:>8}" + (f"  ({lost})" if lost is not None else ''))
    lines.append(f"lost messages: {s['lost_total']}")
    return '\n'.join(lines)


def write(s: dict, out: Path) -> None:
    (Path(out) / 'summary.json').write_text(json.dumps(s, indent=1))


def report(s: dict, out: Path) -> None:
    """Write summary.json into `out` and print the table and where the run is."""
    write(s, out)
    print(table(s))
    print(f'output: {out}')
