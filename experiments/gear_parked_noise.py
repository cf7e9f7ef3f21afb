"""The velocity noise the landing gear puts between the deck point and the IMU, parked.

    python experiments/gear_parked_noise.py [--seeds 2] [--duration 600] [--speed-kn 20]

A parked match compares the IMU's velocity with the rigid deck point's (master velocity plus
lever-arm velocity). On its gear (aircraft.gear, docs/landing-gear.md) the airframe moves
relative to that point: its IMU point's velocity relative to the deck, in ship axes, is the
noise this prints, for the realistic carrier (spectral sea, closed-form RAOs, cos^2
spreading, straight course) at sea states 4 and 5 in head, bow-quartering and beam seas, with
Dryden gusts of the wind over the deck (moderate, 15 m/s); then the same with the deck alone
(no gusts) and the gusts alone (calm sea), to say which drives it.

Per case, over the seeds (the first 20 s dropped): the RMS per ship axis (x fwd, y left, z up)
and of the norm, mm/s; the share of the variance below 0.5 Hz (the wave band: the airframe
following the deck's specific force quasi-statically) and the frequency of the spectrum's peak
(Welch, 164 s segments), with the RMS of the norm in each band; the white-equivalent sigma at the
sample rate f_s in the filter's band, sqrt(max G(f) f_s / 2) over 0.02-0.2 Hz (G: the norm's
one-sided spectrum; a white sequence of that sigma has the noise's largest density there, which
is what a filter averaging for tens of seconds sees); and the airframe's relative attitude (gear
roll, pitch, yaw) RMS in arcminutes.
"""
from __future__ import annotations

import argparse

import numpy as np
from scipy.signal import welch

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.samples import ShipBatch
from alignment_core.units import ARCMIN

SKIP_S = 20.0
SPLIT_HZ = 0.5


def relative_motion(sea_state: int, wave_heading_deg: float, gust: str, seed: int, duration_s: float,
                    speed_kn: float) -> tuple[np.ndarray, np.ndarray, float]:
    """IMU-point velocity relative to the deck (K, 3; ship axes, m/s), gear rotation (K, 3; rad)
    and the sample rate, for one run of the `deck_paper` scenario on a spectral carrier sea."""
    sc = scenario.load('deck_paper', {'seed': seed, 'duration_s': duration_s, 'ship.mode': 'spectral',
                                      'ship.sea_state': sea_state, 'ship.wave_heading_deg': wave_heading_deg,
                                      'ship.speed_kn': speed_kn, 'aircraft.gear.enabled': True,
                                      'aircraft.gear.gust_severity': gust})
    ships = ShipBatch.of(pipeline.ship_samples(sc))
    kin = pipeline.SlaveImuStage(sc).kin
    kin.truth_batch(ships, (ships.t_ns - sc.t0_ns) / 1e9)        # simulates the gear on the way
    k = np.arange(int(SKIP_S * sc.rate_hz), kin.gear.response.n)
    v = np.einsum('ij,kj->ki', kin.gear.c_ds, kin.gear.response.imu_at(k)[1])
    return v, kin.gear.response.rotation_at(k)[0], sc.rate_hz


def summary(vs: list[np.ndarray], ths: list[np.ndarray], rate: float) -> dict[str, np.ndarray | float]:
    v, th = np.concatenate(vs), np.concatenate(ths)
    var = (v**2).mean(axis=0)
    f, g = welch(np.stack(vs, 0), fs=rate, nperseg=min(2**14, len(vs[0])), axis=1)
    g = g.mean(axis=0)                                           # (F, 3) one-sided, (m/s)^2 / Hz
    tot = g.sum(axis=1)
    low = tot[f < SPLIT_HZ].sum() / tot.sum()
    norm = float(np.sqrt(var.sum()))
    return {'rms': np.sqrt(var), 'norm': norm, 'low': float(low), 'rms_low': norm * np.sqrt(low),
            'rms_high': norm * np.sqrt(1.0 - low), 'peak_hz': float(f[np.argmax(tot)]),
            'white': float(np.sqrt(tot[(f >= 0.02) & (f <= 0.2)].max() * rate / 2.0)),
            'theta': np.sqrt((th**2).mean(axis=0)) / ARCMIN}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=2)
    ap.add_argument('--duration', type=float, default=600.0)
    ap.add_argument('--speed-kn', type=float, default=20.0)
    a = ap.parse_args()
    cases = [(ss, hd, 'moderate') for ss in (4, 5) for hd in (180.0, 135.0, 90.0)]
    cases += [(5, 90.0, 'none'), (5, 135.0, 'none'), (0, 180.0, 'moderate')]
    print(f"deck_paper scenario, spot (40, -10, 15) m, spectral carrier at {a.speed_kn:g} kn, cos2 spreading; "
          f"gear defaults; {a.seeds} seeds x {a.duration:g} s (first {SKIP_S:g} s dropped)\n")
    print("| sea state | waves from | gusts | RMS x / y / z (mm/s) | RMS norm (mm/s) | below / above 0.5 Hz "
          "(mm/s) | peak (Hz) | white-equivalent (mm/s) | gear roll / pitch / yaw RMS (') |")
    print("|---|---|---|---|---|---|---|---|---|")
    for ss, hd, gust in cases:
        runs = [relative_motion(ss, hd, gust, s, a.duration, a.speed_kn) for s in range(1, a.seeds + 1)]
        r = summary([x[0] for x in runs], [x[1] for x in runs], runs[0][2])
        rms, th = r['rms'] * 1e3, r['theta']
        print(f"| {ss} | {180.0 - hd:g} deg off the bow | {gust} | {rms[0]:.2f} / {rms[1]:.2f} / {rms[2]:.2f} "
              f"| {1e3 * r['norm']:.2f} | {1e3 * r['rms_low']:.2f} / {1e3 * r['rms_high']:.2f} "
              f"| {r['peak_hz']:.2f} | {1e3 * r['white']:.2f} | {th[0]:.2f} / {th[1]:.2f} / {th[2]:.2f} |", flush=True)


if __name__ == '__main__':
    main()
