"""Tuning grades for the alignment filter (`filter.preset: navigation | tactical | mems`): the
slave IMU's error densities, bias priors and, where a real sensor's bias wanders over an
alignment, a bias random walk. A preset fills the `filter.*` keys the scenario does not give
(defaults < preset < keys in the scenario and --set), like the sensor presets
(sensors/presets.py); without a preset the defaults stay as they are. Numbers (docs/engine.md):
typical datasheet values of each grade, not fitted to this project's simulation.

The random walks stand for the bias instability over an alignment: a first-order Gauss-Markov
bias of sigma s and correlation time tau drifts like a random walk of density s sqrt(2 / tau)
over times short against tau (tau = 300 s here)."""
from __future__ import annotations

from alignment_core.validation import ConfigError

FILTER_PRESETS: dict[str, dict[str, float]] = {
    # ring-laser / fibre-optic navigation grade: 0.01 deg/h, 50 ug, ARW 0.002 deg/sqrt(h),
    # VRW 10 ug/sqrt(Hz); stable over an alignment (no random walk)
    'navigation': dict(gyro_bias_sigma_dph=0.01, accel_bias_sigma_ug=50.0, arw_dpsh=0.002,
                       vrw_ugpshz=10.0, gyro_bias_rw_dphps=0.0, accel_bias_rw_ugps=0.0),
    # tactical grade: 1 deg/h, 1 mg, ARW 0.1 deg/sqrt(h), VRW 50 ug/sqrt(Hz); instability
    # 0.5 deg/h and 50 ug over 300 s -> 0.04 deg/h/sqrt(s), 4 ug/sqrt(s)
    'tactical': dict(gyro_bias_sigma_dph=1.0, accel_bias_sigma_ug=1000.0, arw_dpsh=0.1,
                     vrw_ugpshz=50.0, gyro_bias_rw_dphps=0.04, accel_bias_rw_ugps=4.0),
    # MEMS: 10 deg/h, 5 mg (turn-on bias and scale factor times g), ARW 0.3 deg/sqrt(h),
    # VRW 100 ug/sqrt(Hz); instability 5 deg/h and 100 ug over 300 s -> 0.4 deg/h/sqrt(s), 8 ug/sqrt(s)
    'mems': dict(gyro_bias_sigma_dph=10.0, accel_bias_sigma_ug=5000.0, arw_dpsh=0.3,
                 vrw_ugpshz=100.0, gyro_bias_rw_dphps=0.4, accel_bias_rw_ugps=8.0),
}
PRESET_NAMES = tuple(FILTER_PRESETS)


def apply(data: dict) -> dict:
    """Fill the filter section's missing keys from `filter.preset` (in place; returns data)."""
    sec = data.get('filter')
    if not isinstance(sec, dict) or not sec.get('preset'):
        return data
    name = sec['preset']
    if not isinstance(name, str) or name not in FILTER_PRESETS:
        raise ConfigError(f"filter.preset: unknown preset {name!r} (available: {', '.join(PRESET_NAMES)})")
    for k, v in FILTER_PRESETS[name].items():
        sec.setdefault(k, v)
    return data
