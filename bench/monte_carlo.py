"""Monte Carlo throughput: runs per minute of the 300 s `deck` scenario with 1 and 2 worker
processes (target: 100 runs in under 5 minutes on this 2-core machine), and the alignment
workload (strapdown + error-state filter with a velocity update at every IMU step) against
python-ins (pyins) on the same IMU + velocity workload, measured in the same run.

    scripts/bench.sh monte_carlo [--runs 8] [--scenario deck]

Peer workload: --peer-seconds (default 20 s; per-step times are compared) of 100 Hz IMU
increments and 100 Hz NED velocity measurements through
`pyins.filters.run_feedback_filter` (its covariance step set to the IMU period, as ours);
ours: `TransferAlignment` on the simulated `deck` inputs (IMU, LDV, master at 100 Hz).
The simulation (ship, IMU, sensors) is not timed in the peer comparison: only the filters.
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.ship import track
from alignment_experiments import monte_carlo


def throughput(name: str, runs: int, workers: int) -> float:
    specs = [monte_carlo.RunSpec(index=i, cell='bench', scenario=name, overrides=(), seed=100 + i,
                                 score_at=250.0) for i in range(runs)]
    track.forget_shared_starts()            # each pass starts as a fresh study would: no ship track kept
    t = time.perf_counter()
    monte_carlo.run_many(specs, workers=workers, progress=False)
    return time.perf_counter() - t


def ours_filter_seconds(name: str) -> tuple[float, int]:
    sc = scenario.load(name, seed=1)
    inp = pipeline.simulate(sc)
    t = time.perf_counter()
    filt = pipeline.align(sc, inp)
    return time.perf_counter() - t, filt.counters.updates


def pyins_filter_seconds(duration_s: float, rate_hz: float, time_step: float) -> tuple[float, int] | None:
    try:
        import pandas as pd
        from pyins import filters, measurements, sim, strapdown
    except ImportError:
        return None
    dt = 1.0 / rate_hz
    traj, imu = sim.generate_sine_velocity_motion(dt, duration_s, [40.0, 116.0, 0.0], [5.0, 8.7, 0.0],
                                                  velocity_change_amplitude=[0.5, 0.5, 0.2],
                                                  velocity_change_period=10.0, sensor_type='increment')
    increments = strapdown.compute_increments_from_imu(imu, 'increment')
    vel = sim.generate_ned_velocity_measurements(traj, 0.01, rng=0)
    pva0 = traj.iloc[0]
    meas = [measurements.NedVelocity(pd.DataFrame(vel), 0.01)]
    # warm-up (numba compilation) on a short slice, then the timed run
    filters.run_feedback_filter(pva0, 1.0, 0.1, 1.0, 1.0, increments.iloc[:200],
                                measurements=[measurements.NedVelocity(vel.iloc[:200], 0.01)], time_step=time_step)
    t = time.perf_counter()
    filters.run_feedback_filter(pva0, 1.0, 0.1, 1.0, 1.0, increments, measurements=meas, time_step=time_step)
    return time.perf_counter() - t, len(vel)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--runs', type=int, default=8)
    ap.add_argument('--scenario', default='deck_paper')
    ap.add_argument('--peer-seconds', type=float, default=20.0,
                    help='simulated seconds of the pyins run (it is slow; per-step times are compared)')
    a = ap.parse_args()
    sc = scenario.load(a.scenario)
    print(f'{a.scenario}: {sc.duration_s:.0f} s at {sc.rate_hz:.0f} Hz; {a.runs} runs per setting; '
          f'{os.cpu_count()} CPUs')
    t1 = throughput(a.scenario, a.runs, 1)
    t2 = throughput(a.scenario, a.runs, 2)
    for w, t in ((1, t1), (2, t2)):
        rpm = 60.0 * a.runs / t
        print(f'  workers={w}: {t:7.1f} s  {rpm:6.1f} runs/min  -> 100 runs in {100 / rpm:5.1f} min')
    print(f'  speed-up 1 -> 2 workers: {t1 / t2:.2f}x')
    ours, n_ours = ours_filter_seconds(a.scenario)
    print(f'ours  (TransferAlignment, {n_ours} velocity updates): {ours:6.2f} s  '
          f'{1e6 * ours / n_ours:6.1f} us per IMU step + update')
    peer = pyins_filter_seconds(a.peer_seconds, sc.rate_hz, 1.0 / sc.rate_hz)
    if peer is None:
        print('pyins: not installed (scripts/bench.sh installs requirements-bench.txt)')
        return
    tp, n_p = peer
    print(f'pyins (run_feedback_filter, {n_p} velocity updates): {tp:6.2f} s  {1e6 * tp / n_p:6.1f} us per step')
    print(f'ratio ours / pyins: {ours / tp * (n_p / n_ours):.2f} (< 1: faster than pyins)')


if __name__ == '__main__':
    np.set_printoptions(precision=3)
    main()
