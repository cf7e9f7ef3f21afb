"""Carrier motion by sea state (spectral mode) beside seed 002's Table 3 amplitudes.

    python experiments/ship_table.py [--seeds 5] [--spreading cos2|none] [--rao closed_form|PATH]
                                     [--time-domain HOURS]

For sea states 3-8, head seas (wave heading 180 deg) and beam seas (90 deg, waves from
port), at 0 and 20 kn: significant amplitudes (2 sigma) of roll, pitch (deg) and heave (m),
and their mean zero-crossing periods Tz = 2 pi sqrt(m0/m2) in encounter frequency (s).
Frequency domain over the synthesised components (sum |H|^2 A^2 / 2), averaged over
--seeds realisations of the random in-bin frequencies; --time-domain H also measures 2 std
of an H-hour record of the first seed (a check of the synthesis).

Seed 002's Table 3 gives sinusoid amplitudes A (roll/pitch/yaw, deg); a sinusoid of
amplitude A has sigma = A / sqrt(2), i.e. the significant amplitude of the equivalent
random motion is sqrt(2) A (printed as "paper 2sigma").
"""
from __future__ import annotations

import argparse

import numpy as np

from alignment_core.ship.config import PAPER_TABLE3_DEG, ShipConfig
from alignment_core.ship.spectral import SpectralShipMotion

RAD2DEG = 180.0 / np.pi


def stats(cfg: ShipConfig, seeds: int) -> tuple[np.ndarray, np.ndarray]:
    """Mean over seeds of 2 sigma (6,) and Tz (6,)."""
    sig2, tz = [], []
    for s in range(1, seeds + 1):
        wf = SpectralShipMotion(cfg, s).wf
        m0, m2 = wf.variance(), wf.moments(2)
        sig2.append(2.0 * np.sqrt(m0))
        tz.append(2.0 * np.pi * np.sqrt(m0 / np.where(m2 > 0, m2, np.inf)))
    return np.mean(sig2, axis=0), np.mean(tz, axis=0)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=5)
    ap.add_argument('--spreading', default='cos2', choices=['cos2', 'none'])
    ap.add_argument('--rao', default='closed_form')
    ap.add_argument('--time-domain', type=float, default=0.0)
    a = ap.parse_args()
    print("Carrier (closed-form RAOs: Lpp 310 m, B 40.5 m, T 11.3 m, T4 20 s, zeta4 0.05-0.10)"
          if a.rao == 'closed_form' else f"RAOs from {a.rao}")
    print(f"ITTC spectrum, Bales Hs/Tp, {a.spreading} spreading, mean of {a.seeds} seeds; "
          f"significant amplitude = 2 sigma; Tz in encounter frequency\n")
    hdr = ('| SS | Hs m | Tp s | waves | kn | roll 2s deg | pitch 2s deg | heave 2s m | '
           'Tz roll s | Tz pitch s | Tz heave s | paper A r/p/y deg | paper 2sigma r/p/y deg |')
    if a.time_domain > 0:
        hdr += ' time-domain 2s r/p/h |'
    print(hdr)
    print('|' + '---|' * (hdr.count('|') - 1))
    for ss in range(3, 9):
        for heading, name in ((180.0, 'head'), (90.0, 'beam')):
            for kn in (0.0, 20.0):
                cfg = ShipConfig(mode='spectral', sea_state=ss, speed_kn=kn, wave_heading_deg=heading,
                                 spreading=a.spreading, rao_source=a.rao)
                s2, tz = stats(cfg, a.seeds)
                sea = SpectralShipMotion(cfg, 1).sea
                pa = PAPER_TABLE3_DEG.get(ss)   # the paper gives 3-7 only
                pap = '/'.join(f'{x:.2f}' for x in pa) if pa else '-'
                pas = '/'.join(f'{np.sqrt(2) * x:.2f}' for x in pa) if pa else '-'
                row = (f'| {ss} | {sea.hs_m:.2f} | {sea.tp_s:.1f} | {name} | {kn:.0f} | '
                       f'{s2[3] * RAD2DEG:.2f} | {s2[4] * RAD2DEG:.2f} | {s2[2]:.2f} | '
                       f'{tz[3]:.1f} | {tz[4]:.1f} | {tz[2]:.1f} | {pap} | {pas} |')
                if a.time_domain > 0:
                    t = np.arange(0.0, a.time_domain * 3600.0, 0.5)
                    x = SpectralShipMotion(cfg, 1).wf.evaluate(t)
                    row += (f' {2 * x[:, 3].std() * RAD2DEG:.2f}/{2 * x[:, 4].std() * RAD2DEG:.2f}/'
                            f'{2 * x[:, 2].std():.2f} |')
                print(row)


if __name__ == '__main__':
    main()
