"""WMO sea states and their significant wave height / peak period.

WMO sea-state code by significant wave height Hs (m): 0: 0; 1: 0-0.1; 2: 0.1-0.5;
3: 0.5-1.25; 4: 1.25-2.5; 5: 2.5-4; 6: 4-6; 7: 6-9; 8: 9-14; 9: > 14.

Defaults per code are the North-Atlantic annual table of Bales (1983), as used by NATO
STANAG 4194: mean Hs, the 5-95 % range of the modal (peak) period Tp and the most probable
Tp. Bales gives no period for codes 0-1; for code 1 we use the Pierson-Moskowitz fully
developed relation Tp = 4.99 sqrt(Hs) (Hs = 0.21 U^2/g, omega_p = 0.877 g/U) and its +-30 %.
The table stops at "> 14 m"; we take 14-18 m for code 9 (mean 16 m is our choice: Bales
lists only "> 14").

A Monte Carlo draw takes Hs uniform within the code's bin and Tp from a triangular law on
the 5-95 % range with its mode at the most probable period.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from alignment_core.validation import ConfigError

# WMO bins: code -> (Hs low, Hs high), m
WMO_HS_BIN_M = {0: (0.0, 0.0), 1: (0.0, 0.1), 2: (0.1, 0.5), 3: (0.5, 1.25), 4: (1.25, 2.5),
                5: (2.5, 4.0), 6: (4.0, 6.0), 7: (6.0, 9.0), 8: (9.0, 14.0), 9: (14.0, 18.0)}
# Bales (1983): mean Hs (m), Tp 5 % and 95 % (s), most probable Tp (s)
BALES = {1: (0.05, 0.8, 1.45, 1.1),
         2: (0.3, 3.3, 12.8, 7.5),
         3: (0.88, 5.0, 14.8, 7.5),
         4: (1.88, 6.1, 15.2, 8.8),
         5: (3.25, 8.3, 15.5, 9.7),
         6: (5.0, 9.8, 16.2, 12.4),
         7: (7.5, 11.8, 18.5, 15.0),
         8: (11.5, 14.2, 18.6, 16.4),
         9: (16.0, 18.0, 23.7, 20.0)}


@dataclass(frozen=True)
class SeaState:
    """A resolved sea: WMO code, significant wave height (m) and peak period (s)."""
    code: int
    hs_m: float
    tp_s: float


def wmo_code(hs_m: float) -> int:
    """WMO sea-state code of a significant wave height (upper bin edges belong to the bin)."""
    if hs_m < 0.0:
        raise ConfigError(f"significant wave height must be >= 0, got {hs_m}")
    if hs_m == 0.0:
        return 0
    for code in range(1, 9):
        if hs_m <= WMO_HS_BIN_M[code][1]:
            return code
    return 9


def resolve(code: int, hs_m: float = 0.0, tp_s: float = 0.0,
            rng: np.random.Generator | None = None) -> SeaState:
    """Hs and Tp for a sea state.

    `hs_m` / `tp_s` > 0 override the table; 0 takes the table's value (Bales mean Hs and most
    probable Tp), or a random draw within the bin when `rng` is given. With an Hs override
    and no Tp, Tp comes from the code that Hs falls in. Code 0 (calm) gives Hs = 0."""
    if not (isinstance(code, (int, np.integer)) and 0 <= code <= 9):
        raise ConfigError(f"sea state must be a WMO code 0-9, got {code}")
    if hs_m < 0.0 or tp_s < 0.0:
        raise ConfigError(f"hs_m and tp_s must be >= 0 (0 = from the sea state), got {hs_m}, {tp_s}")
    # the two draws are always taken in the same order so overrides do not shift the stream
    u_hs = rng.uniform() if rng is not None else None
    u_tp = rng.uniform() if rng is not None else None
    if hs_m > 0.0:
        hs = float(hs_m)
    elif code == 0:
        hs = 0.0
    elif u_hs is None:
        hs = BALES[code][0]
    else:
        lo, hi = WMO_HS_BIN_M[code]
        hs = lo + (hi - lo) * u_hs
    if tp_s > 0.0:
        tp = float(tp_s)
    else:
        t_lo, t_mode, t_hi = tp_law(code, hs_m)
        tp = t_mode if u_tp is None or t_lo == t_hi else _triangular_ppf(u_tp, t_lo, t_mode, t_hi)
    return SeaState(code=code if hs_m <= 0.0 else wmo_code(hs), hs_m=hs, tp_s=float(tp))


def tp_law(code: int, hs_m: float = 0.0) -> tuple[float, float, float]:
    """(lowest, most probable, highest) Tp of the sea state (of the code an Hs override falls in):
    the Bales bin `resolve` draws Tp from (calm: code 1's most probable Tp, fixed)."""
    tcode = wmo_code(hs_m) if hs_m > 0.0 else code
    if tcode == 0:
        t = BALES[1][3]
        return t, t, t
    _, t_lo, t_hi, t_mode = BALES[tcode]
    return t_lo, t_mode, t_hi


def _triangular_ppf(u: float, a: float, c: float, b: float) -> float:
    """Quantile of the triangular law on [a, b] with mode c."""
    fc = (c - a) / (b - a)
    if u < fc:
        return a + np.sqrt(u * (b - a) * (c - a))
    return b - np.sqrt((1.0 - u) * (b - a) * (b - c))
