"""Check that a change leaves the batch pipeline's numbers as they were: run a few seeds of the
`deck`, `catapult` and `catapult` (schuler model, master delay state) scenarios, and the other
filters of the bank (float32 Kalman and UD, fading, strong tracking, cubature, vm12), save
every estimate's arrays, or compare them with a saved file.

    python bench/same_numbers.py save REF.npz [--seconds S]
    python bench/same_numbers.py compare REF.npz [--seconds S]

compare prints, per case, whether the estimates are bitwise equal and otherwise the largest
difference of the misalignment (rad) and of any other field.
"""
from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from alignment_core import pipeline
from alignment_core.config import scenario

CASES: list[tuple[str, int, dict]] = [
    ('deck_paper', 1, {}), ('deck_paper', 7, {}), ('catapult_paper', 1, {}), ('catapult_paper', 3, {}),
    ('catapult', 1, {}), ('deck', 1, {}),
    ('deck_paper', 3, {'filter.float32': True}), ('catapult_paper', 3, {'filter.float32': True}),
    ('deck_paper', 3, {'filter.algorithm': 'ud', 'filter.float32': True}),
    ('deck_paper', 3, {'filter.algorithm': 'fading'}), ('catapult_paper', 3, {'filter.algorithm': 'stf'}),
    ('catapult_paper', 3, {'filter.algorithm': 'ckf'}), ('catapult_paper', 3, {'filter.model': 'vm12'})]
SKIP = {'report', 'flags', 'fading'}


def arrays(name: str, seed: int, overrides: dict, seconds: float) -> dict[str, np.ndarray]:
    """Every numeric field of every estimate of one run, stacked by field."""
    sc = scenario.load(name, {**overrides, **({'duration_s': seconds} if seconds else {})}, seed=seed)
    res = pipeline.run(sc, keep_truth=False)
    out: dict[str, list] = {}
    for e in res.estimates:
        for f in dataclasses.fields(e):
            v = getattr(e, f.name)
            if f.name in SKIP or v is None:
                continue
            out.setdefault(f.name, []).append(np.asarray(v, dtype=float).ravel())
    counters = dataclasses.asdict(res.filter.counters)
    out['counters'] = [np.array([float(v) for v in counters.values()])]
    return {k: np.concatenate(v) for k, v in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('mode', choices=['save', 'compare'])
    ap.add_argument('path')
    ap.add_argument('--seconds', type=float, default=None, help='default: each scenario\'s own duration')
    a = ap.parse_args()
    runs = {'_'.join([n, str(s), *(f'{k.split(".")[-1]}={v}' for k, v in o.items())]): arrays(n, s, o, a.seconds)
            for n, s, o in CASES}
    if a.mode == 'save':
        np.savez(a.path, **{f'{c}/{k}': v for c, d in runs.items() for k, v in d.items()})
        print(f'saved {len(runs)} runs to {a.path}')
        return
    ref = np.load(a.path)
    ok = True
    for c, d in runs.items():
        keys = {k.split('/', 1)[1] for k in ref.files if k.startswith(c + '/')}
        if keys != set(d):
            print(f'{c}: fields differ: {sorted(keys ^ set(d))}')
            ok = False
            continue
        worst = {k: float(np.nanmax(np.abs(d[k] - ref[f'{c}/{k}']), initial=0.0))
                 if d[k].shape == ref[f'{c}/{k}'].shape else np.inf for k in d}
        same = all(d[k].shape == ref[f'{c}/{k}'].shape and np.array_equal(d[k].view(np.int64),
                                                                          ref[f'{c}/{k}'].view(np.int64))
                   for k in d)                    # bit patterns: a -0.0 for a 0.0 counts as a change
        ok &= same
        field = max(worst, key=lambda k: worst[k])
        print(f'{c}: {"bitwise equal" if same else "DIFFERENT"}; max |diff| misalignment '
              f'{worst["misalignment"]:.3e} rad, any field {worst[field]:.3e}'
              + (f' ({field})' if worst[field] else ''))
    raise SystemExit(0 if ok else 1)


if __name__ == '__main__':
    main()
