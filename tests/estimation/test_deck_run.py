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
    d = DeckRun(latency_ns)
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


@pytest.mark.parametrize('parked_until', [None, 20])
def test_a_run_first_seen_moving_started_parked_within_the_imus_reach(parked_until):
    """The LDV never valid before the stroke's sample 199 (None), or last valid parked at sample 20,
    more than SHAPED_MAX_NS before it: the run is taken from rest at most 10 s before, as far as
    the IMU reaches, and is the closed form's (the stroke starts at sample 100)."""
    shift = 1200                          # the stroke 12 s into the data: the IMU's reach is 10 s
    d = DeckRun()
    for k in range(1, shift + 320 + 1):
        j = k - shift
        d.observe_imu(k * STEP_NS, acceleration(j) + 0.7, H)
        valid = (parked_until is not None and k <= parked_until) or j >= 199
        d.record(LdvSample(t_ns=k * STEP_NS, v_s=np.array([speed(max(j, 0)), 0.0, 0.0]), sigma=0.01, valid=valid),
                 moving=j >= 101, t_start_ns=(shift + 100) * STEP_NS)
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
