"""What the air-data estimators publish: labelled values with their 1-sigma (the truth topic
uses the same labels, so an estimate and its truth compare label by label)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

AIR_DATA_LABELS = ('mach', 'alpha_rad', 'beta_rad', 'tas_mps', 'static_pressure_pa', 'impact_pressure_pa',
                   'pressure_altitude_m', 'wind_east_mps', 'wind_north_mps', 'wind_up_mps')


@dataclass(frozen=True)
class AirDataEstimate:
    """Estimate at t (s): `labels` (AIR_DATA_LABELS, then the form's own states), `value` and
    `sigma` (1-sigma) per label; v_air_body (3,) FLU with its covariance (3, 3); wind_enu (3,)
    with its covariance; total (pitot) pressure and its sigma (Pa); `healthy` False once the
    filter has failed; `excluded_ports` the ports the fault detector took out."""
    t: float
    labels: tuple[str, ...]
    value: np.ndarray
    sigma: np.ndarray
    v_air_body: np.ndarray
    v_air_cov: np.ndarray
    wind_enu: np.ndarray
    wind_cov: np.ndarray
    total_pressure_pa: float
    total_pressure_sigma_pa: float
    healthy: bool = True
    excluded_ports: tuple[int, ...] = ()

    def get(self, label: str) -> float:
        return float(self.value[self.labels.index(label)])

    def sigma_of(self, label: str) -> float:
        return float(self.sigma[self.labels.index(label)])

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.value)) and np.all(np.isfinite(self.sigma)))
