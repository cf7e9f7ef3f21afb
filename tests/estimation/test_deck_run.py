"""The deck run (estimation/deck_run.py): a stroke the LDV lost, or first saw halfway, is bridged by
the speed the IMU felt, pinned to the LDV's speed at both ends of the gap."""
from __future__ import annotations

import numpy as np
import pytest

from alignment_core.estimation.deck_run import SHAPED_MAX_NS, DeckRun
from alignment_core.samples import LdvSample

STEP_NS = 10_000_000
H = 0.01


def acceleration(k: int) -> float:
    """A stroke's acceleration along the track (m/s^2) in the IMU interval ending at sample k: parked
    until sample 100, 10 m/s^2 for 0.5 s, 30 m/s^2 for 1 s, then 5 m/s^2."""
    if k <= 100:
        return 0.0
    if k <= 150:
        return 10.0
    if k <= 250:
        return 30.0
    return 5.0


def speed(k: int) -> float:
    """The closed-form speed at sample k (the integral of `acceleration`)."""
    return sum(acceleration(j) for j in range(1, k + 1)) * H


def closed_form_run(k0: int, k1: int) -> float:
    """The distance run between samples k0 and k1: the speed is piecewise linear between samples,
    so the trapezoid over the samples is its exact integral."""
    return sum(0.5 * (speed(k) + speed(k + 1)) * H for k in range(k0, k1))


def run(blind: range, baseline: float, direction=(0.8, 0.6, 0.0), feed_imu: bool = True, moving_from: int = 101,
        until: int = 320, latency_ns: int = 0, start_ns: int | None = 100 * STEP_NS) -> DeckRun:
    """Feed a DeckRun the stroke (the IMU's specific force along x is the acceleration plus a constant
    `baseline`: gravity on a pitched airframe, a bias) and an LDV, blind at the samples in `blind`,
    that reads the velocity along `direction` (ship axes); `start_ns`: where the launch detector dated
    the stroke's start (the last interval before the acceleration ends at sample 100)."""
    u = np.asarray(direction)
    d = DeckRun(latency_ns, axis=u)                 # the airframe's x runs along the track
    for k in range(1, until + 1):
        if feed_imu:
            d.observe_imu(k * STEP_NS, acceleration(k) + baseline, H)
        d.record(LdvSample(t_ns=k * STEP_NS + latency_ns, v_s=speed(k) * u, sigma=0.01, valid=k not in blind),
                 moving=k >= moving_from, t_start_ns=start_ns if k >= moving_from else None)
    return d


@pytest.mark.parametrize('start_ns', [100 * STEP_NS, None, 60 * STEP_NS])
@pytest.mark.parametrize('baseline', [0.0, 0.7, -1.3])
def test_a_stroke_first_seen_halfway_is_bridged_from_the_parked_sample(baseline, start_ns):
    """The LDV blind from sample 50 (parked) to 199 (the stroke at 22 m/s): the run is the closed
    form's, whatever the constant part of the specific force, and along the LDV's direction, from
    the stroke's start as dated, undated (from the last parked sample) or dated early (still
    parked); before, the distance run blind was lost (the displacement began at 199)."""
    d = run(range(50, 200), baseline, start_ns=start_ns)
    expected = closed_form_run(49, 320)
    assert np.linalg.norm(d.displacement) == pytest.approx(expected, rel=1e-9)
    np.testing.assert_allclose(d.displacement / np.linalg.norm(d.displacement), [0.8, 0.6, 0.0], atol=1e-12)


def test_a_gap_in_the_stroke_is_bridged_by_the_imus_shape_not_the_trapezoid():
    """A gap across the change from 10 to 30 m/s^2 (samples 120-199): the trapezoid between its ends
    assumes one constant acceleration and is off by 1.2 m here; the IMU's shape gives the closed form."""
    d = run(range(120, 200), 0.4, direction=(1.0, 0.0, 0.0))
    assert d.displacement[0] == pytest.approx(closed_form_run(100, 320), rel=1e-9)
    trapezoid = closed_form_run(100, 119) + 0.5 * (speed(119) + speed(200)) * 0.81 + closed_form_run(200, 320)
    assert abs(trapezoid - closed_form_run(100, 320)) > 1.0


def test_the_ldvs_latency_puts_the_imu_at_its_validity_times():
    """An LDV stamped 30 ms after its validity: the IMU is read at the validity times."""
    d = run(range(50, 200), 0.7, direction=(1.0, 0.0, 0.0), latency_ns=30_000_000)
    assert d.displacement[0] == pytest.approx(closed_form_run(49, 320), rel=1e-9)


def test_without_the_imu_a_gap_from_a_parked_sample_is_not_bridged():
    """No IMU intervals over the gap: only the run the LDV saw (from sample 200 on) counts."""
    d = run(range(50, 200), 0.0, direction=(1.0, 0.0, 0.0), feed_imu=False)
    assert d.displacement[0] == pytest.approx(closed_form_run(200, 320), rel=1e-12)


