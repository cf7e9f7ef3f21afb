"""MMG manoeuvring model (Yasukawa & Yoshimura 2015, "Y&Y"): calm-water equilibrium,
the KVLCC2 trials, port/starboard symmetry, steady turn, autopilot course keeping."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import fsolve

from alignment_core.ship.manoeuvring.autopilot import Autopilot, CourseSchedule, SteeringGear, ZigZag
from alignment_core.ship.manoeuvring.course_keeping import ManoeuvringTrack
from alignment_core.ship.manoeuvring.mmg import CARRIER, KVLCC2, KVLCC2_MODEL, MmgModel, rk4_step

U0_MODEL = 1.179          # Y&Y: approach speed of the 7 m KVLCC2 model (Fn 0.142), m/s


def run(ship, command, t_end, h, u0, revs=None, y0=None, gain=5.0):
    """Open-loop manoeuvre: rudder order command(t, y) at each step start, the steering gear
    at the ship's rate; constant propeller revs (equilibrium of u0 unless given)."""
    m = MmgModel(ship)
    n = m.equilibrium_revs(u0) if revs is None else revs
    gear = SteeringGear(math.radians(ship.rudder_max_deg), math.radians(ship.rudder_rate_dps), gain)
    y = list(y0) if y0 is not None else [0.0, 0.0, 0.0, u0, 0.0, 0.0, 0.0, 0.0, 0.0]
    out = [y]
    for k in range(int(round(t_end / h))):
        dc = command(k * h, y)
        y, _ = rk4_step(lambda t, s, dc=dc: m.rhs(s, s[8], n) + [gear.rate_of(s[8], dc)], k * h, y, h)
        out.append(y)
    return np.arange(len(out)) * h, np.array(out)


def turning_indices(ship, delta_deg, u0, h):
    """Advance and tactical diameter (/L) of a turning trial: the forward (original course)
    and lateral displacement of midship when the heading has changed by 90 and 180 deg."""
    t, y = run(ship, lambda t, s: math.radians(delta_deg), 40.0 * ship.lpp / u0, h, u0)
    psi = y[:, 2] * math.copysign(1.0, delta_deg)
    i90, i180 = np.argmax(psi >= math.pi / 2), np.argmax(psi >= math.pi)
    adv = np.interp(math.pi / 2, psi[i90 - 1:i90 + 1], y[i90 - 1:i90 + 1, 0])
    tac = np.interp(math.pi, psi[i180 - 1:i180 + 1], y[i180 - 1:i180 + 1, 1])
    return adv / ship.lpp, abs(tac) / ship.lpp, t, y


def test_calm_water_holds_course_and_the_closed_form_equilibrium_speed():
    """Rudder 0 from a straight start at 60 % speed: no sway or yaw at all, and the speed
    settles where Y&Y's surge equation balances at v = r = 0 (X_R = 0 at delta = 0):
      (1 - t_P) rho n^2 D^4 (k0 + k1 J + k2 J^2) = 1/2 rho L d R'_0 u^2,  J = (1 - w_P0) u/(n D),
    i.e. [k2 a^2 - c] u^2 + k1 a n D u + k0 n^2 D^2 = 0 with a = 1 - w_P0 and
    c = L d R'_0 / (2 (1 - t_P) D^2): the positive root, for a fixed n = 10 rps (model)."""
    s = KVLCC2_MODEL
    n, a = 10.0, 1.0 - s.w_p0
    c = s.lpp * s.draft * s.r0 / (2.0 * (1.0 - s.t_p) * s.d_p**2)
    qa, qb, qc = s.k2 * a * a - c, s.k1 * a * n * s.d_p, s.k0 * n * n * s.d_p**2
    u_eq = (-qb - math.sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa)
    y0 = [0.0, 0.0, 0.0, 0.6 * u_eq, 0.0, 0.0, 0.0, 0.0, 0.0]
    t, y = run(s, lambda t, st: 0.0, 1200.0, 0.2, u_eq, revs=n, y0=y0)
    assert np.max(np.abs(y[:, [1, 2, 4, 5, 6, 7, 8]])) == 0.0      # east, psi, v, r, phi, p, delta
    assert y[-1, 3] == pytest.approx(u_eq, rel=1e-9)
    # and MmgModel.equilibrium_revs inverts it
    assert MmgModel(s).equilibrium_revs(u_eq) == pytest.approx(n, rel=1e-12)


