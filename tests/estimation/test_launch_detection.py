"""Launch detection from the LDV: one noisy sample above `launch_detect_mps` is not a launch.

A 1 cm/s-per-axis LDV exceeds 5 cm/s in |v| with probability P(chi2_3 > 25) = 1.5e-5 per
sample, i.e. about once in 11 minutes at 100 Hz, and the old single-sample rule took such a
spike for the launch (3 of 50 catapult seeds: parked matching switched to moving minutes early,
the launch noise spent on the deck and 1.2-1.4' of pitch error under vibration). The engine now
needs `launch_confirm_samples` valid samples in a row."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.estimation.launch_detection import LaunchDetector, LaunchThresholds, LdvDecision
from alignment_core.samples import LdvSample


def _run(sc, ldv):
    """The engine on the scenario's inputs with each LDV sample passed through `ldv`."""
    inp = pipeline.simulate(sc)
    inp = replace(inp, ldv=[ldv(s) for s in inp.ldv])
    return pipeline.align(sc, inp), inp


def test_a_single_ldv_spike_on_the_parked_deck_is_not_a_launch():
    sc = scenario.load('deck_paper', {'duration_s': 6.0})
    spike_ns = sc.t0_ns + 3_000_000_000

    def spiked(s):
        return replace(s, v_s=np.array([0.2, 0.0, 0.0])) if s.t_ns == spike_ns else s
    f, _ = _run(sc, spiked)
    assert not f.deck_motion.moving and f.deck_motion.t_launch_ns is None
    assert f.counters.unmatched_master == 0 and f.counters.updates == 600     # 601 samples, the first initialises
    # the old rule (one sample) takes it for the launch
    old = replace(sc, filter=replace(sc.filter, launch_confirm_samples=1))
    f1, _ = _run(old, spiked)
    assert f1.deck_motion.moving and f1.deck_motion.t_launch_ns == spike_ns


def test_the_catapult_launch_is_dated_at_its_first_sample():
    """Confirmation delays the decision by two samples, not the launch time: t_launch is the first
    LDV sample above the threshold, and the held samples are integrated into the deck displacement
    from it on (the trapezoids of every valid sample pair from the one before the first, which
    opens the stroke's first interval, to the last)."""
    sc = scenario.load('catapult_paper', {'duration_s': 4.0, 'aircraft.catapult.launch_time_s': 2.0})
    f, inp = _run(sc, lambda s: s)
    first = next(s.t_ns for s in inp.ldv if s.valid and np.linalg.norm(s.v_s) > sc.filter.launch_detect_mps)
    assert f.deck_motion.t_launch_ns == first
    k = next(i for i, s in enumerate(inp.ldv) if s.t_ns == first)
    v = inp.ldv[k - 1:]
    disp = np.zeros(3)
    for a, b in zip(v[:-1], v[1:]):
        if a.valid and b.valid:
            disp += 0.5 * (a.v_s + b.v_s) * (b.t_ns - a.t_ns) * 1e-9
    np.testing.assert_allclose(f.deck_motion.displacement, disp, rtol=1e-12, atol=1e-12)
    assert np.linalg.norm(disp) > 1.0


def test_hold_back_creep_is_deck_motion_but_not_the_launch():
    """inflight: the engines run up against the hold-back bar for 2 s before the 10 s launch and
    the airframe creeps 5 cm forward (up to ~4.5 cm/s, below the 5 cm/s launch threshold). A
    parked match would take that for a 9-sigma velocity error; the LDV median sees the creep and
    the aircraft counts as moving from then on, while the launch (the launch-noise window) is
    still dated at the stroke."""
    sc = scenario.load('inflight', {'duration_s': 12.0}, seed=3)
    f, _ = _run(sc, lambda s: s)
    hold = sc.t0_ns + 8_000_000_000
    launch = sc.t0_ns + 10_000_000_000
    assert f.counters.creep_detected == 1
    motion = f.deck_motion
    assert hold < motion.t_moving_ns < launch <= motion.t_launch_ns < launch + 100_000_000
    # a parked deck never creeps: the 1 cm/s LDV noise stays far below the median threshold
    g, _ = _run(scenario.load('deck_paper', {'duration_s': 60.0}), lambda s: s)
    assert g.counters.creep_detected == 0 and not g.deck_motion.moving


