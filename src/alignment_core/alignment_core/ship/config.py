"""The ship's configuration (`ship.*`) and the tables of the paper mode."""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Literal

from alignment_core.ship import sea_state, wave_spectrum
from alignment_core.validation import require

# seed 002, Table 3: amplitudes (deg) roll, pitch, yaw by sea state
PAPER_TABLE3_DEG = {3: (1.25, 1.01, 1.03), 4: (2.71, 1.71, 1.92), 5: (5.62, 2.91, 3.36),
                    6: (7.47, 3.15, 4.15), 7: (9.84, 5.27, 6.11)}


# periods (s) roll, pitch, yaw, heave for a 175 m ship (docs/ship-motion.md); 1-2 and 8-9 extend
# its ranges (roll at the natural period, pitch/heave/yaw lengthening with the wave period)
PAPER_PERIOD_S = {1: (17.0, 6.0, 7.5, 6.5), 2: (17.0, 6.25, 7.75, 6.75),
                  3: (17.0, 6.5, 8.0, 7.0), 4: (17.0, 7.0, 8.5, 7.5), 5: (17.0, 7.5, 9.0, 8.0),
                  6: (17.0, 7.75, 9.25, 8.5), 7: (18.5, 8.0, 9.5, 9.0),
                  8: (18.5, 8.5, 10.0, 9.5), 9: (18.5, 9.0, 10.5, 10.0)}


# Bales (1983) mean significant wave height (m) by sea state
BALES_HS_M = {0: 0.0, 1: 0.05, 2: 0.3, 3: 0.88, 4: 1.88, 5: 3.25, 6: 5.0, 7: 7.5, 8: 11.5, 9: 14.0}


def _paper_amplitudes() -> dict[int, tuple[float, float, float]]:
    """Seed 002 Table 3 (sea states 3-7) plus 1-2 and 8-9, which the paper does not give:
    linear response at a fixed period, i.e. amplitude proportional to the Bales Hs, with the
    amplitude per metre of the nearest tabulated sea state (3 for 1-2, 7 for 8-9)."""
    out = dict(PAPER_TABLE3_DEG)
    for ss, ref in ((1, 3), (2, 3), (8, 7), (9, 7)):
        k = BALES_HS_M[ss] / BALES_HS_M[ref]
        roll, pitch, yaw = PAPER_TABLE3_DEG[ref]
        out[ss] = (roll * k, pitch * k, yaw * k)
    return dict(sorted(out.items()))


PAPER_AMPLITUDE_DEG = _paper_amplitudes()