# Y&Y (2015) simulated the 7 m KVLCC2 model (their Tables 1-3) at 1.179 m/s with the rudder
# at 15.8 deg/s. Their Table 4 (35 deg turning, 7 m model), as transcribed by two independent
# public sources (JuliaComputing/DyadShip scripts/validate_kvlcc2.jl, which cites Table 4, and a
# second implementation plan citing "Table 4 p12"; we could not read the paper itself here):
# simulation starboard AD 3.31 L, DT 3.36 L, port 3.26 / 3.26; free-running test starboard
# 3.25 / 3.34, port 3.11 / 3.08. Ours (h = 0.05 s, revs at the calm-water equilibrium of
# R'_0 = 0.022, 11.85 rps): starboard 3.08 / 3.12, port 3.09 / 3.11 -- 7 % tighter than their
# simulation, 5 % than their test. Our equations were checked against three independent
# implementations (ShipMMG.jl, shipmmg, tud_rl) to 1e-13 at 2000 random states and every
# coefficient against their transcriptions of Table 3; the paper's propeller revs and
# resistance for its 7 m-model simulation are what we lack (10 % lower R'_0 alone moves us to
# 3.18 / 3.22). The 10/10 zig-zag overshoots (their Table 5) were not found in any reachable
# source, so no test compares them (ours: 5.0 / 13.8 deg; 20/20: 10.6 / 15.7 deg); the zig-zag
# order itself is tested below against the trial's definition.
YY2015_TURNING_35_STBD = (3.31, 3.36)   # (advance / L, tactical diameter / L), Y&Y 2015 Table 4, simulation


@pytest.mark.xfail(strict=True, reason="7 % tighter than Y&Y's simulated 35 deg turn (their 7 m-model "
                                       "simulation conditions are not available; see the comment above)")
def test_kvlcc2_turning_circle_matches_yasukawa_yoshimura():
    adv, tac, _, _ = turning_indices(KVLCC2_MODEL, 35.0, U0_MODEL, 0.05)
    assert adv == pytest.approx(YY2015_TURNING_35_STBD[0], rel=0.05)
    assert tac == pytest.approx(YY2015_TURNING_35_STBD[1], rel=0.05)


@pytest.mark.parametrize('first', [1.0, -1.0], ids=['starboard-first', 'port-first'])
def test_zigzag_order_reverses_when_the_heading_passes_the_deviation(first):
    """An angle/deviation zig-zag (ITTC 7.5-04-02-01): rudder `angle` to the first side; reversed
    the moment the heading change from the initial heading reaches `deviation` on that side,
    and again when it reaches `deviation` on the other side; held in between."""
    psi0, dev, angle = math.radians(30.0), math.radians(10.0), math.radians(20.0)
    zz = ZigZag(angle, dev, psi0, first)
    change_deg = [0.0, 5.0, 9.99, 10.01, 12.0, 3.0, -9.99, -10.01, -11.0, 0.0, 9.99, 10.01]
    want_side = [1, 1, 1, -1, -1, -1, -1, 1, 1, 1, 1, -1]
    got = [zz(psi0 + first * math.radians(d)) for d in change_deg]
    assert got == [first * s * angle for s in want_side]