# ----- the detector on its own (estimation/launch_detection.py) -----
def _detector(latency_ns: int = 0) -> LaunchDetector:
    return LaunchDetector(LaunchThresholds(launch_mps=0.05, confirm_samples=3, creep_mps=0.02, creep_window=9,
                                           ldv_latency_ns=latency_ns))


def _ldv(t_ms: int, vx: float, valid: bool = True) -> LdvSample:
    return LdvSample(t_ns=t_ms * 1_000_000, v_s=np.array([vx, 0.0, 0.0]), sigma=0.01, valid=valid)


def test_a_confirmed_run_is_the_launch_dated_at_its_first_sample():
    d = _detector(latency_ns=7_000_000)
    run = [_ldv(t, 0.2) for t in (10, 20, 30)]
    assert d.observe(run[0]) == LdvDecision() and d.observe(run[1]) == LdvDecision()   # held: no match
    last = d.observe(run[2])
    assert last.record == tuple(run) and last.launch_ns == 3_000_000 and not last.creep
    assert d.moving and d.t_moving_ns == d.t_launch_ns == 3_000_000
    nxt = _ldv(40, 0.3)
    assert d.observe(nxt) == LdvDecision((nxt,))


def test_a_broken_run_is_released_parked_and_gaps_do_not_count():
    d = _detector()
    fast, gap, slow = _ldv(10, 0.2), _ldv(20, 0.0, valid=False), _ldv(30, 0.01)
    assert d.observe(fast) == LdvDecision() and d.observe(gap) == LdvDecision()
    assert d.observe(slow) == LdvDecision((fast, gap, slow))
    assert not d.moving and d.t_launch_ns is None
    held = [_ldv(40, 0.2), _ldv(50, 0.0, valid=False), _ldv(60, 0.2)]
    assert all(d.observe(s) == LdvDecision() for s in held)          # two fast of three: not yet
    assert d.release() == tuple(held) and d.release() == ()          # the end of the data: parked


def test_creep_is_motion_and_a_stroke_above_it_is_the_launch():
    """Nine samples at 3 cm/s (each below 5 cm/s, the median of the 9-sample window above 2 cm/s):
    creep at the ninth. Then the launch needs 3 samples in a row faster than the window's median
    plus 5 cm/s: three at 7 cm/s are not (median 3 cm/s), the three at 20 cm/s after them are
    (medians 3, 7, 7 cm/s)."""
    d = _detector()
    creep = [_ldv(10 * k, 0.03) for k in range(1, 10)]
    decisions = [d.observe(s) for s in creep]
    assert [x.creep for x in decisions] == [False] * 8 + [True]
    assert all(x.record == (s,) and x.launch_ns is None for x, s in zip(decisions, creep, strict=True))
    assert d.moving and d.t_moving_ns == 90_000_000 and d.t_launch_ns is None
    assert all(d.observe(_ldv(t, 0.07)).launch_ns is None for t in (100, 110, 120))
    assert d.t_launch_ns is None
    launch = [d.observe(_ldv(t, 0.2)).launch_ns for t in (130, 140, 150)]
    assert launch == [None, None, 130_000_000] and d.t_moving_ns == 90_000_000