@pytest.mark.parametrize('dated', [True, False])
@pytest.mark.parametrize('parked_until', [None, 20])
def test_a_run_first_seen_moving_started_parked_within_the_imus_reach(parked_until, dated):
    """The LDV never valid before the stroke's sample 199 (None), or last valid parked at sample 20,
    more than SHAPED_MAX_NS before it: the run is taken from rest, from its dated start or, undated,
    from 10 s before (as far as the IMU reaches), and is the closed form's (the stroke starts at
    sample 100)."""
    shift = 1200                          # the stroke 12 s into the data: the IMU's reach is 10 s
    d = DeckRun()                                   # the airframe's x along the ship's x (the default)
    for k in range(1, shift + 320 + 1):
        j = k - shift
        d.observe_imu(k * STEP_NS, acceleration(j) + 0.7, H)
        valid = (parked_until is not None and k <= parked_until) or j >= 199
        d.record(LdvSample(t_ns=k * STEP_NS, v_s=np.array([speed(max(j, 0)), 0.0, 0.0]), sigma=0.01, valid=valid),
                 moving=j >= 101, t_start_ns=(shift + 100) * STEP_NS if dated else None)
    assert (shift + 199) * STEP_NS - SHAPED_MAX_NS > 20 * STEP_NS
    assert d.displacement[0] == pytest.approx(closed_form_run(0, 320), rel=1e-9)


def test_slow_motion_across_a_long_gap_is_not_bridged_by_the_imu():
    """Creep at 0.5 m/s, blind for 2 s (over TRAPEZOID_MAX_NS, the speed unchanged): the IMU's
    residuals (here a 0.3 m/s^2 offset, and the deck's motion in a run) would swamp a slow run over
    that long, so it is not bridged; the runs the LDV saw on either side count."""
    d = DeckRun()
    for k in range(0, 301):
        d.observe_imu(k * STEP_NS, 0.3, H)
        d.record(LdvSample(t_ns=k * STEP_NS, v_s=np.array([0.5, 0.0, 0.0]), sigma=0.01, valid=not 50 <= k < 250),
                 moving=k > 0)                 # the first sample parked: the run starts there
    assert d.displacement[0] == pytest.approx(0.5 * (0.49 + 0.5), rel=1e-12)


def test_a_short_gap_at_the_strokes_start_follows_the_imu():
    """Creeping at 0.04 m/s, then the stroke (10 m/s^2 from sample 100), the LDV blind from 85 to
    129 (3 m/s at its end: under SHAPED_MIN_MPS, a gap under TRAPEZOID_MAX_NS): the IMU's shape
    gives the closed form; the trapezoid from 0.04 to 3 m/s across it overshoots by 0.2 m."""
    d = DeckRun()
    v = [0.04 + speed(k) for k in range(0, 200)]
    for k in range(0, 200):
        d.observe_imu(k * STEP_NS, acceleration(k) - 0.6, H)
        d.record(LdvSample(t_ns=k * STEP_NS, v_s=np.array([v[k], 0.0, 0.0]), sigma=0.01, valid=not 85 <= k < 130),
                 moving=k > 0)
    exact = sum(0.5 * (v[k] + v[k + 1]) * H for k in range(199))
    assert d.displacement[0] == pytest.approx(exact, rel=1e-9)
    trapezoid = exact - sum(0.5 * (v[k] + v[k + 1]) * H for k in range(84, 130)) + 0.5 * (v[84] + v[130]) * 0.46
    assert trapezoid - exact > 0.15


def smooth_stroke(t: float, peak: float = 20.0, rise: float = 2.0) -> tuple[float, float, float]:
    """(acceleration, speed, distance) at t s of a stroke whose acceleration grows as
    peak sin^2(pi t / (2 rise)) from t = 0 (at rest before), closed forms."""
    if t <= 0.0:
        return 0.0, 0.0, 0.0
    w = np.pi / rise
    a = peak * np.sin(0.5 * w * t) ** 2
    v = peak * (0.5 * t - np.sin(w * t) / (2.0 * w))
    x = peak * (0.25 * t * t + (np.cos(w * t) - 1.0) / (2.0 * w * w))
    return a, v, x