def test_full_scale_kvlcc2_repeats_the_model_trials():
    """Froude similarity: with every primed coefficient the same, the full-scale ship (Y&Y
    Table 1, rudder rate scaled by 1/sqrt(45.7)) turns on the same circle in ship lengths
    as the 7 m model (the particulars differ by their rounding, < 1 %)."""
    m_adv, m_tac, _, _ = turning_indices(KVLCC2_MODEL, 35.0, U0_MODEL, 0.05)
    f_adv, f_tac, _, _ = turning_indices(KVLCC2, 35.0, U0_MODEL * math.sqrt(320.0 / 7.0), 0.4)
    assert f_adv == pytest.approx(m_adv, rel=0.01)
    assert f_tac == pytest.approx(m_tac, rel=0.01)


@pytest.mark.parametrize('ship', [CARRIER, dataclasses.replace(KVLCC2_MODEL, c2_minus=1.6,
                                                                 gamma_r_minus=0.640)],
                         ids=['carrier', 'kvlcc2-symmetric'])
def test_turning_circle_port_and_starboard_are_mirror_images(ship):
    """A ship whose coefficients are the same both ways (the carrier's twin screws; KVLCC2
    with Y&Y's starboard C2 and gamma_R on both sides) turns to port on the mirror image of
    its starboard circle: east, heading, sway, yaw rate and roll change sign, the rest not."""
    u0 = 15.0 * 0.514444 if ship is CARRIER else U0_MODEL
    h = 0.5 if ship is CARRIER else 0.05
    a1, t1, _, ys = turning_indices(ship, 35.0, u0, h)
    a2, t2, _, yp = turning_indices(ship, -35.0, u0, h)
    mirror = np.array([1, -1, -1, 1, -1, -1, -1, -1, -1])
    np.testing.assert_allclose(yp, ys * mirror, rtol=1e-9, atol=1e-9 * ship.lpp)
    assert (a1, t1) == pytest.approx((a2, t2), rel=1e-9)


def test_steady_turn_matches_the_algebraic_force_balance():
    """After the transient, the 35 deg turn is a circle whose speed and yaw rate solve the
    steady equations (u' = v' = r' = 0 of the model's force balance, solved by fsolve):
    diameter 2 U / r. Checks the integration and the track kinematics, not the forces."""
    ship = KVLCC2_MODEL
    m = MmgModel(ship)
    n = m.equilibrium_revs(U0_MODEL)
    delta = math.radians(35.0)

    def resid(x):
        d = m.rhs([0.0, 0.0, 0.0, x[0], x[1], x[2], 0.0, 0.0], delta, n)
        return [d[3] * 10.0, d[4] * 10.0, d[5] * 100.0]
    u, v, r = fsolve(resid, [0.5 * U0_MODEL, -0.1 * U0_MODEL, 0.1], xtol=1e-13)
    diameter = 2.0 * math.hypot(u, v) / r
    _, _, t, y = turning_indices(ship, 35.0, U0_MODEL, 0.05)
    late = t > t[-1] - 2.0 * math.pi / r                         # the last full circle
    north, east = y[late, 0], y[late, 1]
    # circle through the last positions: diameter from the extent of the track
    assert (np.ptp(north) + np.ptp(east)) / 2.0 == pytest.approx(diameter, rel=2e-3)
    assert y[-1, 5] == pytest.approx(r, rel=1e-5)


def test_autopilot_holds_and_changes_course():
    """The carrier holds its course in a beam wind (heading within 0.01 deg after 20 min,
    the integral trims the wind's yaw moment) and turns 90 deg on order, settling within
    0.5 deg of the new course 10 min after the order."""
    from alignment_core.ship.manoeuvring.mmg import Wind
    model = MmgModel(CARRIER, Wind(20.0, math.radians(120.0)))
    rmax = math.radians(35.0)
    ap = Autopilot(2.0, 0.01, 60.0, rmax)
    gear = SteeringGear(rmax, math.radians(2.5), 2.0)
    sched = CourseSchedule(math.radians(30.0), 20 * 0.514444, 1200.0, math.radians(120.0))
    tr = ManoeuvringTrack(model, ap, gear, sched, math.radians(40.0), math.radians(116.0), 0.5)
    k = tr.kinematics(np.array([1200.0, 1800.0]))
    assert math.degrees(k['psi'][0]) == pytest.approx(30.0, abs=0.01)
    assert math.degrees(k['psi'][1]) == pytest.approx(120.0, abs=0.5)