def test_an_ldv_run_the_accelerometers_do_not_feel_is_not_a_launch():
    """Five LDV samples of 10 m/s on the parked deck: reaching 10 m/s takes a velocity change of
    10 m/s along the aircraft's x axis, which the accelerometers would integrate; they felt
    nothing (the deck's motion, < 0.1 m/s), so the run is released as parked and counted, and
    the matches go on as in the clean run."""
    sc = scenario.load('deck_paper', {'duration_s': 6.0})
    t0 = sc.t0_ns + 3_000_000_000
    fake = {t0 + k * 10_000_000 for k in range(5)}

    def run10(s):
        return replace(s, v_s=np.array([10.0, 0.0, 0.0])) if s.t_ns in fake else s
    f, _ = _run(sc, run10)
    clean, _ = _run(sc, lambda s: s)
    assert not f.deck_motion.moving and f.deck_motion.t_launch_ns is None
    assert f.counters.launch_not_felt == 1 and f.counters.updates == clean.counters.updates
    np.testing.assert_allclose(f.outputs[-1].misalignment, clean.outputs[-1].misalignment, rtol=0, atol=1e-5)
    # without the IMU check (launch_felt_fraction 0) the LDV alone takes it for the launch
    old = replace(sc, filter=replace(sc.filter, launch_felt_fraction=0.0))
    f0, _ = _run(old, run10)
    assert f0.deck_motion.t_launch_ns == t0 and f0.counters.launch_not_felt == 0


def test_the_catapult_is_felt_and_dated_as_without_the_check():
    """The 2 g stroke: by the third LDV sample (0.59 m/s) the accelerometers integrated ~0.6 m/s,
    well above the 0.5 * 0.59 - 0.2 m/s required: the same launch, at the same time."""
    sc = scenario.load('catapult_paper', {'duration_s': 4.0, 'aircraft.catapult.launch_time_s': 2.0})
    f, _ = _run(sc, lambda s: s)
    off = replace(sc, filter=replace(sc.filter, launch_felt_fraction=0.0))
    f0, _ = _run(off, lambda s: s)
    assert f.deck_motion.t_launch_ns == f0.deck_motion.t_launch_ns is not None
    assert f.counters.launch_not_felt == 0
    assert np.array_equal(f.outputs[-1].misalignment, f0.outputs[-1].misalignment)


def test_the_felt_check_integrates_specific_force_against_the_parked_baseline():
    """The detector alone: parked at a 0.5 m/s^2 offset (gravity on a pitched deck), then 2 g along
    x from 2.0 s, the IMU fed to 2.29 s. The run starts at the first fast LDV sample (2.01 s); the
    velocity change is summed over the intervals after 1.91 s less the baseline (the offset, which
    cancels exactly): 2 g * 0.29 s, against the 0.5 * 0.588 - 0.2 m/s the run's speed requires."""
    lim = LaunchThresholds(0.05, 3, 0.0, 25, 0, 0.5, 0.2)
    d = LaunchDetector(lim)
    ms = 1_000_000
    t_launch = 2000 * ms
    for k in range(1, 230):
        t = k * 10 * ms
        d.observe_imu(t, 0.5 + (19.6133 if t > t_launch else 0.0), 0.01)
    for k, v in enumerate((0.196, 0.392, 0.588)):
        dec = d.observe(LdvSample(t_launch + (k + 1) * 10 * ms, np.array([v, 0.0, 0.0]), 0.01, True))
    assert dec.launch_ns == t_launch + 10 * ms
    dv = 19.6133 * 0.29                                    # 2 g over the intervals ending (1.91 s, 2.29 s]
    assert d.felt_margin_mps == pytest.approx(dv - (0.5 * 0.588 - 0.2), rel=1e-9)


