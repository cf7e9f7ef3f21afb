"""The catapult: hold-back tensioning, then the stroke's acceleration profile along the track.

Distance s(t), speed s'(t) and acceleration s''(t) of the aircraft along the catapult track
(the mounted aircraft x axis), relative to the deck; aircraft/kinematics.py turns them into motion on the
rotating, heaving ship (with the Coriolis and centripetal terms).

Stroke profiles (t = time since the launch, T = stroke_s, A = accel_g g):
- 'constant': s'' = A (seed 000: 2 g for 3 s): s' = A t, s = A t^2 / 2.
- 'shape': a steam-catapult-like shape: ramp-up over ramp_s, plateau at A, tail-off over
  tail_s to tail_fraction A at the release: A S(t / ramp_s), A, A (1 - (1 - e) S(x)), with
  S(x) = 10x^3 - 15x^4 + 6x^5 (the acceleration and its rate are continuous inside).
- 'knots': monotone cubic (PCHIP) through (knot_time_s, knot_accel_g): no overshoot between
  knots, so a non-negative table stays non-negative.
Non-constant profiles are piecewise polynomials (scipy PPoly): speed and distance are their
exact antiderivatives, so end speed = int a dt and stroke length = int int a dt hold exactly.

Hold-back tensioning (holdback_s > 0): the engines run up against the hold-back bar for
holdback_s before the launch. The bar's net force cancels the thrust, so with no motion the
accelerometers feel nothing new (specific force is the net non-gravitational force per mass);
what they do feel is the airframe creeping forward by holdback_stretch_m as the bar and the
nose gear take the load: s = d S(x) over the tensioning (a small forward-then-back specific
force, d 5.77 / T^2 peak), then held through the stroke.

Every event (tensioning start, launch, profile breakpoints, release) must fall on the sample
grid, so no sample interval straddles a change of the acceleration's formula.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

if TYPE_CHECKING:
    from scipy.interpolate import PPoly

from alignment_core.units import G0
from alignment_core.validation import ConfigError, build, require


@dataclass(frozen=True)
class CatapultConfig:
    """Catapult stroke along the aircraft axis (seed 000: constant 2 g for 3 s) and the
    hold-back tensioning before it (off by default)."""
    enabled: bool = True
    launch_time_s: float = 60.0
    stroke_s: float = 3.0
    accel_g: float = 2.0
    profile: Literal['constant', 'shape', 'knots'] = 'constant'
    ramp_s: float = 0.2
    tail_s: float = 0.3
    tail_fraction: float = 0.6
    knot_time_s: tuple[float, ...] = (0.0, 3.0)
    knot_accel_g: tuple[float, ...] = (2.0, 2.0)
    holdback_s: float = 0.0
    holdback_stretch_m: float = 0.0

    def validate(self) -> None:
        require(self.launch_time_s >= 0.0, f"launch_time_s must be >= 0, got {self.launch_time_s}")
        require(0.0 < self.stroke_s <= 10.0, f"stroke_s must be in (0, 10], got {self.stroke_s}")
        require(0.0 < self.accel_g <= 8.0, f"accel_g must be in (0, 8], got {self.accel_g}")
        require(self.ramp_s >= 0.0 and self.tail_s >= 0.0,
                f"ramp_s and tail_s must be >= 0, got {self.ramp_s}, {self.tail_s}")
        if self.profile == 'shape':
            require(self.ramp_s + self.tail_s <= self.stroke_s,
                    f"ramp_s + tail_s = {self.ramp_s + self.tail_s} s must fit in stroke_s = {self.stroke_s} s")
        require(0.0 <= self.tail_fraction <= 1.0, f"tail_fraction must be in [0, 1], got {self.tail_fraction}")
        kt, ka = np.asarray(self.knot_time_s), np.asarray(self.knot_accel_g)
        require(len(kt) == len(ka) and len(kt) >= 2,
                f"knot_time_s and knot_accel_g need the same length >= 2, got {len(kt)} and {len(ka)}")
        require(bool(np.all(np.diff(kt) > 0.0)), f"knot_time_s must increase strictly: {self.knot_time_s}")
        require(bool(np.all((ka >= 0.0) & (ka <= 8.0))), f"knot_accel_g must be in [0, 8] g: {self.knot_accel_g}")
        if self.profile == 'knots':
            require(kt[0] == 0.0 and abs(kt[-1] - self.stroke_s) < 1e-9,
                    f"knot_time_s must run from 0 to stroke_s = {self.stroke_s}: {self.knot_time_s}")
            require(bool(np.any(ka > 0.0)), "knot_accel_g must not be all zero")
        require(0.0 <= self.holdback_s <= 30.0, f"holdback_s must be in [0, 30], got {self.holdback_s}")
        require(self.holdback_s <= self.launch_time_s,
                f"holdback_s = {self.holdback_s} s must end at the launch and so start at or after 0 "
                f"(launch_time_s = {self.launch_time_s})")
        require(0.0 <= self.holdback_stretch_m <= 0.5,
                f"holdback_stretch_m must be in [0, 0.5], got {self.holdback_stretch_m}")
        require(self.holdback_stretch_m == 0.0 or self.holdback_s > 0.0,
                "holdback_stretch_m needs holdback_s > 0 (the creep happens during the tensioning)")


def profile_breakpoints(cat: CatapultConfig) -> list[float]:
    """Times since the launch where the stroke acceleration's formula changes (inside the stroke)."""
    if cat.profile == 'shape':
        return [t for t in (cat.ramp_s, cat.stroke_s - cat.tail_s) if 0.0 < t < cat.stroke_s]
    if cat.profile == 'knots':
        return [float(t) for t in cat.knot_time_s[1:-1]]
    return []