def _counted_steps(monkeypatch) -> list[int]:
    """A one-element list that counts the RK4 steps course_keeping takes from now on."""
    import alignment_core.ship.manoeuvring.course_keeping as ck
    steps = [0]

    def counted(*args):
        steps[0] += 1
        return rk4_step(*args)
    monkeypatch.setattr(ck, 'rk4_step', counted)
    return steps


def _track_parts(change_at_s: float) -> tuple:
    """ManoeuvringTrack's arguments for the carrier turning from 30 to 60 deg at change_at_s."""
    rmax = math.radians(35.0)
    return (MmgModel(CARRIER), Autopilot(2.0, 0.01, 60.0, rmax), SteeringGear(rmax, math.radians(2.5), 2.0),
            CourseSchedule(math.radians(30.0), 20 * 0.514444, change_at_s, math.radians(60.0)),
            math.radians(40.0), math.radians(116.0), 0.5)


def test_tracks_of_one_configuration_share_their_start_bit_for_bit(monkeypatch):
    """Tracks made with one SharedStart, read in turns: nothing is stored while there is one
    track (a process with one track keeps no copy), then each block by whichever track reaches
    it first, up to SHARED_BLOCKS; a third track integrates only the block beyond them; each
    one's kinematics, read in turns, are those of a track made alone, bit for bit."""
    import alignment_core.ship.manoeuvring.course_keeping as ck
    monkeypatch.setattr(ck, 'SHARED_BLOCKS', 2)
    steps = _counted_steps(monkeypatch)
    parts = _track_parts(change_at_s=300.0)
    early, late = np.linspace(0.0, 400.0, 801), np.linspace(400.5, 1100.0, 1400)   # three blocks of 512 s
    alone = ManoeuvringTrack(*parts, warmup=60.0)
    want = [alone.kinematics(early), alone.kinematics(late)]
    shared = ck.SharedStart()
    first = ManoeuvringTrack(*parts, warmup=60.0, shared=shared)
    got_first = [first.kinematics(early)]
    assert shared.warm is None and not shared.blocks           # one track so far: nothing kept
    second = ManoeuvringTrack(*parts, warmup=60.0, shared=shared)
    got_second = [second.kinematics(early)]                    # the warm-up and the first block, stored
    got_first.append(first.kinematics(late))                   # the second block stored by the first track
    got_second.append(second.kinematics(late))                 # replayed, then its third integrated
    assert shared.warm is not None and len(shared.blocks) == 2
    steps[0] = 0
    third = ManoeuvringTrack(*parts, warmup=60.0, shared=shared)
    other_times = [early + 0.25, late + 0.25]                  # not asked for before: not recalled
    got_third = [third.kinematics(x) for x in other_times]
    assert steps[0] == ck.BLOCK                                # the third block alone
    want_third = [alone.kinematics(x) for x in other_times]
    for got, want_of in ((got_first, want), (got_second, want), (got_third, want_third)):
        for part, want_part in zip(got, want_of, strict=True):
            for key, value in want_part.items():
                assert part[key].tobytes() == value.tobytes(), key