def _stroke_seen_late(blind_from_s: float | None, accel: float, ldv_accel: float = 19.6133) -> LaunchDetector:
    """The detector alone: parked at a 0.5 m/s^2 offset, the IMU feeling `accel` along x from 2.0 s,
    fed to 3.0 s; the LDV valid and parked up to `blind_from_s` (None: never valid), then blind
    until it first sees the aircraft at 2.5 s, at the speed a `ldv_accel` stroke reaches then."""
    d = LaunchDetector(LaunchThresholds(0.05, 3, 0.0, 25, 0, 0.5, 0.2))
    ms = 1_000_000
    for k in range(1, 301):             # in stamp order, as the engine feeds it: the IMU, then the LDV
        t = k * 10 * ms
        d.observe_imu(t, 0.5 + (accel if t > 2000 * ms else 0.0), 0.01)
        if t >= 2500 * ms:
            v = ldv_accel * (t - 2000 * ms) * 1e-9
            d.observe(LdvSample(t, np.array([v, 0.0, 0.0]), 0.01, True))
        else:
            seen = blind_from_s is not None and t < blind_from_s * 1e9
            d.observe(LdvSample(t, np.zeros(3), 0.01 if seen else float('nan'), seen))
    return d


@pytest.mark.parametrize('blind_from_s', [1.0, None])
def test_a_stroke_the_ldv_first_sees_halfway_is_felt_from_where_it_went_blind(blind_from_s):
    """2 g from 2.0 s, the LDV blind from 1.0 s (a dropout) or never valid (out of range at the
    spot) until 2.5 s, when the aircraft already does 9.8 m/s: the accelerometers felt the whole
    9.8 m/s since the LDV last saw it parked, not the 0.1 s before its first fast sample (that
    check released the stroke as parked, and the matches took a 10 m/s innovation as the deck's).
    The launch is dated where the IMU felt the stroke begin, 2.0 s (a step: an interval early at
    most), not at the first fast sample (2.5 s: the launch noise started half a second late)."""
    d = _stroke_seen_late(blind_from_s, 19.6133)
    assert d.moving and d.t_launch_ns is not None and 1990 * 1_000_000 <= d.t_launch_ns <= 2000 * 1_000_000
    assert d.felt_margin_mps > 0.0


def test_after_a_blind_spell_an_ldv_reading_the_imu_did_not_feel_is_still_not_a_launch():
    """The same LDV (blind from 1.0 s, then 'fast' from 2.5 s) on a deck that never moved: the
    accelerometers felt nothing since the LDV last saw the aircraft parked, so no launch."""
    d = _stroke_seen_late(1.0, 0.0, ldv_accel=19.6133)
    assert not d.moving and d.t_launch_ns is None


def test_a_blind_stroke_is_dated_where_the_imu_felt_it_begin_despite_the_decks_motion():
    """Parked on a deck that surges (0.3 m/s^2 at 8 s along x, on a 0.5 m/s^2 offset), the LDV blind
    from 1.0 s; a 2 g stroke from 5.0 s, first seen at 5.5 s. The parked level is the felt speed's
    lowest over the half second before it reaches a tenth of the stroke's: the deck's residual
    motion (+-0.4 m/s since the blind spell began) does not move the date by more than an IMU
    interval or two."""
    d = LaunchDetector(LaunchThresholds(0.05, 3, 0.0, 25, 0, 0.5, 0.2))
    ms = 1_000_000
    for k in range(1, 601):
        t = k * 10 * ms
        surge = 0.3 * np.sin(2.0 * np.pi * t * 1e-9 / 8.0)
        d.observe_imu(t, 0.5 + surge + (19.6133 if t > 5000 * ms else 0.0), 0.01)
        if t >= 5500 * ms:
            d.observe(LdvSample(t, np.array([19.6133 * (t - 5000 * ms) * 1e-9, 0.0, 0.0]), 0.01, True))
        else:
            seen = t < 1000 * ms
            d.observe(LdvSample(t, np.zeros(3), 0.01 if seen else float('nan'), seen))
    assert d.moving and d.t_launch_ns is not None
    assert abs(d.t_launch_ns - 5000 * ms) <= 20 * ms


