"""Named sensor grades (`imu.preset: seed001`, `master.preset: seed000`).

A preset fills the keys of its section that the scenario does not give: explicit keys always
win (defaults < preset < keys in the scenario file and --set overrides). It is resolved when a
scenario is loaded (scenario.from_dict); node parameters and params files carry the resolved
values, with the preset name kept for the record. Presets set a grade, never a mode
(imu.output, master.model, rates and latencies stay separate keys).

Where a paper is silent (noise densities of seeds 000/001), the value is the project's
default or typical of the grade, as the comment says.
"""
from __future__ import annotations

from alignment_core.validation import ConfigError

IMU_PRESETS: dict[str, dict[str, float]] = {
    # seed 000 slave: 0.01 deg/h, 100 ug random constants (noise: the project's defaults)
    'seed000': dict(gyro_bias_dph=0.01, accel_bias_ug=100.0, arw_dpsh=0.001, vrw_ugpshz=10.0),
    # seed 001: medium grade (1 nmi/h): constant 0.02 deg/h and 1e-4 g, random 0.01 deg/h and
    # 5e-5 g with 10800 s correlation time; white noise not stated (typical of the grade)
    'seed001': dict(gyro_bias_dph=0.02, accel_bias_ug=100.0, gyro_bias_instability_dph=0.01,
                    accel_bias_instability_ug=50.0, bias_corr_time_s=10800.0,
                    arw_dpsh=0.003, vrw_ugpshz=20.0),
    # seed 002: bias 0.01 deg/h and 1e-4 g, random 0.001 deg/sqrt(h) and 1e-5 g/sqrt(Hz),
    # scale factors 1e-4
    'seed002': dict(gyro_bias_dph=0.01, accel_bias_ug=100.0, arw_dpsh=0.001, vrw_ugpshz=10.0,
                    gyro_scale_ppm=100.0, accel_scale_ppm=100.0),
    # seed 003: missile grade, drift 0.2 deg/h, noise 0.01 deg/sqrt(h), bias 2 mg, noise 0.5 mg
    'seed003': dict(gyro_bias_dph=0.2, accel_bias_ug=2000.0, arw_dpsh=0.01, vrw_ugpshz=500.0),
    # navigation-grade aircraft INS (ring-laser gyros): 0.005 deg/h, 25 ug
    'nav_aircraft': dict(gyro_bias_dph=0.005, accel_bias_ug=25.0, arw_dpsh=0.002, vrw_ugpshz=5.0,
                         gyro_bias_instability_dph=0.002, accel_bias_instability_ug=5.0,
                         bias_corr_time_s=3600.0, gyro_scale_ppm=5.0, accel_scale_ppm=50.0,
                         gyro_nonorth_arcsec=3.0, accel_nonorth_arcsec=5.0,
                         angle_quantum_arcsec=0.1, velocity_quantum_mps=1e-4),
    # MEMS IMU of a store/missile: 10 deg/h, 1 mg, with instability, random walk, g-sensitivity
    'mems_store': dict(gyro_bias_dph=10.0, accel_bias_ug=1000.0, arw_dpsh=0.15, vrw_ugpshz=80.0,
                       gyro_bias_instability_dph=3.0, accel_bias_instability_ug=50.0,
                       bias_corr_time_s=300.0, gyro_scale_ppm=500.0, accel_scale_ppm=500.0,
                       gyro_nonorth_arcsec=60.0, accel_nonorth_arcsec=60.0,
                       gyro_bias_rw_dphps=0.01, accel_bias_rw_ugps=0.2,
                       gyro_g_sensitivity_dphpg=5.0,
                       angle_quantum_arcsec=0.5, velocity_quantum_mps=1e-4),
}

MASTER_PRESETS: dict[str, dict[str, float]] = {
    # seed 000 master: 0.001 deg/h, 50 ug
    'seed000': dict(gyro_bias_dph=0.001, accel_bias_ug=50.0, velocity_noise_mps=0.001),
    # the low end of a carrier's master INS (architecture notes: 0.001-0.01 deg/h, 10-50 ug)
    'ship_medium': dict(gyro_bias_dph=0.01, accel_bias_ug=50.0, velocity_noise_mps=0.001),
}

PRESETS = {'imu': IMU_PRESETS, 'master': MASTER_PRESETS}


def check_preset(section: str, name: str, table: dict) -> None:
    """'' (none) or a known name; otherwise a ConfigError listing the names."""
    if name and name not in table:
        raise ConfigError(f"{section}.preset: unknown preset {name!r} "
                          f"(available: {', '.join(sorted(table))})")


def apply(data: dict) -> dict:
    """Fill each section's missing keys from its preset (in place; returns data)."""
    for section, table in PRESETS.items():
        sec = data.get(section)
        if not isinstance(sec, dict) or not sec.get('preset'):
            continue
        name = sec['preset']
        if not isinstance(name, str):
            raise ConfigError(f"{section}.preset: expected a string, got {name!r}")
        check_preset(section, name, table)
        for k, v in table[name].items():
            sec.setdefault(k, v)
    return data
