"""The ship truth with `course_keeping: mmg`: INS consistency through a turn at sea state 6
(the critical check), sample-by-sample evaluation equal to the batch, the turn and the wind
really happen, and bad configuration values are rejected naming the key (library and node).

`python bench/ship_motion.py --mmg --ins` runs the consistency over the hour."""
from __future__ import annotations

import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from support.ins_consistency import ATT_TOL, NOISE_OFF, VEL_TOL, strapdown_errors

from alignment_core import pipeline
from alignment_core.config import scenario
from alignment_core.validation import ConfigError

ROOT = Path(__file__).resolve().parents[2]
TURN_SS6 = {'ship.mode': 'spectral', 'ship.sea_state': 6, 'ship.speed_kn': 20.0,
            'ship.wave_heading_deg': 120.0, 'ship.course_keeping': 'mmg', 'ship.turn_at_s': 60.0,
            'ship.turn_to_deg': 120.0, 'ship.wind_speed_kn': 25.0, 'ship.wind_from_deg': 70.0}


def test_strapdown_reproduces_the_truth_through_a_turn_at_sea_state_6():
    """Noise-free slave IMU 100 m from the master, 10 min: 20 kn on 030, a 90 deg turn to 120
    ordered at 60 s (the rudder hard over), 25 kn of wind, bow-quartering seas turning to
    the beam; strapdown from the true initial state within 1e-6 rad and 1e-3 m/s."""
    sc = scenario.load('deck_paper', {**NOISE_OFF, **TURN_SS6, 'aircraft.lever_arm_m': [90.0, -40.0, 15.0],
                                'duration_s': 600.0})
    att, vel, truth = strapdown_errors(sc)
    assert len(att) == 60000 and np.all(truth['on_deck'])
    lf = pipeline.ship_source(sc).track.kinematics(np.array([0.0, 600.0]))
    assert math.degrees(lf['psi'][0]) == pytest.approx(30.0, abs=0.5)
    assert math.degrees(lf['psi'][1]) == pytest.approx(120.0, abs=1.0)
    assert att.max() < ATT_TOL, f'attitude error {att.max():.3g} rad'
    assert vel.max() < VEL_TOL, f'velocity error {vel.max():.3g} m/s'


def test_strapdown_reproduces_the_paper_ship_on_the_mmg_track():
    """Paper mode: the seed's sinusoids about the MMG track driven by the box-ship forces."""
    sc = scenario.load('deck_paper', {**NOISE_OFF, 'ship.sea_state': 6, 'ship.course_keeping': 'mmg',
                                'ship.turn_at_s': 20.0, 'ship.turn_to_deg': 60.0,
                                'aircraft.lever_arm_m': [90.0, -40.0, 15.0], 'duration_s': 120.0})
    att, vel, _ = strapdown_errors(sc)
    assert att.max() < ATT_TOL and vel.max() < VEL_TOL


@pytest.mark.parametrize('mode', ['spectral', 'paper'])
def test_sample_by_sample_equals_the_batch(mode):
    """The node asks for one sample at a time (and the track extends lazily): the same
    numbers as the batch, whatever the order (to the last bit but for the rounding of
    small matrix products, as in 'straight')."""
    ov = {**TURN_SS6, 'ship.mode': mode, 'duration_s': 40.0, 'ship.n_frequencies': 30,
          'ship.n_directions': 5}
    sc = scenario.load('deck_paper', ov)
    taus = np.arange(sc.n_samples) * sc.dt_ns / 1e9
    batch = pipeline.ship_source(sc).samples(taus, sc.t0_ns, sc.dt_ns)
    single = pipeline.ship_source(sc)
    for k in (3999, 17, 1234, 0, 4000):
        s = single.samples(np.array([taus[k]]), sc.t0_ns, sc.dt_ns, k0=k)[0]
        b = batch[k]
        assert s.t_ns == b.t_ns
        for f in ('p_w', 'q_nb', 'v_b', 'w_b', 'a_b', 'wdot_b'):
            np.testing.assert_allclose(getattr(s, f), getattr(b, f), rtol=1e-14, atol=1e-13,
                                       err_msg=f'{f} at sample {k}')


