"""The beam LDV (ldv.mode: beam, sensors/ldv_beam.py): its reading is the range rate d|d|/dt of the
line from the head on the deck to the reflector on the aircraft, checked against finite
differences of that distance computed from the world positions of both points (a rolling,
pitching, turning, heaving ship; the aircraft running along the deck, swaying and pitching on
its gear, the reflector 3 m from the IMU); the geometric blockage; the sample's layout; the
vector mode untouched."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from alignment_core.geometry import earth
from alignment_core.samples import ShipBatch
from alignment_core.sensors.ldv import LdvConfig, LdvModel

PLANE = earth.TangentPlane(0.7, 2.0, 0.0)
R0 = np.array([40.0, -10.0, 15.0])          # the IMU's deck spot, ship axes
MOUNT = np.array([100.0, -6.0, 16.0])       # the head, ship axes
REFLECTOR = np.array([3.0, 0.4, -1.2])      # aircraft axes, from the IMU
PSI = 0.02                                  # heading on deck, rad


def ship_pose(t: float) -> tuple[np.ndarray, Rotation]:
    """World position and attitude (nav <- ship) of a ship heaving at the plane's origin (a ship
    under way turns its local level at the transport rate, |v| / R = 1e-7 rad/s at 0.6 m/s, which
    the LDV model neglects, as the vector mode does: 6e-6 m/s at 60 m)."""
    p = np.array([0.0, 0.0, 0.6 * np.sin(0.6 * t)])
    c = Rotation.from_euler('ZYX', [0.3 + 0.02 * t, 0.05 * np.sin(0.5 * t), 0.08 * np.sin(0.7 * t + 0.4)])
    return p, c


def aircraft_in_ship(t: float) -> tuple[np.ndarray, Rotation]:
    """The IMU's position (ship axes) and the aircraft's attitude relative to the ship: a 2 g run
    along the deck with a lateral sway, pitching and rolling on its gear."""
    r = R0 + np.array([0.5 * 19.6 * t ** 2, 0.2 * np.sin(1.3 * t), 0.05 * np.sin(2.5 * t)])
    c_as = Rotation.from_euler('ZYX', [-PSI, 0.03 * np.sin(2.0 * t), 0.02 * np.cos(1.7 * t)])
    return r, c_as


def world(t: float) -> dict:
    """Everything in world / nav axes at t. The nav frame is the local level at the ship (the
    aircraft's own, 40-100 m away, differs by 1e-5 rad; the LDV model uses the ship's)."""
    p_s, c_sn = ship_pose(t)
    c_lw = PLANE.c_local_to_world(p_s)
    r, c_as = aircraft_in_ship(t)
    c_an = c_sn * c_as
    p_a = p_s + c_lw @ c_sn.apply(r)
    return {'p_s': p_s, 'c_sn': c_sn, 'c_lw': c_lw, 'p_a': p_a, 'c_an': c_an,
            'mount': p_s + c_lw @ c_sn.apply(MOUNT), 'refl': p_a + c_lw @ c_an.apply(REFLECTOR)}


def rate(c0: Rotation, c1: Rotation, h: float) -> np.ndarray:
    """Body rate (own axes) from attitudes at t - h/2... t + h/2 apart by h."""
    return (c0.inv() * c1).as_rotvec() / h


def inputs(times: np.ndarray, h: float = 1e-5):
    """ShipBatch and the aircraft truth (p_w, q_nb, v_b, w_b) at `times`, velocities and rates by
    central differences of the poses above (h = 1e-5 s: errors ~1e-9)."""
    rows = {k: [] for k in ('p_w', 'q_nb', 'v_b', 'w_b', 'pa', 'qa', 'va', 'wa')}
    for t in times:
        a, b, m = world(t - h), world(t + h), world(t)
        c_nl = m['c_lw'].T
        rows['p_w'].append(m['p_s'])
        rows['q_nb'].append(m['c_sn'].as_quat())
        rows['v_b'].append(m['c_sn'].inv().apply(c_nl @ (b['p_s'] - a['p_s']) / (2 * h)))
        rows['w_b'].append(rate(a['c_sn'], b['c_sn'], 2 * h))
        rows['pa'].append(m['p_a'])
        rows['qa'].append(m['c_an'].as_quat())
        rows['va'].append(m['c_an'].inv().apply(c_nl @ (b['p_a'] - a['p_a']) / (2 * h)))
        rows['wa'].append(rate(a['c_an'], b['c_an'], 2 * h))
    arr = {k: np.array(v) for k, v in rows.items()}
    n = len(times)
    sb = ShipBatch(t_ns=(1e9 + times * 1e9).astype(np.int64), p_w=arr['p_w'], q_nb=arr['q_nb'], v_b=arr['v_b'],
                   w_b=arr['w_b'], a_b=np.zeros((n, 3)), wdot_b=np.zeros((n, 3)))
    return sb, arr['pa'], arr['qa'], arr['va'], arr['wa']


def beam_cfg(**kw) -> LdvConfig:
    return LdvConfig(mode='beam', noise_mps=1e-12, origin_m=tuple(R0), track_heading_deg=np.degrees(PSI),
                     track_length_m=60.0, mount_m=tuple(MOUNT), reflector_m=tuple(REFLECTOR), **kw)


def test_beam_reads_the_range_rate_of_the_head_reflector_line():
    times = np.linspace(0.05, 2.2, 40)      # the IMU runs 47 m: the line turns by ~20 deg
    sb, pa, qa, va, wa = inputs(times)
    out = LdvModel(beam_cfg(), seed=1, plane=PLANE).measure_batch(sb, pa, qa, va, wa)
    h = 1e-4
    for k, t in enumerate(times):
        dist = [np.linalg.norm(world(t + s)['refl'] - world(t + s)['mount']) for s in (-h, h)]
        range_rate = (dist[1] - dist[0]) / (2 * h)          # truncation h^2/6 |D'''| < 1e-7 m/s
        w = world(t)
        los_ship = w['c_sn'].inv().apply(w['c_lw'].T @ (w['refl'] - w['mount']))
        s = out[k]
        assert s.valid and s.beam is not None
        np.testing.assert_allclose(s.beam, los_ship / np.linalg.norm(los_ship), rtol=0, atol=1e-9)
        assert float(s.v_s @ s.beam) == pytest.approx(range_rate, abs=1e-6)
        np.testing.assert_allclose(s.v_s, float(s.v_s @ s.beam) * s.beam, rtol=0, atol=1e-12)
    speeds = np.array([float(s.v_s @ s.beam) for s in out])
    assert np.ptp(speeds) > 20.0                             # a real run, not a parked aircraft
    assert np.degrees(np.arccos(out[0].beam @ out[-1].beam)) > 15.0


def test_reflector_lever_arm_and_gear_rotation_matter():
    """Without the aircraft's rate (rigid on the ship assumed) the reflector's own motion on the
    gear is lost: the reading is then off by more than the tolerance above, so the test above
    sees the rotation term."""
    times = np.linspace(0.05, 1.6, 10)
    sb, pa, qa, va, wa = inputs(times)
    with_rate = LdvModel(beam_cfg(), seed=1, plane=PLANE).measure_batch(sb, pa, qa, va, wa)
    rigid = LdvModel(beam_cfg(), seed=1, plane=PLANE).measure_batch(sb, pa, qa, va, None)
    diff = [abs(float(a.v_s @ a.beam) - float(b.v_s @ b.beam)) for a, b in zip(with_rate, rigid)]
    assert max(diff) > 1e-3


def test_blocked_when_the_reflector_faces_away_or_the_head_is_too_near():
    """A ship at rest; the aircraft parked at spots along the track towards the head at
    (100, -6, 16): the reflector (at the IMU, facing forward) sees the head within 45 deg while
    atan(hypot(4, 1) / (100 - x)) <= 45 deg, i.e. x <= 95.88 m; a 1 m minimum range."""
    xs = np.array([40.0, 80.0, 95.8, 95.95, 99.0, 120.0])
    n = len(xs)
    z = np.zeros((n, 3))
    sb = ShipBatch(t_ns=np.arange(n, dtype=np.int64) * 10_000_000 + 1_000_000_000, p_w=z.copy(),
                   q_nb=np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), v_b=z.copy(), w_b=z.copy(), a_b=z.copy(),
                   wdot_b=z.copy())
    p = np.c_[xs, np.full(n, -10.0), np.full(n, 15.0)]
    q = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    cfg = LdvConfig(mode='beam', origin_m=tuple(R0), track_length_m=95.0, mount_m=tuple(MOUNT),
                    reflector_m=(0.0, 0.0, 0.0))
    out = LdvModel(cfg, seed=1, plane=PLANE).measure_batch(sb, p, q, z.copy(), z.copy())
    # 120 m: beyond the track (95 m from the spot) as well
    assert [s.valid for s in out] == [True, True, True, False, False, False]
    assert all(s.beam is None and np.all(s.v_s == 0.0) for s in out[3:])
    near = LdvConfig(mode='beam', origin_m=tuple(R0), track_length_m=95.0, mount_m=(60.0, -10.0, 15.5),
                     reflector_m=(0.0, 0.0, 0.0), reflector_halfangle_deg=90.0, min_range_m=1.0)
    p2 = np.array([[59.5, -10.0, 15.0], [58.0, -10.0, 15.0]])
    out2 = LdvModel(near, seed=1, plane=PLANE).measure_batch(sb.slice(slice(0, 2)), p2, q[:2], z[:2], z[:2])
    assert [s.valid for s in out2] == [False, True]          # 0.71 m and 2.06 m from the head


def test_beam_errors_are_scalar_and_the_noise_is_along_the_beam():
    times = np.linspace(0.05, 1.6, 400)
    sb, pa, qa, va, wa = inputs(times)
    cfg = beam_cfg(bias_mps=0.05, scale_ppm=1000.0)
    clean = LdvModel(beam_cfg(), seed=2, plane=PLANE).measure_batch(sb, pa, qa, va, wa)
    m = LdvModel(LdvConfig(**{**cfg.__dict__, 'noise_mps': 0.01}), seed=2, plane=PLANE)
    noisy = m.measure_batch(sb, pa, qa, va, wa)
    s0 = np.array([float(a.v_s @ a.beam) for a in clean])
    s1 = np.array([float(a.v_s @ a.beam) for a in noisy])
    resid = s1 - (s0 * (1.0 + m.scale[0]) + m.bias[0])
    assert abs(resid.std() - 0.01) < 4 * 0.01 / np.sqrt(2 * len(resid))
    assert abs(resid.mean()) < 4 * 0.01 / np.sqrt(len(resid))
    assert all(a.sigma == 0.01 for a in noisy)


def test_vector_mode_is_todays_and_carries_no_beam():
    times = np.linspace(0.05, 1.6, 5)
    sb, pa, qa, va, wa = inputs(times)
    cfg = LdvConfig(origin_m=tuple(R0), track_heading_deg=np.degrees(PSI), track_length_m=60.0)
    assert cfg.mode == 'vector'
    a = LdvModel(cfg, seed=1, plane=PLANE).measure_batch(sb, pa, qa, va, wa)
    b = LdvModel(cfg, seed=1, plane=PLANE).measure_batch(sb, pa, qa, va)
    for x, y in zip(a, b):
        assert x.beam is None and np.array_equal(x.v_s, y.v_s)
