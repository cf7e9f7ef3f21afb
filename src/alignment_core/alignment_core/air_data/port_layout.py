"""Where the flush ports sit on the nose and the eps(M) calibration of their pressure model
(air_data/ports.py): the configuration a scenario names, apart from the model's physics so that
loading a scenario does not load the atmosphere."""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from alignment_core.validation import require

if TYPE_CHECKING:
    from scipy.interpolate import PchipInterpolator


@dataclass(frozen=True)
class PortGeometry:
    """Cone and clock angles (deg) of the ports, one entry per port."""
    cone_deg: tuple[float, ...] = (0.0, 30.0, 30.0, 30.0, 30.0)
    clock_deg: tuple[float, ...] = (0.0, 0.0, 90.0, 180.0, 270.0)

    def validate(self) -> None:
        require(len(self.cone_deg) == len(self.clock_deg) >= 3,
                f"cone_deg and clock_deg need the same length (>= 3), got {len(self.cone_deg)}, {len(self.clock_deg)}")
        require(all(0.0 <= c < 90.0 for c in self.cone_deg), f"cone angles must be in [0, 90) deg: {self.cone_deg}")

    @property
    def count(self) -> int:
        return len(self.cone_deg)

    @cached_property
    def normals(self) -> np.ndarray:
        """Outward unit normals (n, 3) in FLU body axes."""
        lam, phi = np.deg2rad(self.cone_deg), np.deg2rad(self.clock_deg)
        return np.stack([np.cos(lam), -np.sin(lam) * np.sin(phi), -np.sin(lam) * np.cos(phi)], axis=-1)


@dataclass(frozen=True)
class EpsilonCalibration:
    """eps(M): a monotone cubic (PCHIP) through the table, held constant beyond its ends."""
    mach: tuple[float, ...] = (0.0, 0.6, 0.9, 1.1, 1.5, 2.5, 4.0)
    eps: tuple[float, ...] = (-0.10, -0.10, -0.05, 0.02, 0.05, 0.02, 0.0)

    def validate(self) -> None:
        require(len(self.mach) == len(self.eps) >= 2, "mach and eps need the same length (>= 2)")
        require(all(b > a for a, b in zip(self.mach, self.mach[1:])), f"mach must increase: {self.mach}")
        require(all(e < 1.0 for e in self.eps), f"eps must be < 1 (eps = 1 erases the angles): {self.eps}")

    @classmethod
    def constant(cls, eps: float) -> EpsilonCalibration:
        return cls(mach=(0.0, 1.0), eps=(eps, eps))

    @cached_property
    def _curve(self) -> PchipInterpolator:
        from scipy.interpolate import PchipInterpolator  # not at import: a scenario's config loads this module
        return PchipInterpolator(np.asarray(self.mach), np.asarray(self.eps), extrapolate=False)

    def _clamped(self, mach: np.ndarray | float) -> np.ndarray:
        return np.clip(np.asarray(mach, dtype=float), self.mach[0], self.mach[-1])

    def __call__(self, mach: np.ndarray | float) -> np.ndarray:
        return np.asarray(self._curve(self._clamped(mach)), dtype=float)

    def slope(self, mach: np.ndarray | float) -> np.ndarray:
        """d eps / dM (0 beyond the table's ends)."""
        m = np.asarray(mach, dtype=float)
        inside = (m > self.mach[0]) & (m < self.mach[-1])
        return np.where(inside, self._curve.derivative()(self._clamped(m)), 0.0)