def check_catapult_grid(cat: CatapultConfig, rate_hz: float) -> None:
    """Every catapult event must be a sample instant (no interval straddles one)."""
    events = [('launch_time_s', cat.launch_time_s),
              ('launch_time_s + stroke_s', cat.launch_time_s + cat.stroke_s)]
    if cat.holdback_s > 0.0:
        events.append(('launch_time_s - holdback_s', cat.launch_time_s - cat.holdback_s))
    events += [(f'launch_time_s + {t:g} s ({cat.profile} profile breakpoint)', cat.launch_time_s + t)
               for t in profile_breakpoints(cat)]
    for name, t in events:
        require(abs(t * rate_hz - round(t * rate_hz)) < 1e-6,
                f"aircraft.catapult.{name} = {t} s must fall on the {rate_hz} Hz sample grid")


def _smoothstep_ppoly(t0: float, dur: float, a0: float, a1: float) -> np.ndarray:
    """PPoly coefficients (highest power first, 6) of a0 + (a1 - a0) S((t - t0) / dur)."""
    d = a1 - a0
    return np.array([6.0 * d / dur**5, -15.0 * d / dur**4, 10.0 * d / dur**3, 0.0, 0.0, a0])


def acceleration_profile(cat: CatapultConfig) -> PPoly | None:
    """The stroke acceleration (m/s^2) as a PPoly over [0, stroke_s]; None for 'constant'."""
    A, T = cat.accel_g * G0, cat.stroke_s
    if cat.profile == 'constant':
        return None
    # scipy.interpolate (and scipy.optimize with it): ~0.3 s of every node's start-up otherwise
    from scipy.interpolate import PchipInterpolator, PPoly
    if cat.profile == 'knots':
        return PchipInterpolator(np.asarray(cat.knot_time_s), np.asarray(cat.knot_accel_g) * G0,
                                 extrapolate=True)
    if cat.profile == 'shape':
        x, c = [0.0], []
        t1, t2 = cat.ramp_s, T - cat.tail_s
        if t1 > 0.0:
            c.append(_smoothstep_ppoly(0.0, t1, 0.0, A))
            x.append(t1)
        if t2 > t1:
            c.append(np.array([0.0, 0.0, 0.0, 0.0, 0.0, A]))
            x.append(t2)
        if T > t2:
            c.append(_smoothstep_ppoly(t2, T - t2, A, cat.tail_fraction * A))
            x.append(T)
        return PPoly(np.array(c).T, np.array(x), extrapolate=True)
    raise ConfigError(f"aircraft.catapult.profile {cat.profile!r} is not available")


def stroke_end_speed(cat: CatapultConfig) -> float:
    """Speed relative to the deck at the release, m/s (int of the acceleration)."""
    prof = acceleration_profile(cat)
    if prof is None:
        return cat.accel_g * G0 * cat.stroke_s
    return float(prof.antiderivative(1)(cat.stroke_s))


def stroke_length(cat: CatapultConfig) -> float:
    """Distance along the track from the launch to the release, m (double integral)."""
    prof = acceleration_profile(cat)
    if prof is None:
        return 0.5 * (cat.accel_g * G0) * cat.stroke_s**2
    return float(prof.antiderivative(2)(cat.stroke_s))


def track_length_from_dict(cat: dict | None) -> float:
    """Hold-back creep + stroke length of a raw `aircraft.catapult` mapping (scenario defaults)."""
    cfg = build(CatapultConfig, cat or {}, 'aircraft.catapult')
    return stroke_length(cfg) + cfg.holdback_stretch_m


class CatapultMotion:
    """s, s', s'' along the track at scenario times tau (s), from the configuration."""

    def __init__(self, cat: CatapultConfig, rate_hz: float) -> None:
        self.cfg = cat
        self.acc = cat.accel_g * G0
        # event instants as sample instants, computed exactly as tau is from stamps
        dt_ns = int(round(1e9 / rate_hz))
        self.launch = int(round(cat.launch_time_s * rate_hz)) * dt_ns / 1e9
        self.release = int(round((cat.launch_time_s + cat.stroke_s) * rate_hz)) * dt_ns / 1e9
        self.holdback_start = int(round((cat.launch_time_s - cat.holdback_s) * rate_hz)) * dt_ns / 1e9
        prof = acceleration_profile(cat)
        self.profile = None if prof is None else (prof, prof.antiderivative(1), prof.antiderivative(2))
        self.creep = cat.holdback_stretch_m if cat.holdback_s > 0.0 else 0.0

    def along(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(s, s', s'') at tau (any shape): from the deck spot, along the track."""
        s_t = np.clip(tau - self.launch, 0.0, self.release - self.launch)
        moving = ((tau > self.launch) & (tau <= self.release)).astype(float)
        if self.profile is None:
            s = 0.5 * self.acc * s_t**2
            sd = self.acc * s_t
            sdd = self.acc * moving
        else:
            a, v, p = self.profile
            s, sd, sdd = p(s_t), v(s_t), a(s_t) * moving
        if self.creep > 0.0:
            T = self.launch - self.holdback_start
            x = np.clip((tau - self.holdback_start) / T, 0.0, 1.0)
            d = self.creep
            s = s + d * x**3 * (10.0 - 15.0 * x + 6.0 * x * x)
            sd = sd + d / T * 30.0 * x * x * (1.0 - x) ** 2
            sdd = sdd + d / T**2 * 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x)
        return s, sd, sdd
