"""Consistency monitor: is the filter consistent with its data? A consistent Kalman filter's
innovations are white with the covariance S it predicts, so the normalised innovation squared
(NIS) y^T S^-1 y of an update with m rows is chi-square with m degrees of freedom, and the sum
over a window of updates is chi-square with the window's total degrees of freedom D. A window
whose sum exceeds the chi-square quantile of D at 1 - warn_p fails: the filter is optimistic
(its covariance smaller than its errors), the dangerous direction. One failing window is a WARN
(cleared by the next passing one), `error_windows` failing in a row an ERROR that persists.
The test is one-sided: a pessimistic filter (NIS below its bound, e.g. a parked allowance wider
than the deck's motion) reports its mean but is not flagged (docs/engine.md)."""
from __future__ import annotations

import math
from dataclasses import dataclass

# the chi-square tail and quantile from scipy.special (what scipy.stats' chi2.sf / chi2.isf call, the
# same numbers): importing scipy.stats costs a node ~1 s of start-up
from scipy.special import chdtrc, chdtri

from alignment_core.estimation.health import ERROR, OK, WARN


@dataclass(frozen=True)
class WindowResult:
    """One completed window: the NIS sum, its degrees of freedom, the bound and the tail probability."""
    nis_sum: float
    dof: int
    bound: float            # chi2(dof) quantile at 1 - warn_p
    p: float                # P(chi2(dof) > nis_sum)
    failed: bool

    @property
    def mean_per_dof(self) -> float:
        """NIS sum / dof: 1 for a consistent filter (sd sqrt(2 / dof))."""
        return self.nis_sum / self.dof


class NisMonitor:
    """The windowed NIS test over blocks of `window` updates. `cap` (the innovation gate, if any)
    bounds each update's NIS: a gated outlier counts at the gate, updates gated one after another
    (the filter has lost its data) fail the window."""

    def __init__(self, window: int, warn_p: float, error_windows: int, cap: float | None = None) -> None:
        if window < 1 or not 0.0 < warn_p < 1.0 or error_windows < 1:
            raise ValueError(f'bad monitor settings: window {window}, warn_p {warn_p}, error_windows {error_windows}')
        self.window = window
        self.warn_p = warn_p
        self.error_windows = error_windows
        self.cap = cap
        self._bounds: dict[int, float] = {}
        self._sum = 0.0
        self._dof = 0
        self._n = 0
        self.completed = 0          # windows completed
        self.failures = 0           # windows failed
        self.fails_in_row = 0
        self.last: WindowResult | None = None
        self._error = False

    @property
    def level(self) -> int:
        if self._error:
            return ERROR
        return WARN if self.fails_in_row else OK

    def bound(self, dof: int) -> float:
        """The chi2(dof) quantile at 1 - warn_p (cached per dof)."""
        b = self._bounds.get(dof)
        if b is None:
            b = self._bounds[dof] = float(chdtri(dof, self.warn_p))
        return b

    def add(self, nis: float, dof: int) -> WindowResult | None:
        """One update's NIS (non-finite ones are skipped); the window's result when it completes."""
        if not math.isfinite(nis) or dof < 1:
            return None
        self._sum += nis if self.cap is None else min(nis, self.cap)
        self._dof += dof
        self._n += 1
        if self._n < self.window:
            return None
        d, s = self._dof, self._sum
        self._sum, self._dof, self._n = 0.0, 0, 0
        b = self.bound(d)
        failed = s > b
        res = WindowResult(s, d, b, float(chdtrc(d, s)), failed)
        self.last = res
        self.completed += 1
        if failed:
            self.failures += 1
            self.fails_in_row += 1
            if self.fails_in_row >= self.error_windows:
                self._error = True
        else:
            self.fails_in_row = 0
        return res

    def restart(self) -> None:
        """Drop the window in progress (the next one starts with the next update), e.g. after a
        gap: the first window completed afterwards holds only updates after it."""
        self._sum, self._dof, self._n = 0.0, 0, 0

    def summary(self) -> dict[str, float | int | str]:
        """The last window for /diagnostics (empty before the first)."""
        r = self.last
        if r is None:
            return {}
        return {'nis_window_mean': r.mean_per_dof, 'nis_window_bound': r.bound / r.dof, 'nis_window_p': r.p,
                'nis_windows_failed': self.failures, 'nis_windows': self.completed}
