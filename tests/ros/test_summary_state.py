"""summary.json's whole estimate (summary.state_estimate): the /alignment/state message at the
scored instant (or the last), its labels with their SI units, estimate and 1-sigma rows."""
from __future__ import annotations

import dataclasses

import numpy as np
from rclpy.serialization import serialize_message

from alignment_core.estimation.outputs import Estimate
from alignment_ros import convert, summary
from alignment_ros.bag import BagWriter

NS = 1_000_000_000
LABELS = ('attitude_error_E_rad', 'gyro_bias_x_radps', 'master_delay_s')


def _estimate(t_ns: int, k: int) -> Estimate:
    z3 = np.zeros(3)
    return Estimate(t_ns=t_ns, misalignment=z3, misalignment_sigma=np.full(3, 1e-4), q_nb=np.array([0, 0, 0, 1.0]),
                    attitude_cov=np.eye(3), x=np.full(3, -1.0), sigma=np.array([1e-4, 2e-6, 1e-3]) * (k + 1),
                    bias_gyro=z3, bias_accel=z3, nis=1.0, updates=k, matching=True,
                    state=np.array([0.0, 1e-5, 0.02]) * k)


def test_the_state_at_the_scored_instant_and_the_last(tmp_path):
    bag = tmp_path / 'bag'
    with BagWriter(bag) as w:
        w.add_topic('/alignment/state', 'std_msgs/msg/Float64MultiArray')
        for k in range(5):
            t = NS + k * NS // 10
            w.write('/alignment/state', serialize_message(convert.state_msg(_estimate(t, k), LABELS)), t)
    at = summary.state_estimate(bag, 1.2)
    assert at is not None and abs(at['t_s'] - 1.2) < 1e-9 and at['labels'] == list(LABELS)
    np.testing.assert_allclose(at['estimate'], [0.0, 2e-5, 0.04])
    np.testing.assert_allclose(at['sigma'], np.array([1e-4, 2e-6, 1e-3]) * 3)
    last = summary.state_estimate(bag)
    assert last is not None and abs(last['t_s'] - 1.4) < 1e-9 and last['estimate'][2] == 0.08


def test_no_state_message_no_estimate(tmp_path):
    bag = tmp_path / 'bag'
    with BagWriter(bag) as w:
        w.add_topic('/alignment/state', 'std_msgs/msg/Float64MultiArray')
    assert summary.state_estimate(bag) is None
    e = dataclasses.replace(_estimate(NS, 1), state=None)       # not computed: NaN, never a made-up zero
    assert np.isnan(np.array(convert.state_msg(e, LABELS).data[3:6])).all()


def test_the_whiteness_of_the_filters_last_diagnostics(tmp_path):
    bag = tmp_path / 'bag'
    vals = {'whiteness': 'fail', 'whiteness_q': '812.5', 'whiteness_dof': '30', 'whiteness_p': '1e-150',
            'whiteness_r1_max': '0.91', 'whiteness_band': '0.08765', 'whiteness_windows': '7',
            'whiteness_windows_failed': '6', 'relative_velocity': 'zero (no LDV stream)'}
    for path, last in ((tmp_path / 'early', False), (bag, True)):
        with BagWriter(path) as w:
            w.add_topic('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray')
            for k, name, v in ((1, 'alignment_filter', {}), (2, 'air_data_filter', vals),
                               (3, 'alignment_filter', vals))[:3 if last else 2]:
                w.write('/diagnostics', serialize_message(convert.diagnostics(k * NS, name, b'\x00', 'x', v)), k * NS)
    assert summary.whiteness(tmp_path / 'early') is None     # no window in the alignment filter's yet
    wh = summary.whiteness(bag)
    assert wh == {'result': 'fail', 'relative_velocity': 'zero (no LDV stream)', 'q': 812.5, 'p': 1e-150,
                  'r1_max': 0.91, 'band': 0.08765, 'dof': 30, 'windows': 7, 'windows_failed': 6}
    assert summary.whiteness_line(wh).startswith('innovation whiteness: fail (last window: Ljung-Box p 1e-150')


def test_states_recorded_out_of_order_are_read_by_their_stamps(tmp_path):
    """A state that arrived late (log time after later outputs') is still the one at its stamp."""
    bag = tmp_path / 'bag'
    with BagWriter(bag) as w:
        w.add_topic('/alignment/state', 'std_msgs/msg/Float64MultiArray')
        for i, k in enumerate((0, 3, 4, 1, 2)):
            t = NS + k * NS // 10
            msg = serialize_message(convert.state_msg(_estimate(t, k), LABELS))
            w.write('/alignment/state', msg, NS + i * NS // 10)
    at = summary.state_estimate(bag, 1.2)
    assert at is not None and abs(at['t_s'] - 1.2) < 1e-9
    np.testing.assert_allclose(at['estimate'], [0.0, 2e-5, 0.04])
    last = summary.state_estimate(bag)
    assert last is not None and abs(last['t_s'] - 1.4) < 1e-9
