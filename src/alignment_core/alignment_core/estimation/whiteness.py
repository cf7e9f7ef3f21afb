"""Innovation whiteness: are the filter's innovations uncorrelated in time, as a consistent
Kalman filter's are? A timing error nobody modelled (a master latency, an LDV lag) makes the
innovation follow the ship's acceleration times the lag: smooth, strongly correlated from one
update to the next, while the NIS may still look acceptable against a generous noise allowance.

Test (docs/engine.md, innovation whiteness): over a window of N accepted master updates with m
rows each, every row's normalised innovation e = y_i / sqrt(S_ii) (mean removed over the
window) gives the sample autocorrelation r_k = sum_t e_t e_(t+k) / sum_t e_t^2 at lags
k = 1..K, and the Ljung-Box statistic Q = N (N + 2) sum_k r_k^2 / (N - k), chi-square with K
degrees of freedom for a white sequence. The rows' statistics are summed (chi-square with m K
degrees of freedom, taking the rows as independent); the window fails when its tail probability
is below `whiteness_p`. Also reported: the largest |r_1| of the rows against the 95 % band of a
white sequence, 1.96 / sqrt(N). The test informs (/diagnostics, the engine's outputs); it does
not change the health level."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

# the chi-square tail and quantile from scipy.special (what scipy.stats' chi2.sf calls, the
# same numbers): importing scipy.stats costs a node ~1 s of start-up
from scipy.special import chdtrc

from alignment_core.compiled import as_float, as_float64, kernel


@dataclass(frozen=True)
class WhitenessResult:
    """One completed window: Ljung-Box Q (summed over rows), its degrees of freedom, its tail
    probability, the largest lag-1 autocorrelation of a row and the white band 1.96 / sqrt(N)."""
    q: float
    dof: int
    p: float
    r1_max: float
    band: float
    failed: bool


def ljung_box(e: np.ndarray, lags: int) -> tuple[np.ndarray, np.ndarray]:
    """(Q per column, r (lags, columns)) of the columns of e (N, m), each with its mean removed."""
    n = e.shape[0]
    d = e - e.mean(axis=0)
    den = np.sum(d * d, axis=0)
    den = np.where(den > 0.0, den, np.inf)
    r = np.array([np.sum(d[k:] * d[:-k], axis=0) / den for k in range(1, lags + 1)])
    k = np.arange(1, lags + 1)[:, None]
    return n * (n + 2.0) * np.sum(r * r / (n - k), axis=0), r


class InnovationWhiteness:
    """The windowed Ljung-Box test over blocks of `window` accepted updates."""

    def __init__(self, window: int, lags: int, p_fail: float, keep_history: bool = True) -> None:
        """keep_history False (a node): `history` stays empty, so memory does not grow with the run."""
        if window < 10 or not 1 <= lags < window // 2 or not 0.0 < p_fail < 1.0:
            raise ValueError(f'bad whiteness settings: window {window}, lags {lags}, p {p_fail}')
        self.window, self.lags, self.p_fail = window, lags, p_fail
        self._rows: list[np.ndarray] = []
        self.completed = 0
        self.failures = 0
        self.last: WhitenessResult | None = None
        self.history: list[tuple[WhitenessResult, int]] = []    # (result, updates seen) per window
        self._keep_history = keep_history
        self._seen = 0

    def add(self, innovation: np.ndarray, s: np.ndarray) -> WhitenessResult | None:
        """One accepted update's innovation (m,) and its covariance S (m, m); the window's result
        when it completes. A change of m (rows added or dropped) restarts the window."""
        ok, e = normalised(as_float64(innovation), as_float(s))
        if not ok:
            return None
        if self._rows and len(self._rows[0]) != len(e):
            self._rows = []
        self._rows.append(e)
        self._seen += 1
        if len(self._rows) < self.window:
            return None
        q_rows, r = ljung_box(np.array(self._rows), self.lags)
        self._rows = []
        q = float(np.sum(q_rows))
        dof = self.lags * len(q_rows)
        p = float(chdtrc(dof, q))
        res = WhitenessResult(q, dof, p, float(np.max(np.abs(r[0]))), 1.96 / math.sqrt(self.window),
                              p < self.p_fail)
        self.last = res
        self.completed += 1
        self.failures += res.failed
        if self._keep_history:
            self.history.append((res, self._seen))
        return res

    def restart(self) -> None:
        """Drop the window in progress (after a gap)."""
        self._rows = []

    def summary(self) -> dict[str, float | int | str]:
        """The last window for /diagnostics (empty before the first)."""
        r = self.last
        if r is None:
            return {}
        return {'whiteness': 'fail' if r.failed else 'pass', 'whiteness_q': r.q, 'whiteness_dof': r.dof,
                'whiteness_p': r.p, 'whiteness_r1_max': r.r1_max, 'whiteness_band': r.band,
                'whiteness_windows': self.completed, 'whiteness_windows_failed': self.failures}


@kernel
def normalised(y, s):
    """(True, e) with e_i = y_i / sqrt(S_ii) of an innovation y (m,) and its covariance s (m, m),
    the root in S's precision; (False, y) when an element of y is not finite or a variance is
    not positive (NaN included)."""
    e = np.empty_like(y)
    for i in range(y.shape[0]):
        v = s[i, i]
        if not (-math.inf < y[i] < math.inf and v > 0.0):
            return False, y
        e[i] = y[i] / np.sqrt(v)
    return True, e
