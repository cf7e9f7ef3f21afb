"""The plots and the report from a small bag written here: /alignment/state read by its labels
(today's layout and a unit-labelled one), units from the state names, the NIS dof recovered from
the monitor's published bound, figures drawn only for the topics present, and report.md's
tables. The graph runs of tests/graph/test_watch.py check them on real runs."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Vector3Stamped
from rclpy.serialization import serialize_message
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from alignment_core.estimation.consistency import NisMonitor
from alignment_ros import plots, run_report, state_layout
from alignment_ros.bag import BagWriter
from alignment_ros.plots.consistency import update_dof

NS = 1_000_000_000
ARCMIN = math.pi / 180.0 / 60.0
PNG_MAGIC = b'\x89PNG\r\n\x1a\n'
OLD = ('phi_E', 'phi_N', 'phi_U', 'dV_E', 'dV_N', 'dV_U', 'eps_x', 'eps_y', 'eps_z')
# the unit-labelled layout (issue 13: rows t_s|estimate|sigma|mu_sigma|correction, names with their unit)
NEW = ('attitude_error_E_rad', 'attitude_error_N_rad', 'attitude_error_U_rad', 'gyro_bias_x_radps',
       'gyro_bias_y_radps', 'gyro_bias_z_radps', 'master_delay_s')
NEW_ROWS = ('t_s', 'estimate', 'sigma', 'mu_sigma', 'correction')


def _state_msg(t_s: float, labels, rows: dict[str, list[float]]) -> Float64MultiArray:
    m = Float64MultiArray(data=[float(v) for r in rows.values() for v in r])
    m.layout.dim = [MultiArrayDimension(label='|'.join(rows), size=len(rows), stride=len(rows) * len(labels)),
                    MultiArrayDimension(label=','.join(labels), size=len(labels), stride=len(labels))]
    return m


def test_state_layout_today_and_unit_labelled():
    n = len(OLD)
    old = state_layout.from_msg(_state_msg(2.0, OLD, {'t_s': [2.0] * n, 'value': [0.0] * n, 'sigma': [1e-3] * n,
                                                      'mu_sigma': [1e-4, 2e-4, 3e-4] + [0.0] * (n - 3)}))
    assert old.t_s == 2.0 and old.misalignment_sigma().tolist() == [1e-4, 2e-4, 3e-4]
    k = len(NEW)
    new = state_layout.from_msg(_state_msg(3.0, NEW, {'t_s': [3.0] * k, 'estimate': [0.0] * k,
                                                      'sigma': [1e-3] * k, 'mu_sigma': [5e-4, 6e-4, 7e-4] + [0.0] * 4,
                                                      'correction': [0.0] * k}))
    assert new.t_s == 3.0 and new.misalignment_sigma().tolist() == [5e-4, 6e-4, 7e-4]
    assert [state_layout.group_of(n) for n in NEW] == ['attitude_error'] * 3 + ['gyro_bias'] * 3 + ['master_delay']
    with pytest.raises(ValueError, match='values for'):
        state_layout.parse([('t_s|value', 2), ('a,b', 2)], [1.0, 2.0, 3.0])


@pytest.mark.parametrize('label, unit, factor', [
    ('phi_E', 'arcmin', 180 * 60 / math.pi), ('eps_x', 'deg/h', 180 / math.pi * 3600),
    ('nabla_y', 'mg', 1000 / 9.80665), ('dV_N', 'm/s', 1.0), ('gyro_bias_x_radps', 'deg/h', 180 / math.pi * 3600),
    ('accel_bias_x_mps2', 'mg', 1000 / 9.80665), ('lever_arm_error_x_m', 'm', 1.0), ('master_delay_s', 'ms', 1000.0),
    ('attitude_error_E_rad', 'arcmin', 180 * 60 / math.pi), ('doppler_scale_factor_error_ratio', 'ppm', 1e6),
    ('mystery', '', 1.0)])
def test_display_units_from_names(label, unit, factor):
    got_unit, got = state_layout.display_unit(label)
    assert got_unit == unit and got == pytest.approx(factor, rel=1e-12)


@pytest.mark.parametrize('dof', [1, 2, 3, 6])
def test_update_dof_from_the_monitors_bound(dof):
    window, warn_p = 100, 1e-4
    m = NisMonitor(window, warn_p, 3)
    bound = float(f'{m.bound(window * dof) / (window * dof):.4g}')    # as /diagnostics prints it
    assert update_dof(bound, window, warn_p) == dof
    assert update_dof(float('nan'), window, warn_p) is None


def _vec(t_ns: int, v) -> bytes:
    m = Vector3Stamped()
    m.header.stamp.sec, m.header.stamp.nanosec = t_ns // NS, t_ns % NS
    m.vector.x, m.vector.y, m.vector.z = (float(x) for x in v)
    return serialize_message(m)


def _diag(t_ns: int, level: int, values: dict) -> bytes:
    d = DiagnosticArray()
    d.header.stamp.sec, d.header.stamp.nanosec = t_ns // NS, t_ns % NS
    st = DiagnosticStatus(level=bytes([level]), name='alignment_filter', message='aligning')
    st.values = [KeyValue(key=k, value=str(v)) for k, v in values.items()]
    d.status = [st]
    return serialize_message(d)


def write_bag(path: Path, labels, truth: bool) -> None:
    """1..3 s at 10 Hz: estimate = truth + (1, -2, 0.5) arcmin, sigma shrinking from 10 to 1 arcmin."""
    mu = np.array([15.0, -10.0, -30.0]) * ARCMIN
    with BagWriter(path) as w:
        w.add_topic('/alignment/misalignment', 'geometry_msgs/msg/Vector3Stamped')
        w.add_topic('/alignment/state', 'std_msgs/msg/Float64MultiArray')
        w.add_topic('/diagnostics', 'diagnostic_msgs/msg/DiagnosticArray')
        if truth:
            w.add_topic('/truth/misalignment', 'geometry_msgs/msg/Vector3Stamped')
        n = len(labels)
        for k in range(21):
            t = NS + k * NS // 10
            sig = (10.0 - 9.0 * k / 20) * ARCMIN
            w.write('/alignment/misalignment', _vec(t, mu + np.array([1.0, -2.0, 0.5]) * ARCMIN), t)
            if 'phi_E' in labels:
                rows = {'t_s': [t / NS] * n, 'value': [0.0] * n, 'sigma': [sig] * n,
                        'mu_sigma': [sig] * 3 + [0.0] * (n - 3)}
            else:
                rows = dict(zip(NEW_ROWS, ([t / NS] * n, [0.0] * n, [sig] * n, [sig] * 3 + [0.0] * (n - 3),
                                           [0.0] * n)))
            w.write('/alignment/state', serialize_message(_state_msg(t / NS, labels, rows)), t)
            if truth:
                w.write('/truth/misalignment', _vec(t, mu), t)
            if k % 5 == 0:
                w.write('/diagnostics', _diag(t, 1 if k == 5 else 0, {
                    'nis': 2.5, 'nis_window_mean': 1.1, 'nis_window_bound': 1.329, 'nis_windows': k // 5,
                    'nis_windows_failed': 0, 'rejected_range': 2 if k else 0, 'imu_gaps': 1, 'healthy': 'true'}), t)


@pytest.mark.parametrize('labels, truth', [(OLD, True), (NEW, False)])
def test_figures_and_report_from_a_bag(tmp_path, labels, truth):
    bag = tmp_path / 'bag'
    write_bag(bag, labels, truth)
    report = run_report.build([bag], tmp_path / 'plots', None, 'test', report_dir=tmp_path)
    drawn = sorted(p.name for p in (tmp_path / 'plots').glob('*.png'))
    assert drawn == ['consistency.png', 'misalignment.png', 'states.png']     # no ship, LDV, air data
    for p in drawn:
        data = (tmp_path / 'plots' / p).read_bytes()
        assert data.startswith(PNG_MAGIC) and len(data) > 10_000
    text = report.read_text()
    assert '| x (roll) | 16.000 | 1.000 |' in text           # the last estimate and its 1 sigma, arcmin
    assert '| z (yaw) | -29.500 | 1.000 |' in text
    assert 'rejections by reason: range 2' in text and 'imu_gaps 1' in text
    assert '- WARN from t = 1.50 s to 1.50 s: "aligning"' in text
    assert '![Misalignment estimate](plots/misalignment.png)' in text


def test_nothing_to_draw(tmp_path):
    bag = tmp_path / 'bag'
    with BagWriter(bag) as w:
        w.add_topic('/ship/fix', 'sensor_msgs/msg/NavSatFix')
    assert plots.draw_all([bag], tmp_path / 'plots') == []


def test_report_of_a_truth_free_summary_with_the_whole_estimate():
    """summary.json without truth (``truth: false``: estimate and 1 sigma only), with the whole
    estimate and the innovation whiteness (issue 13's keys): the report shows each."""
    s = {'truth': False, 'misalignment_truth_rad': None, 'misalignment_estimate_rad': [ARCMIN, -2 * ARCMIN, 0.0],
         'misalignment_sigma_rad': [0.1 * ARCMIN] * 3, 'estimate_stamp_s': 12.5, 'sim_time_s': 12.0,
         'planned_sim_time_s': 12.0, 'wall_time_s': 6.0, 'real_time_factor': 2.0, 'lost_total': 0, 'complete': True,
         'state_estimate': {'t_s': 12.5, 'labels': ['gyro_bias_x_radps', 'master_delay_s'],
                            'estimate': [math.radians(0.5) / 3600, 0.02], 'sigma': [math.radians(0.1) / 3600, 1e-4]},
         'innovation_whiteness': {'result': 'pass', 'p': 0.42, 'r1_max': 0.05, 'band': 0.2, 'windows': 4,
                                  'windows_failed': 0, 'relative_velocity': 'ldv'}}
    text = run_report.markdown('t', s, plots.series.RunSeries(), [], Path('.'))
    assert 'No truth in the input' in text and '| x (roll) | 1.000 | 0.100 |' in text
    assert '| y (pitch) | -2.000 | 0.100 |' in text
    assert '| gyro_bias_x_radps | 0.5 | 0.1 | deg/h |' in text and '| master_delay_s | 20 | 0.1 | ms |' in text
    assert 'innovation whiteness: pass (last window: Ljung-Box p 0.42' in text


def test_a_held_estimate_is_told_from_a_fresh_one():
    """Estimates repeated bit for bit (no match since) are held; a changing one is fresh."""
    from alignment_ros.plots.alignment import held
    mu = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 0, 0], [2, 0, 0], [3, 0, 0]])
    np.testing.assert_array_equal(held(mu), [False, False, False, True, True, False])