def test_a_smooth_stroke_off_the_imus_grid_is_bridged_to_the_interpolation_error():
    """A stroke whose acceleration grows smoothly (no interval of constant acceleration), the LDV's
    validity times 4 ms off the IMU's grid, blind for 0.8 s from 0.5 s: the IMU gives the mean
    acceleration of each interval (the closed form's velocity change over it), and the bridge meets
    the closed-form distance to the error of interpolating within an interval (dv'' h^2 T / 12,
    under 1e-4 m here); the trapezoid between the gap's ends is off by 0.1 m."""
    d = DeckRun(axis=np.array([1.0, 0.0, 0.0]))
    off = 4_000_000
    h = 0.01
    for k in range(-20, 150):
        t_end = k * STEP_NS
        d.observe_imu(t_end, (smooth_stroke(t_end * 1e-9)[1] - smooth_stroke(t_end * 1e-9 - h)[1]) / h + 0.4, h)
        t_ldv = t_end - STEP_NS + off               # validity (and stamp: no latency) inside the interval
        v = smooth_stroke(t_ldv * 1e-9)[1]
        d.record(LdvSample(t_ns=t_ldv, v_s=np.array([v, 0.0, 0.0]), sigma=0.01, valid=not 50 <= k < 130),
                 moving=t_ldv > 0)
    t_a, t_b = 49 * STEP_NS - STEP_NS + off, 130 * STEP_NS - STEP_NS + off
    gap = smooth_stroke(t_b * 1e-9)[2] - smooth_stroke(t_a * 1e-9)[2]
    # the LDV's own trapezoid between consecutive valid samples on either side of the gap
    t_ldv = [k * STEP_NS - STEP_NS + off for k in range(-20, 150)]
    ldv_seen = sum(0.5 * (smooth_stroke(a * 1e-9)[1] + smooth_stroke(b * 1e-9)[1]) * h
                   for a, b in zip(t_ldv[:-1], t_ldv[1:]) if b > 0 and not t_a < b <= t_b)
    bridged = d.displacement[0] - ldv_seen
    assert bridged == pytest.approx(gap, abs=1e-4)
    va, vb = smooth_stroke(t_a * 1e-9)[1], smooth_stroke(t_b * 1e-9)[1]
    assert abs(0.5 * (va + vb) * (t_b - t_a) * 1e-9 - gap) > 0.1


@pytest.mark.parametrize('v0, accel', [(-3.0, -8.0), (6.0, -12.0)])
def test_backward_and_reversing_runs_follow_the_imu_with_its_sign(v0, accel):
    """Tail first and speeding up (-3 m/s, -8 m/s^2), or reversing inside the gap (6 m/s, -12 m/s^2:
    at rest at 0.5 s, then backwards), with the acceleration switching to 4 times that half-way
    through the 0.8 s gap: the speed along the airframe's x is signed, so the bridge is the exact
    run (the trapezoid between the ends assumes one acceleration)."""
    d = DeckRun()
    acc = [accel if k < 60 else 4.0 * accel for k in range(120)]
    v = [v0]
    for k in range(1, 120):
        v.append(v[-1] + acc[k] * H)
    for k in range(120):
        d.observe_imu(k * STEP_NS, acc[k] - 0.3, H)
        d.record(LdvSample(t_ns=k * STEP_NS, v_s=np.array([v[k], 0.0, 0.0]), sigma=0.01, valid=not 20 <= k < 100),
                 moving=k > 0)
    exact = sum(0.5 * (v[k] + v[k + 1]) * H for k in range(119))
    assert d.displacement[0] == pytest.approx(exact, rel=1e-9)
    trapezoid = exact - sum(0.5 * (v[k] + v[k + 1]) * H for k in range(19, 100)) + 0.5 * (v[19] + v[100]) * 0.81
    assert abs(trapezoid - exact) > 0.2


def test_a_slow_ldv_that_sees_every_sample_keeps_the_trapezoid():
    """An LDV at 0.5 Hz (samples 2 s apart, all valid) on a taxi at 2 m/s: the trapezoid between
    consecutive samples, as before the IMU bridge (16 m over 8 s)."""
    d = DeckRun()
    for k in range(0, 801):
        d.observe_imu(k * STEP_NS, 0.2, H)
        if k % 200 == 0:
            d.record(LdvSample(t_ns=k * STEP_NS, v_s=np.array([2.0, 0.0, 0.0]), sigma=0.01, valid=True),
                     moving=k > 0)
    assert d.displacement[0] == pytest.approx(16.0, rel=1e-12)


@pytest.mark.parametrize('dated', [True, False])
def test_a_stroke_first_seen_slow_long_after_the_last_parked_sample_is_bridged_from_its_dated_start(dated):
    """Parked on a surging deck (0.3 m/s^2 at 2 s, felt by the IMU), the LDV blind from sample 1;
    the stroke (10 m/s^2 from sample 100) first seen at sample 125, at 2.5 m/s, 1.24 s after the last
    parked sample. Dated at its start, the bridge runs over the 0.25 s of the stroke and is exact
    (the surge before it does not enter). Undated, the bridge would span 1.24 s for under
    SHAPED_MIN_MPS of change, where the deck's motion felt would swamp it: nothing is bridged."""
    d = DeckRun()
    v = [0.0 if k <= 100 else (k - 100) * 10.0 * H for k in range(200)]
    for k in range(200):
        surge = 0.3 * np.sin(np.pi * k * H) if k <= 100 else 0.0
        d.observe_imu(k * STEP_NS, (10.0 if k > 100 else 0.0) + 0.5 + surge, H)
        d.record(LdvSample(t_ns=k * STEP_NS, v_s=np.array([v[k], 0.0, 0.0]), sigma=0.01, valid=not 1 <= k < 125),
                 moving=k >= 125, t_start_ns=100 * STEP_NS if dated and k >= 125 else None)
    seen = sum(0.5 * (v[k] + v[k + 1]) * H for k in range(125, 199))
    exact = sum(0.5 * (v[k] + v[k + 1]) * H for k in range(100, 199))
    assert d.displacement[0] == pytest.approx(exact if dated else seen, rel=1e-9)