def test_tracks_of_one_configuration_share_their_kinematics_bit_for_bit(monkeypatch):
    """Kinematics asked for again at the same times, once the configuration has a second track,
    are stored and then recalled by any of its tracks without integrating: the numbers of a track
    made alone, bit for bit, as copies (a caller's change to them is not recalled). Nothing is
    stored while there is one track, nor times asked for once (a stepped run's chunks); the
    oldest go when the store is full, and a set larger than it is never stored."""
    import alignment_core.ship.manoeuvring.course_keeping as ck
    steps = _counted_steps(monkeypatch)
    parts = _track_parts(change_at_s=100.0)
    times = [np.linspace(0.0, 300.0, 3001), np.linspace(0.05, 300.05, 3001), np.linspace(0.1, 300.1, 3001)]
    alone = ManoeuvringTrack(*parts, warmup=60.0)
    want = [alone.kinematics(t) for t in times]
    shared = ck.SharedStart()
    first = ManoeuvringTrack(*parts, warmup=60.0, shared=shared)
    first.kinematics(times[0])
    second = ManoeuvringTrack(*parts, warmup=60.0, shared=shared)
    for t in times[:2]:
        second.kinematics(t)
    assert not shared.kinematics                               # one track, then asked for once: nothing kept
    third = ManoeuvringTrack(*parts, warmup=60.0, shared=shared)
    stored = [third.kinematics(t) for t in times[:2]]          # asked for again: stored
    assert list(shared.kinematics) == [times[0].tobytes(), times[1].tobytes()]
    stored[0]['lat'][:] = 0.0                                  # the storing caller's arrays: a copy was kept
    steps[0] = 0
    fourth = ManoeuvringTrack(*parts, warmup=60.0, shared=shared)
    again = [fourth.kinematics(t) for t in times[:2]]
    assert steps[0] == 0                                       # recalled: nothing integrated
    for part, want_part in zip(again, want[:2], strict=True):
        assert part.keys() == want_part.keys()
        for key, value in want_part.items():
            assert part[key].tobytes() == value.tobytes(), key
    again[0]['lat'][:] = 0.0                                   # a recalled copy
    assert fourth.kinematics(times[0])['lat'].tobytes() == want[0]['lat'].tobytes()
    one = len(times[0].tobytes()) + sum(a.nbytes for a in want[0].values())
    monkeypatch.setattr(ck, 'SHARED_KINEMATICS_BYTES', 2 * one)
    fourth.kinematics(times[2])
    fourth.kinematics(times[2])                                # the third set: the oldest goes
    assert list(shared.kinematics) == [times[1].tobytes(), times[2].tobytes()]
    monkeypatch.setattr(ck, 'SHARED_KINEMATICS_BYTES', one - 1)
    fresh = ck.SharedStart()
    fresh.users = 2
    for _ in range(3):
        fresh.store_kinematics(times[0].tobytes(), want[0])   # larger than the store: never kept
    assert not fresh.kinematics
    monkeypatch.setattr(ck, 'SHARED_KINEMATICS_BYTES', 4 * one)
    monkeypatch.setattr(ck, 'ASKED_KEPT', 1)                   # remembers one first ask at a time
    a, b = times[0].tobytes(), times[1].tobytes()
    fresh.store_kinematics(a, want[0])
    fresh.store_kinematics(b, want[1])                         # forgets a's ask
    fresh.store_kinematics(a, want[0])
    assert not fresh.kinematics                                # a's ask again counts as its first
    fresh.store_kinematics(a, want[0])
    assert list(fresh.kinematics) == [a]


def test_make_track_shares_a_start_per_configuration_and_keeps_a_few():
    from alignment_core.config import scenario
    from alignment_core.ship import track
    cfg = scenario.load('deck').ship
    track.forget_shared_starts()                    # other tests of this process made tracks of it
    a, b = track.make_track(cfg), track.make_track(cfg)
    assert a._shared is not None and a._shared is b._shared and a._shared.users == 2
    other = track.make_track(dataclasses.replace(cfg, heading_deg=cfg.heading_deg + 10.0))
    assert other._shared is not a._shared
    assert track.make_track(cfg, external=lambda t, n, e, psi: (0.0, 0.0, 0.0, 0.0))._shared is None
    for k in range(track.SHARED_CONFIGURATIONS + 2):
        track.make_track(dataclasses.replace(cfg, heading_deg=float(k)))
    assert len(track._SHARED) == track.SHARED_CONFIGURATIONS
    track.forget_shared_starts()
    assert track.make_track(cfg)._shared is not a._shared