def _with_motion(path: Path) -> Path:
    """write_bag's topics and 2 s of /ship/odom (rolling 1 degree) and /ldv/twist at 10 Hz."""
    from geometry_msgs.msg import TwistWithCovarianceStamped
    from nav_msgs.msg import Odometry
    write_bag(path, OLD, True)
    more = path.parent / 'motion'
    with BagWriter(more) as w:
        w.add_topic('/ship/odom', 'nav_msgs/msg/Odometry')
        w.add_topic('/ldv/twist', 'geometry_msgs/msg/TwistWithCovarianceStamped')
        for k in range(21):
            t = NS + k * NS // 10
            o = Odometry()
            o.header.stamp.sec, o.header.stamp.nanosec = t // NS, t % NS
            roll = math.radians(1.0) * math.sin(k / 3)
            o.pose.pose.orientation.x, o.pose.pose.orientation.w = math.sin(roll / 2), math.cos(roll / 2)
            w.write('/ship/odom', serialize_message(o), t)
            v = TwistWithCovarianceStamped()
            v.header.stamp = o.header.stamp
            v.twist.twist.linear.x = 0.01 * k
            v.twist.covariance[0] = v.twist.covariance[7] = v.twist.covariance[14] = 1e-4
            w.write('/ldv/twist', serialize_message(v), t)
    return more


