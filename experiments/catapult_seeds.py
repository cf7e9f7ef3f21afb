"""Final misalignment error and 1-sigma per axis over N seeds of a scenario (batch pipeline).

    python experiments/catapult_seeds.py [--scenario catapult] [--seeds 20] [--set KEY=VALUE ...]

The scored estimate is the filter output at the last on-deck truth sample (the release),
as in run_graph's summary. Prints per-seed rows, RMS error, mean 1-sigma, and the fraction of
errors inside 2 sigma (about 95 % for an honest filter).
"""
from __future__ import annotations

import argparse

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.units import ARCMIN


def score(res: pipeline.BatchResult) -> tuple[np.ndarray, np.ndarray]:
    t_rel = max(t.t_ns for t in res.truth if t.on_deck)
    est = [e for e in res.estimates if e.t_ns <= t_rel][-1]
    mu = np.asarray(res.scenario.aircraft.misalignment_arcmin) * ARCMIN
    return est.misalignment - mu, est.misalignment_sigma


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--scenario', default='catapult_paper')
    ap.add_argument('--seeds', type=int, default=20)
    ap.add_argument('--first-seed', type=int, default=1)
    ap.add_argument('--set', dest='sets', action='append', default=[])
    a = ap.parse_args()
    ov = scenario.parse_overrides(a.sets)
    errs, sigs = [], []
    print(f"{'seed':>5}  {'err x':>8}{'err y':>8}{'err z':>8}  {'sig x':>7}{'sig y':>7}{'sig z':>7}   arcmin")
    for seed in range(a.first_seed, a.first_seed + a.seeds):
        res = pipeline.run(scenario.load(a.scenario, ov, seed=seed))
        e, s = score(res)
        errs.append(e)
        sigs.append(s)
        print(f"{seed:>5}  " + ''.join(f'{x / ARCMIN:>8.3f}' for x in e) + '  '
              + ''.join(f'{x / ARCMIN:>7.3f}' for x in s))
    errs, sigs = np.array(errs), np.array(sigs)
    print('RMS error     ' + ''.join(f'{x / ARCMIN:>8.3f}' for x in np.sqrt(np.mean(errs**2, 0))))
    print('mean error    ' + ''.join(f'{x / ARCMIN:>8.3f}' for x in np.mean(errs, 0)))
    print('mean 1 sigma  ' + ''.join(f'{x / ARCMIN:>8.3f}' for x in np.mean(sigs, 0)))
    print('|err| < 2 sig ' + ''.join(f'{x:>8.2f}' for x in np.mean(np.abs(errs) < 2 * sigs, 0)))


if __name__ == '__main__':
    main()