@pytest.mark.parametrize('ramp_s', [0.2, 1.0, 2.0, 4.0])
def test_a_blind_stroke_that_ramps_up_is_dated_at_the_start_of_its_ramp(ramp_s):
    """The acceleration grows linearly from zero to 2 g over `ramp_s` from 5.0 s (the speed rises as
    k t^2 / 2, k = 2 g / ramp_s); the LDV blind from 1.0 s until 0.8 s after the ramp. The speed passes
    the felt tolerance (0.2 m/s) at t_c = sqrt(0.4 / k); back along the ramp with the slope averaged
    over the next 50 ms, k (t_c + 0.025), the date is t_c - t_c^2 / (t_c + 0.025) late, under 25 ms,
    and snapped to an IMU interval's end: within 35 ms of 5.0 s. (The tolerance's crossing alone
    dated it 50, 130, 320 and 940 ms late.)"""
    d = LaunchDetector(LaunchThresholds(0.05, 3, 0.0, 25, 0, 0.5, 0.2))
    ms = 1_000_000
    g2 = 19.6133

    def speed(t_s: float) -> float:
        r = min(max(t_s - 5.0, 0.0), ramp_s)
        return g2 * (0.5 * r * r / ramp_s + max(t_s - 5.0 - ramp_s, 0.0))
    first_seen = 5000 + 800 + int(ramp_s * 1000)
    for k in range(1, first_seen // 10 + 21):
        t = k * 10 * ms
        d.observe_imu(t, 0.5 + (speed(t * 1e-9) - speed(t * 1e-9 - 0.01)) / 0.01, 0.01)   # the interval's mean
        seen = t < 1000 * ms or t >= first_seen * ms
        d.observe(LdvSample(t, np.array([speed(t * 1e-9) if seen else 0.0, 0.0, 0.0]), 0.01, seen))
    assert d.moving and d.t_launch_ns is not None
    assert abs(d.t_launch_ns - 5000 * ms) <= 35 * ms


def test_the_window_kernels_are_numpys_arithmetic():
    """The speed, the window's running sum and its mean's speed: numpy's own operations (v @ v,
    total -= old, total += new, total / count) bit for bit, compiled and interpreted."""
    from alignment_core.estimation.launch_detection import mean_speed, norm3, slide
    rng = np.random.default_rng(3)
    total = np.zeros(3)
    want = np.zeros(3)
    window: list[np.ndarray] = []
    for k in range(400):
        v = rng.standard_normal(3) * 10.0 ** rng.uniform(-4, 1)
        assert norm3(v) == norm3.py_func(v) == float(np.sqrt(v @ v))
        full = len(window) == 25
        old = window.pop(0) if full else v
        if full:
            want -= old
        want += v
        (slide if k % 2 else slide.py_func)(total, old, v, full)
        window.append(v)
        assert np.array_equal(total, want)
        mean = want / 25
        assert mean_speed(total, 25) == mean_speed.py_func(total, 25) == float(np.sqrt(mean @ mean))


def test_a_valid_sample_taken_in_one_call_is_the_three_kernels():
    """take_valid: the same running sum, the same speed and the same window speed as slide,
    norm3 and mean_speed called one by one (a window of no samples too: its non-finite speed),
    bit for bit."""
    from alignment_core.estimation.launch_detection import mean_speed, norm3, slide, take_valid
    rng = np.random.default_rng(7)
    total, want = np.zeros(3), np.zeros(3)
    window: list[np.ndarray] = []
    for k in range(200):
        v = rng.standard_normal(3) * 10.0 ** rng.uniform(-4, 1)
        full = len(window) == 25
        old = window.pop(0) if full else v
        count = 25 if k % 7 else 0
        speed, mean = take_valid(total, old, v, full, count)
        slide(want, old, v, full)
        window.append(v)
        assert np.array_equal(total, want)
        assert speed == norm3(v)
        assert np.float64(mean).tobytes() == np.float64(mean_speed(want, count)).tobytes()