def test_the_motion_figure_drawn_meanwhile_is_the_one_drawn_in_turn(tmp_path):
    """read_and_draw forks the ship-motion figure off: the same files, bit for bit, and the same
    list as reading and drawing every figure in one process."""
    bag = tmp_path / 'bag'
    more = _with_motion(bag)
    in_turn = plots.draw_all([bag, more], tmp_path / 'in_turn')
    series, meanwhile = plots.read_and_draw([bag, more], tmp_path / 'meanwhile')
    assert [t for t, _ in meanwhile] == [t for t, _ in in_turn] == [
        'Misalignment estimate', 'Estimated states', 'Innovation consistency (NIS)',
        "Ship motion and the aircraft's deck velocity"]
    for (_, a), (_, b) in zip(in_turn, meanwhile):
        assert a.name == b.name and a.read_bytes() == b.read_bytes()
    assert series.misalignment is not None and series.ship is None      # the child's topics stay there


def test_an_error_in_either_process_reaches_the_caller(tmp_path, monkeypatch):
    """The motion figure's process fails on a /ship/odom that is not CDR: its error is raised;
    this process's own error comes first, and the other process is not left behind."""
    bag = tmp_path / 'bag'
    write_bag(bag, OLD, True)
    bad = tmp_path / 'bad'
    with BagWriter(bad) as w:
        w.add_topic('/ship/odom', 'nav_msgs/msg/Odometry')
        w.write('/ship/odom', b'\x00\x01\x00\x00not an odometry', NS)
    with pytest.raises(RuntimeError, match='the motion figure: '):
        plots.read_and_draw([bag, bad], tmp_path / 'a')
    assert sorted(p.name for p in (tmp_path / 'a').glob('*.png')) == ['consistency.png', 'misalignment.png',
                                                                      'states.png']

    def broken(*_):
        raise ValueError('broken figure')
    monkeypatch.setattr(plots, 'FIGURES', tuple((n, t, broken if n == 'states' else f) for n, t, f in plots.FIGURES))
    more = _with_motion(tmp_path / 'c' / 'bag')
    with pytest.raises(ValueError, match='broken figure'):
        plots.read_and_draw([tmp_path / 'c' / 'bag', more], tmp_path / 'b')
