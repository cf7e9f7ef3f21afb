"""Real-time factor of the node graph and of the batch pipeline on the default scenario.

    python bench/graph_rtf.py [--rtf 5 10 0] [--repeat 3]

Graph: runs scripts/run_graph.sh at each requested real_time_factor and reports the
streaming RTF (simulated seconds / wall seconds between the recorder's first and last
message), the whole-run RTF including start-up, and lost messages (must be 0).
Batch: the same scenario in-process; simulation stages, filter alone, and whole pipeline.
Peer: filterpy's KalmanFilter doing the same 12-state predict + 3-measurement update, so
the filter's per-step cost is read as a ratio against a well-known implementation.
Each graph run also gives its start-up (from the command to the first message recorded), each
node's CPU time per simulated minute (the nodes' stats), the longest any node waited at its end for
its messages to be acknowledged, and the command's own wall time, the summary included (with
--plots: report.md and the plots too, as the README's first command makes them; what a user waits
for), and whether its scored estimate is, bit for bit, the batch pipeline's on the same scenario.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.filters.kalman import KalmanFilter

ROOT = Path(__file__).resolve().parents[1]


def graph(rtf: float, plots: bool = False) -> dict:
    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / 'run'
        t0 = time.perf_counter()
        p = subprocess.run([str(ROOT / 'scripts/run_graph.sh'), '--out', str(out), *([] if plots else ['--no-plots']),
                            '--real-time-factor', str(rtf)], capture_output=True, text=True)
        command_s = time.perf_counter() - t0
        if p.returncode != 0:
            raise RuntimeError(p.stderr)
        s = json.loads((out / 'summary.json').read_text())
        rec = json.loads((out / 'stats' / 'recorder.json').read_text())
        span = rec.get('receive_span_s') or s['wall_time_s']
        stats = {f.stem: json.loads(f.read_text()) for f in sorted((out / 'stats').glob('*.json'))
                 if f.stem != 'published'}
        cpu = {n: st.get('cpu_s') for n, st in stats.items()}     # every node's and the recorder's own CPU time
        # ... and that of their start-up (a node's until it spun, the recorder's until its first message)
        cpu_ready = {n: st.get('cpu_ready_s') for n, st in stats.items()}
        ack = max((st.get('ack_wait_s') or 0.0 for st in stats.values()), default=0.0)
        same = same_as_batch(out, s)
        return {'same_estimate': same, 'rtf_setting': rtf, 'streaming_rtf': s['sim_time_s'] / span,
                'whole_run_rtf': s['real_time_factor'], 'lost': s['lost_total'],
                'messages': sum(s['topics'].values()), 'topics': s['topics'], 'startup_s': s.get('startup_s'),
                'sim_time_s': s['sim_time_s'], 'cpu_s': cpu, 'cpu_ready_s': cpu_ready, 'ack_wait_s': ack,
                'command_s': command_s}


def same_as_batch(out: Path, s: dict) -> bool:
    """Whether the run's scored estimate (summary.json) is, bit for bit, the batch pipeline's
    estimate at the same instant on the run's own resolved scenario."""
    sc = scenario.load(str(out / 'scenario.yaml'))
    est = pipeline.run(sc, keep_truth=False).estimates
    t_b = np.array([e.t_ns for e in est])
    i = int(np.searchsorted(t_b, round(s['scored_at_s'] * 1e9), side='right')) - 1
    return i >= 0 and s['misalignment_estimate_rad'] == est[i].misalignment.tolist()


def batch(repeat: int) -> dict:
    sc = scenario.load('catapult_paper')
    sim, filt = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        inp = pipeline.simulate(sc)
        t1 = time.perf_counter()
        pipeline.align(sc, inp)
        t2 = time.perf_counter()
        sim.append(t1 - t0)
        filt.append(t2 - t1)
    s, f = min(sim), min(filt)
    return {'simulate_s': s, 'filter_s': f, 'rtf_pipeline': sc.duration_s / (s + f),
            'rtf_filter': sc.duration_s / f, 'filter_us_per_step': f / sc.n_samples * 1e6}


def kf_peer(steps: int = 5000) -> dict:
    from filterpy.kalman import KalmanFilter as FpKF
    rng = np.random.default_rng(0)
    n, m = 12, 3
    phi = np.eye(n) + 0.01 * rng.standard_normal((n, n))
    q = np.eye(n) * 1e-6
    h = np.hstack([np.zeros((3, 3)), np.eye(3), np.zeros((3, 6))])
    r = np.eye(m) * 1e-4
    zs = rng.standard_normal((steps, m))
    ours = KalmanFilter(np.zeros(n), np.eye(n))
    t = time.perf_counter()
    for z in zs:
        ours.predict(phi, q)
        ours.update(z, h, r)
    t_ours = time.perf_counter() - t
    fp = FpKF(dim_x=n, dim_z=m)
    fp.F, fp.Q, fp.H, fp.R, fp.P = phi, q, h, r, np.eye(n)
    t = time.perf_counter()
    for z in zs:
        fp.predict()
        fp.update(z)
    t_fp = time.perf_counter() - t
    return {'ours_us': t_ours / steps * 1e6, 'filterpy_us': t_fp / steps * 1e6,
            'speed_ratio_vs_filterpy': t_fp / t_ours}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--rtf', type=float, nargs='*', default=[5.0, 10.0, 0.0])
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--plots', action='store_true', help='runs with the report and plots, as the main job')
    a = ap.parse_args()
    b = batch(a.repeat)
    print(f"batch pipeline (catapult, 68 s): simulate {b['simulate_s']:.3f} s, filter {b['filter_s']:.3f} s "
          f"({b['filter_us_per_step']:.0f} us/step); RTF whole pipeline {b['rtf_pipeline']:.0f}x, "
          f"filter alone {b['rtf_filter']:.0f}x")
    k = kf_peer()
    print(f"12-state KF predict+update: ours {k['ours_us']:.1f} us, filterpy {k['filterpy_us']:.1f} us "
          f"-> {k['speed_ratio_vs_filterpy']:.2f}x filterpy's speed (Joseph form in both)")
    for rtf in a.rtf:
        g = graph(rtf, a.plots)
        print(f"graph at real_time_factor {rtf:g}: streaming RTF {g['streaming_rtf']:.2f}, "
              f"whole run incl. start-up {g['whole_run_rtf']:.2f}, first message {g['startup_s']:.2f} s "
              f"after the command, {g['messages']} messages, lost {g['lost']}; the command took "
              f"{g['command_s']:.2f} s{' with the report' if a.plots else ''}, its longest wait for "
              f"acknowledgements at a node's end {g['ack_wait_s']:.2f} s; the scored estimate "
              f"{'equals' if g['same_estimate'] else 'DIFFERS FROM'} the batch pipeline's")
        print('  CPU s per simulated minute: ' + ', '.join(
            f"{n} {c * 60.0 / g['sim_time_s']:.1f}" for n, c in g['cpu_s'].items() if c is not None))


if __name__ == '__main__':
    main()