@dataclass(frozen=True)
class ShipConfig:
    """Ship scenario: course, speed, start position and the sea.

    Spectral mode only (ignored by 'paper'): `hs_m` / `tp_s` override the sea state's
    significant wave height and peak period (0 = Bales table value for `sea_state`);
    `sea_draw` draws them at random within the sea state's bin instead (Monte Carlo);
    `spectrum` ITTC (Bretschneider) or JONSWAP (`jonswap_gamma`); `spreading` 'none'
    (long-crested) or 'cos2' over `n_directions`; `wave_heading_deg` is the direction the
    waves travel relative to the bow, clockwise (180 = head seas, 90 = waves from port,
    0 = following); `n_frequencies` log-spaced bins on `omega_min`..`omega_max` rad/s (0 = auto:
    the default band of Tp; one edge given alone must leave it non-empty for every Tp of the sea);
    `rao_source` 'closed_form' (a 310 m carrier, `rao.CarrierParams`, with `roll_period_s` and
    `roll_zeta` (0 = 0.05 at 0 kn to 0.10 at 30 kn)) or a path to an MSS vessel .mat file;
    `course_keeping` 'straight' (constant course and speed) or 'mmg': the low-frequency
    track from the MMG manoeuvring model (`mmg.py`, `ship_model` 'carrier' or 'kvlcc2')
    steered by a PID autopilot (`autopilot_kp` rad/rad, `autopilot_ki` 1/s, `autopilot_kd`
    s; rudder `rudder_max_deg`, `rudder_rate_dps`), integrated by RK4 every `mmg_step_s`
    (`course_keeping.py`); the schedule orders `speed_kn` on `heading_deg`, then from
    `turn_at_s` (negative: never) heading `turn_to_deg` (at `turn_rate_dps`, 0 = at once)
    and speed `speed_to_kn` (negative: unchanged); steady wind `wind_speed_kn` from
    `wind_from_deg` (true, from North clockwise). In paper mode the MMG ship also feels
    seed 002's box-ship forces of a regular wave (`box_ship_waves.py`).
    """
    mode: Literal['paper', 'spectral'] = 'spectral'   # the seed scenarios set 'paper' explicitly
    sea_state: int = 4
    speed_kn: float = 10.0
    heading_deg: float = 30.0
    lat_deg: float = 40.0
    lon_deg: float = 116.0
    heave: bool = True
    motion_scale: float = 1.0
    hs_m: float = 0.0
    tp_s: float = 0.0
    sea_draw: bool = False
    spectrum: Literal['ittc', 'jonswap'] = 'ittc'
    jonswap_gamma: float = 3.3
    spreading: Literal['none', 'cos2'] = 'cos2'
    wave_heading_deg: float = 180.0
    n_frequencies: int = 150
    n_directions: int = 15
    omega_min: float = 0.0
    omega_max: float = 0.0
    rao_source: str = 'closed_form'
    roll_period_s: float = 20.0
    roll_zeta: float = 0.0
    course_keeping: Literal['straight', 'mmg'] = 'straight'
    ship_model: Literal['carrier', 'kvlcc2'] = 'carrier'
    autopilot_kp: float = 2.0
    autopilot_ki: float = 0.01
    autopilot_kd: float = 60.0
    rudder_max_deg: float = 35.0
    rudder_rate_dps: float = 2.5
    turn_at_s: float = -1.0
    turn_to_deg: float = 0.0
    turn_rate_dps: float = 0.0
    speed_to_kn: float = -1.0
    wind_speed_kn: float = 0.0
    wind_from_deg: float = 0.0
    mmg_step_s: float = 0.5

    def validate(self) -> None:
        require(0 <= self.sea_state <= 9, f"sea_state must be a WMO code 0-9, got {self.sea_state}")
        if self.mode == 'paper':
            require(self.sea_state in PAPER_AMPLITUDE_DEG or self.sea_state == 0,
                    f"paper mode has amplitudes for sea states 1-9 (seed 002 Table 3, extended) "
                    f"and 0 (calm), got {self.sea_state}")
        require(0.0 <= self.speed_kn <= 40.0, f"speed_kn must be in [0, 40], got {self.speed_kn}")
        require(-90.0 < self.lat_deg < 90.0, f"lat_deg must be in (-90, 90), got {self.lat_deg}")
        require(-180.0 <= self.lon_deg <= 360.0, f"lon_deg out of range: {self.lon_deg}")
        require(0.0 <= self.motion_scale <= 10.0, f"motion_scale must be in [0, 10], got {self.motion_scale}")
        require(0.0 <= self.hs_m <= 30.0, f"hs_m must be in [0, 30] m (0 = from sea_state), got {self.hs_m}")
        require(self.tp_s == 0.0 or 1.0 <= self.tp_s <= 30.0,
                f"tp_s must be 0 (from sea_state) or in [1, 30] s, got {self.tp_s}")
        require(1.0 <= self.jonswap_gamma <= 10.0, f"jonswap_gamma must be in [1, 10], got {self.jonswap_gamma}")
        require(-360.0 <= self.wave_heading_deg <= 360.0,
                f"wave_heading_deg must be in [-360, 360], got {self.wave_heading_deg}")
        require(1 <= self.n_frequencies <= 2000, f"n_frequencies must be in [1, 2000], got {self.n_frequencies}")
        require(1 <= self.n_directions <= 101, f"n_directions must be in [1, 101], got {self.n_directions}")
        require(self.omega_min >= 0.0 and self.omega_max >= 0.0,
                f"omega_min / omega_max must be >= 0 (0 = auto), got {self.omega_min}, {self.omega_max}")
        require(self.omega_min == 0.0 or self.omega_max == 0.0 or self.omega_min < self.omega_max,
                f"omega_min must be below omega_max, got {self.omega_min}, {self.omega_max}")
        require(5.0 <= self.roll_period_s <= 60.0, f"roll_period_s must be in [5, 60], got {self.roll_period_s}")
        require(0.0 <= self.roll_zeta < 1.0, f"roll_zeta must be in [0, 1) (0 = speed dependent), got {self.roll_zeta}")
        require(self.autopilot_kp > 0.0, f"autopilot_kp must be > 0 (rad of rudder per rad of heading "
                                         f"error), got {self.autopilot_kp}")
        require(self.autopilot_ki >= 0.0, f"autopilot_ki must be >= 0 (1/s), got {self.autopilot_ki}")
        require(self.autopilot_kd >= 0.0, f"autopilot_kd must be >= 0 (s), got {self.autopilot_kd}")
        require(0.0 < self.rudder_max_deg <= 45.0,
                f"rudder_max_deg must be in (0, 45], got {self.rudder_max_deg}")
        require(0.0 < self.rudder_rate_dps <= 20.0,
                f"rudder_rate_dps must be in (0, 20], got {self.rudder_rate_dps}")
        require(self.turn_at_s < 0.0 or 0.0 <= self.turn_to_deg <= 360.0,
                f"turn_to_deg must be a heading in [0, 360], got {self.turn_to_deg}")
        require(self.turn_rate_dps >= 0.0,
                f"turn_rate_dps must be >= 0 (0 = ordered at once), got {self.turn_rate_dps}")
        require(self.speed_to_kn < 0.0 or 1.0 <= self.speed_to_kn <= 40.0,
                f"speed_to_kn must be negative (unchanged) or in [1, 40], got {self.speed_to_kn}")
        require(0.0 <= self.wind_speed_kn <= 150.0,
                f"wind_speed_kn must be in [0, 150], got {self.wind_speed_kn}")
        require(-360.0 <= self.wind_from_deg <= 360.0,
                f"wind_from_deg must be in [-360, 360], got {self.wind_from_deg}")
        require(0.01 <= self.mmg_step_s <= 2.0, f"mmg_step_s must be in [0.01, 2] s, got {self.mmg_step_s}")
        if self.course_keeping == 'mmg':
            require(self.speed_kn >= 1.0, f"speed_kn must be >= 1 with course_keeping 'mmg' (the MMG "
                                          f"model is a manoeuvring model at speed), got {self.speed_kn}")
        if self.mode == 'spectral' and (self.omega_min == 0.0) != (self.omega_max == 0.0):
            self.validate_band()
        if self.mode == 'spectral' and self.rao_source != 'closed_form':
            path = os.path.expandvars(os.path.expanduser(self.rao_source))
            require(os.path.isfile(path), f"rao_source: RAO file not found: {self.rao_source!r} "
                                          f"(give 'closed_form' or the path of an MSS vessel .mat file)")

    def peak_periods(self) -> tuple[float, float]:
        """The shortest and longest peak period Tp (s) the sea can have: sea_state.resolve's, or
        the ends of its draw's range under sea_draw."""
        if not self.sea_draw or self.tp_s > 0.0:
            tp = sea_state.resolve(self.sea_state, self.hs_m, self.tp_s).tp_s
            return tp, tp
        lo, _, hi = sea_state.tp_law(self.sea_state, self.hs_m)
        return lo, hi

    def validate_band(self) -> None:
        """One of omega_min / omega_max given, the other automatic (wave_spectrum.default_band of
        Tp, both edges falling as Tp grows): the band must be non-empty for every Tp of the sea."""
        tp_lo, tp_hi = self.peak_periods()
        if self.omega_min > 0.0:
            hi = wave_spectrum.default_band(tp_hi)[1]
            require(self.omega_min < hi,
                    f"omega_min = {self.omega_min} rad/s must be below omega_max, automatic here: {hi:.4g} rad/s "
                    f"(the default band's upper edge at Tp {tp_hi:.4g} s, sea_state {self.sea_state}); "
                    f"give omega_max too")
        else:
            lo = wave_spectrum.default_band(tp_lo)[0]
            require(self.omega_max > lo,
                    f"omega_max = {self.omega_max} rad/s must be above omega_min, automatic here: {lo:.4g} rad/s "
                    f"(the default band's lower edge at Tp {tp_lo:.4g} s, sea_state {self.sea_state}); "
                    f"give omega_min too")