def test_wind_heels_the_ship_by_the_heeling_arm():
    """A steady beam wind from starboard heels the ship to port: in the steady state the
    hull and rudder lateral forces balance the wind's, Y_H + Y_R = -Y_W, acting z_H below G
    while the wind acts h above it, so phi = (h + z_H) Y_W / (m g GM) (the heeling arm of
    stability books). Y_W with the relative wind of the ship's speed (its small sway drift
    neglected: 5 %). The autopilot holds the course (within 0.2 deg: the 600 s warm-up
    before t = 0 trims most of the wind's yaw moment)."""
    from alignment_core.ship.manoeuvring.mmg import CARRIER, RHO_AIR
    ov = {'ship.mode': 'spectral', 'ship.sea_state': 0, 'ship.course_keeping': 'mmg',
          'ship.heading_deg': 0.0, 'ship.wind_speed_kn': 40.0, 'ship.wind_from_deg': 90.0,
          'ship.speed_kn': 15.0}
    sc = scenario.load('deck_paper', ov)
    lf = pipeline.ship_source(sc).track.kinematics(np.array([0.0, 900.0]))
    assert np.degrees(lf['psi']) == pytest.approx([0.0, 0.0], abs=0.2)
    vw, u = 40.0 * 0.514444, np.linalg.norm(lf['v_n'][1])
    g = -math.atan2(vw, u)                       # relative wind angle (from starboard: < 0)
    yw = 0.5 * RHO_AIR * (vw * vw + u * u) * CARRIER.area_lateral * CARRIER.c_y * math.sin(g)
    heel = (CARRIER.wind_arm + CARRIER.z_h) * yw / (CARRIER.mass * 9.80665 * CARRIER.gm)
    assert lf['phi'][1] < 0.0
    assert lf['phi'][1] == pytest.approx(heel, rel=0.05)


@pytest.mark.parametrize('key,value,message', [
    ('ship.ship_model', 'nimitz', "ship.ship_model: must be one of \\['carrier', 'kvlcc2'\\]"),
    ('ship.course_keeping', 'pid', 'ship.course_keeping: must be one of'),
    ('ship.autopilot_kp', -1.0, 'ship: autopilot_kp must be > 0'),
    ('ship.autopilot_ki', -0.1, 'ship: autopilot_ki must be >= 0'),
    ('ship.autopilot_kd', -5.0, 'ship: autopilot_kd must be >= 0'),
    ('ship.rudder_rate_dps', 0.0, 'ship: rudder_rate_dps must be in'),
    ('ship.rudder_max_deg', 60.0, 'ship: rudder_max_deg must be in'),
    ('ship.turn_to_deg', 400.0, 'ship: turn_to_deg must be a heading'),
    ('ship.speed_to_kn', 0.5, 'ship: speed_to_kn must be negative'),
    ('ship.wind_speed_kn', -3.0, 'ship: wind_speed_kn must be in'),
    ('ship.mmg_step_s', 5.0, 'ship: mmg_step_s must be in'),
    ('ship.speed_kn', 0.0, "ship: speed_kn must be >= 1 with course_keeping 'mmg'"),
])
def test_bad_values_are_rejected_naming_the_key(key, value, message):
    ov = {'ship.course_keeping': 'mmg', 'ship.turn_at_s': 10.0, key: value}
    with pytest.raises(ConfigError, match=message):
        scenario.load('deck_paper', ov)


def test_ship_motion_node_refuses_a_bad_autopilot_gain():
    """The node declares the new ship parameters from the scenario dataclasses and validates
    them at start-up: exit code 2 and the key in its message."""
    from alignment_ros import domain
    dom = domain.claim()
    try:
        env = dict(os.environ, ROS_DOMAIN_ID=str(dom))
        p = subprocess.run([str(ROOT / 'scripts/start_node.sh'), 'ship_motion_node', '--params-file',
                            str(ROOT / 'config/params/catapult_paper.yaml'), '--ros-args', '-p',
                            'ship.autopilot_kp:=-1.0'], env=env, capture_output=True, text=True,
                           timeout=60)
    finally:
        domain.release(dom)
    assert p.returncode == 2, p.stdout + p.stderr
    assert 'autopilot_kp must be > 0' in p.stdout + p.stderr
