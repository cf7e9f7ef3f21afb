"""Cost of one predict + update for every filter of the bank, against filterpy's KalmanFilter on
the same workload in the same run; optionally seed 003's long single-precision run.

    python bench/filter_bank.py [--steps 3000] [--repeat 3] [--float32 [STEPS]] [--engine [SECONDS]]

Workloads (H as in the alignment filters):
  n=12, m=3: velocity matching, H = [0 I 0 0] (selects the velocity states);
  n=21, m=6: velocity + attitude matching, H = [[0 I 0 ...], [I 0 0 0 -C -C 0]] (seed 003).
Phi = expm(0.01 (K - K^T) - 1e-4 I) (dense, stable), Qd diagonal, R diagonal; measurements from a simulated truth so the
innovations are realistic (nothing is gated). Each step (predict + update) is timed on its own;
the table gives the median over all steps of the best of --repeat runs, in microseconds, and the
ratio to filterpy's median (< 1: faster than filterpy). Rows '(callables)' use
predict_nonlinear / update_nonlinear with Python callables for the same linear model.

--engine [SECONDS]: the transfer-alignment engine itself (TransferAlignment, what the filter node
runs per message) on a simulated deck run (default 60 s at sea state 4): the time per IMU step
with its master + LDV match (push the three samples, process), median / 95th percentile /
mean in microseconds, for seed003_21 (the 21-state node step; target < 200 us) beside vm15 (the
default) and vm15 with 20 ms of master latency (matching against the slave history); ratio =
median / the bare KalmanFilter predict + update on the n=21, m=6 workload timed in the same run
(what the machine's load does to both).

--float32: the closed-loop 21-state run of tests/filters/test_float32.py, longer (default
60000 steps = 600 s at 100 Hz): smallest eigenvalue of P and the worst |error| / sigma_64 of the
float32 KF, Carlson and UD filters against the float64 KF, every 10 s.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sla

from alignment_core.estimation.filters import (
    CarlsonFilter,
    CubatureKalmanFilter,
    ExtendedKalmanFilter,
    FadingMemoryFilter,
    KalmanFilter,
    SqrtFadingFilter,
    StrongTrackingFilter,
    UDFilter,
    UnscentedKalmanFilter,
)

ROOT = Path(__file__).resolve().parents[1]


def workload(n: int, m: int, steps: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    k = rng.standard_normal((n, n))
    phi = sla.expm(0.01 * (k - k.T) - 1e-4 * np.eye(n))      # dense, stable: the truth stays bounded
    qd = np.diag(rng.uniform(0.5, 2.0, n)) * 1e-6
    h = np.zeros((m, n))
    if m == 3:
        h[:, 3:6] = np.eye(3)
    else:
        c = np.array([[0.8, -0.6, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 1.0]])
        h[0:3, 3:6] = np.eye(3)
        h[3:6, 0:3] = np.eye(3)
        h[3:6, 12:15] = -c
        h[3:6, 15:18] = -c
    r = np.diag(rng.uniform(0.5, 2.0, m)) * 1e-4
    p0 = np.eye(n) * 1e-2
    x = rng.standard_normal(n) * 0.1
    zs = np.empty((steps, m))
    for k in range(steps):
        x = phi @ x + np.sqrt(np.diag(qd)) * rng.standard_normal(n)
        zs[k] = h @ x + np.sqrt(np.diag(r)) * rng.standard_normal(m)
    return phi, qd, h, r, p0, zs


FILTERS = {
    'KalmanFilter (Joseph)': lambda x, p: KalmanFilter(x, p),
    'KalmanFilter float32': lambda x, p: KalmanFilter(x, p, dtype=np.float32),
    'FadingMemory lam=1.01': lambda x, p: FadingMemoryFilter(x, p, lam=1.01),
    'FadingMemory tested g=3': lambda x, p: FadingMemoryFilter(x, p, gamma=3.0),
    'StrongTracking single': lambda x, p: StrongTrackingFilter(x, p),
    'StrongTracking multiple': lambda x, p: StrongTrackingFilter(x, p, alpha=np.ones(x.size)),
    'Carlson': lambda x, p: CarlsonFilter(x, p),
    'Carlson float32': lambda x, p: CarlsonFilter(x, p, dtype=np.float32),
    'UD (Bierman-Thornton)': lambda x, p: UDFilter(x, p),
    'UD float32': lambda x, p: UDFilter(x, p, dtype=np.float32),
    'Combined (003) g=3': lambda x, p: SqrtFadingFilter(x, p, gamma=3.0),
    'EKF': lambda x, p: ExtendedKalmanFilter(x, p),
    'UKF': lambda x, p: UnscentedKalmanFilter(x, p),
    'CKF': lambda x, p: CubatureKalmanFilter(x, p),
}
CALLABLES = {
    'EKF (callables, jacobians)': lambda x, p: ExtendedKalmanFilter(x, p),
    'UKF (callables)': lambda x, p: UnscentedKalmanFilter(x, p),
    'CKF (callables)': lambda x, p: CubatureKalmanFilter(x, p),
}


def time_filter(make, wl, callables: bool) -> float:
    phi, qd, h, r, p0, zs = wl
    f = make(np.zeros(phi.shape[0]), p0)
    fx, hx = (lambda x: phi @ x), (lambda x: h @ x)
    jf, jh = (lambda x: phi), (lambda x: h)
    ts = np.empty(len(zs))
    clock = time.perf_counter_ns
    for k, z in enumerate(zs):
        t0 = clock()
        if callables:
            f.predict_nonlinear(fx, qd, jac=jf)
            f.update_nonlinear(z, hx, r, jac=jh)
        else:
            f.predict(phi, qd)
            f.update(z, h, r)
        ts[k] = clock() - t0
    assert f.diagnostics()['gated'] == 0
    return float(np.median(ts)) * 1e-3


def time_filterpy(wl) -> float:
    from filterpy.kalman import KalmanFilter as FpKF
    phi, qd, h, r, p0, zs = wl
    n, m = h.shape[1], h.shape[0]
    f = FpKF(dim_x=n, dim_z=m)
    f.F, f.Q, f.H, f.R, f.P = phi, qd, h, r, p0.copy()
    ts = np.empty(len(zs))
    clock = time.perf_counter_ns
    for k, z in enumerate(zs):
        t0 = clock()
        f.predict()
        f.update(z)
        ts[k] = clock() - t0
    return float(np.median(ts)) * 1e-3


def bench(steps: int, repeat: int) -> None:
    sizes = [(12, 3), (21, 6)]
    wls = {s: workload(*s, steps) for s in sizes}
    rows = [(name, make, False) for name, make in FILTERS.items()] + \
           [(name, make, True) for name, make in CALLABLES.items()]
    fp = {s: min(time_filterpy(wls[s]) for _ in range(repeat)) for s in sizes}
    res = {}
    for name, make, cb in rows:
        res[name] = {s: min(time_filter(make, wls[s], cb) for _ in range(repeat)) for s in sizes}
    fp2 = {s: min(time_filterpy(wls[s]) for _ in range(repeat)) for s in sizes}   # drift check
    fp = {s: min(fp[s], fp2[s]) for s in sizes}
    print(f'median us per predict+update ({steps} steps, best of {repeat}); ratio = ours / filterpy')
    head = ''.join(f'{f"n={n} m={m}":>22}' for n, m in sizes)
    print(f'{"filter":30s}{head}')
    print(f'{"filterpy KalmanFilter":30s}' + ''.join(f'{fp[s]:10.1f} us {"1.00":>8}' for s in sizes))
    for name, _, _ in rows:
        print(f'{name:30s}' + ''.join(f'{res[name][s]:10.1f} us {res[name][s] / fp[s]:8.2f}' for s in sizes))
    kf = res['KalmanFilter (Joseph)']
    print('plain KF speed vs filterpy: ' + ', '.join(f'n={n}: {fp[(n, m)] / kf[(n, m)]:.2f}x' for n, m in sizes))


def float32_run(steps: int) -> None:
    sys.path.insert(0, str(ROOT / 'tests' / 'filters'))
    from filter_problems import seed003_model, sqrt_psd
    phi, qd, h, r, p0 = seed003_model(dt=0.01)
    n = phi.shape[0]
    rng = np.random.default_rng(2024)
    lq, lr = sqrt_psd(qd), np.linalg.cholesky(r)
    x0 = np.linalg.cholesky(p0) @ rng.standard_normal(n)
    fs = {'kf64': KalmanFilter(np.zeros(n), p0), 'kf32': KalmanFilter(np.zeros(n), p0, dtype=np.float32),
          'carlson32': CarlsonFilter(np.zeros(n), p0, dtype=np.float32),
          'ud32': UDFilter(np.zeros(n), p0, dtype=np.float32)}
    truth = {k: x0.copy() for k in fs}
    print('closed loop, seed-003 21-state model at 100 Hz; per filter: min eig P, max |e - e64| / sigma64, '
          'max |e| / own sigma')
    for k in range(steps):
        w, v = lq @ rng.standard_normal(n), lr @ rng.standard_normal(6)
        for name, f in fs.items():
            t = phi @ truth[name] + w
            f.predict(phi, qd)
            f.update(h @ t + v, h, r)
            truth[name] = t - f.x.astype(float)
            f.reset_state()
        if (k + 1) % 1000 == 0:
            sig64 = np.sqrt(np.diag(fs['kf64'].P))
            out = []
            for name, f in fs.items():
                p = f.P.astype(float)
                own = np.sqrt(np.abs(np.diag(p)))
                dev = np.max(np.abs(truth[name] - truth['kf64']) / sig64)
                worst = np.max(np.abs(truth[name]) / own)
                out.append(f'{name} {np.linalg.eigvalsh(p).min():+.1e} {dev:6.2f} {worst:6.1f}')
            print(f'{(k + 1) / 100:6.0f} s  ' + ' | '.join(out), flush=True)


ENGINE_CASES = {
    'seed003_21 (21 states, v + att)': {'filter.model': 'seed003_21'},
    'vm15 (default, 15 states)': {},
    'vm15, master latency 20 ms': {'master.latency_s': 0.02, 'filter.master_latency_s': 0.02},
}


def engine_run(seconds: float, repeat: int) -> None:
    from alignment_core import pipeline
    from alignment_core.config import scenario
    kf_us = min(time_filter(FILTERS['KalmanFilter (Joseph)'], workload(21, 6, 2000), False) for _ in range(repeat))
    print(f'TransferAlignment per IMU step + match, deck scenario, {seconds:g} s at 100 Hz, best of {repeat}; '
          f'bare KF step (n=21, m=6): {kf_us:.1f} us')
    print(f'{"case":36s}{"median us":>11}{"p95 us":>9}{"mean us":>9}{"ratio":>7}{"updates":>9}')
    for name, ov in ENGINE_CASES.items():
        sc = scenario.load('deck_paper', {'duration_s': seconds, **ov})
        inp = pipeline.simulate(sc)
        best, f = engine_step_times(sc, inp, repeat)
        print(f'{name:36s}{np.median(best):11.1f}{np.quantile(best, 0.95):9.1f}{best.mean():9.1f}'
              f'{np.median(best) / kf_us:7.1f}{f.counters.updates:9d}')


def engine_step_times(sc, inp, repeat: int):
    """(us per IMU step with its LDV + master pushes and process(), the first tenth skipped, of
    the fastest of `repeat` runs; that run's engine) for a simulated scenario."""
    from alignment_core import pipeline
    from alignment_core.estimation.engine import TransferAlignment
    best, best_f = None, None
    for _ in range(repeat):
        f = TransferAlignment(sc.filter, pipeline.plane_of(sc), sc.rate_hz)
        ts = np.empty(len(inp.imu))
        clock = time.perf_counter_ns
        j_l = j_m = 0
        for k, imu in enumerate(inp.imu):
            t = imu.t_ns
            t0 = clock()
            f.push_imu(imu)
            while j_l < len(inp.ldv) and inp.ldv[j_l].t_ns <= t:
                f.push_ldv(inp.ldv[j_l])
                j_l += 1
            while j_m < len(inp.master) and inp.master[j_m].t_ns <= t:
                f.push_master(inp.master[j_m])
                j_m += 1
            f.process()
            ts[k] = clock() - t0
        ts = ts[len(ts) // 10:] * 1e-3          # skip the first tenth (start-up, caches)
        if best is None or np.median(ts) < np.median(best):
            best, best_f = ts, f
    return best, best_f


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--steps', type=int, default=3000)
    ap.add_argument('--repeat', type=int, default=3)
    ap.add_argument('--float32', type=int, nargs='?', const=60000, default=None)
    ap.add_argument('--engine', type=float, nargs='?', const=60.0, default=None, metavar='SECONDS')
    a = ap.parse_args()
    if a.engine:
        engine_run(a.engine, a.repeat)
    elif a.float32:
        float32_run(a.float32)
    else:
        bench(a.steps, a.repeat)


if __name__ == '__main__':
    main()
