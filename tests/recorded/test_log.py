"""Reading logs: the canonical layout, a map, .mat files, the time base, and each error a bad
file gives (a missing column named, time not increasing with its lines, NaN rows skipped and
counted, a unit that the magnitudes contradict)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.io import savemat

from alignment_core.recorded import recording
from alignment_core.recorded.column_units import LogError
from alignment_core.units import DEG, G0

IMU_HEAD = 't_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps'
MASTER_HEAD = 't_s,qw,qx,qy,qz,v_e_mps,v_n_mps,v_u_mps,lat_deg,lon_deg,h_m'
DT = 0.01


def imu_rows(n: int = 20, t0: float = 1.0, rate=(0.001, 0.0, 0.0), g: float = G0) -> list[str]:
    return [f'{t0 + (k + 1) * DT!r},{rate[0] * DT!r},{rate[1] * DT!r},{rate[2] * DT!r},0.0,0.0,{g * DT!r}'
            for k in range(n)]


def master_rows(n: int = 21, t0: float = 1.0) -> list[str]:
    return [f'{t0 + k * DT!r},1.0,0.0,0.0,0.0,1.0,2.0,0.0,40.0,116.0,5.0' for k in range(n)]


def write(path, head: str, rows: list[str]):
    path.write_text(head + '\n' + '\n'.join(rows) + '\n')
    return path


@pytest.fixture
def logs(tmp_path):
    return (write(tmp_path / 'imu.csv', IMU_HEAD, imu_rows()),
            write(tmp_path / 'master.csv', MASTER_HEAD, master_rows()))


def test_the_canonical_layout(logs):
    log = recording.load(*logs)
    assert log.time_offset_ns == 0
    assert log.imu.t_ns[0] == 1_010_000_000 and log.imu.gyro[:, 0] == pytest.approx(0.001)
    assert log.imu.accel[:, 2] == pytest.approx(G0)
    assert log.master.v_b[0] == pytest.approx([1.0, 2.0, 0.0])        # attitude = identity
    assert log.master.lat[0] == pytest.approx(40 * DEG) and log.master.rate_derived
    assert log.master.w_b == pytest.approx(np.zeros((21, 3)))
    assert [r.skipped for r in log.reports()] == [0, 0]


def test_times_from_zero_start_at_one_second_and_absolute_times_are_kept(tmp_path):
    imu = write(tmp_path / 'i.csv', IMU_HEAD, imu_rows(t0=0.0))
    master = write(tmp_path / 'm.csv', MASTER_HEAD, master_rows(t0=0.0))
    log = recording.load(imu, master)
    assert log.time_offset_ns == 1_000_000_000 and log.master.t_ns[0] == 1_000_000_000
    imu = write(tmp_path / 'i.csv', IMU_HEAD, imu_rows(t0=345600.0))
    master = write(tmp_path / 'm.csv', MASTER_HEAD, master_rows(t0=345600.0))
    log = recording.load(imu, master)
    assert log.time_offset_ns == 0 and log.imu.t_ns[0] == 345600_010_000_000     # exact decimal text
    log = recording.load(imu, master, layout_map={'time_offset_s': -345599.0})
    assert log.master.t_ns[0] == 1_000_000_000


def test_a_missing_column_is_named(logs, tmp_path):
    bad = write(tmp_path / 'm.csv', MASTER_HEAD.replace('v_n_mps', 'vn'), master_rows())
    with pytest.raises(LogError, match=r"master.velocity: no column named 'v_n_mps' \(columns: .*vn"):
        recording.load(logs[0], bad)


def test_time_not_increasing_names_its_lines(logs, tmp_path):
    rows = imu_rows()
    rows[5], rows[6] = rows[6], rows[5]
    bad = write(tmp_path / 'i.csv', IMU_HEAD, rows)
    want = r'imu: time not increasing at 1 row\(s\): line 8 \(t = 1.06 s after 1.07 s at 7\)'
    with pytest.raises(LogError, match=want):
        recording.load(bad, logs[1])
    rows = imu_rows()
    rows[3] = rows[2]
    with pytest.raises(LogError, match='line 5'):
        recording.load(write(tmp_path / 'i.csv', IMU_HEAD, rows), logs[1])


def test_nan_rows_are_skipped_and_counted(logs, tmp_path):
    rows = imu_rows()
    rows[3] = rows[3].replace(',0.0,0.0,', ',nan,0.0,', 1)
    rows[9] = ','.join(rows[9].split(',')[:3] + [''] + rows[9].split(',')[4:])
    log = recording.load(write(tmp_path / 'i.csv', IMU_HEAD, rows), logs[1])
    rep = log.imu.report
    assert (rep.rows, rep.skipped, rep.skipped_lines) == (18, 2, [5, 11])
    assert '2 skipped (NaN or empty cells: lines/rows 5, 11)' in rep.lines()[0]


def test_units_the_magnitudes_contradict_are_warned(logs, tmp_path):
    # deg/s values (30 deg/s) in a column declared rad/s; g values in a column declared m/s^2
    path = write(tmp_path / 'i.csv', 't,gx,gy,gz,ax,ay,az',
                 [f'{1 + k * DT!r},30.0,0.0,0.0,0.0,0.0,1.0' for k in range(1, 21)])
    lay = {'imu': {'kind': 'rates', 'time': 't', 'gyro': ['gx', 'gy', 'gz'], 'accel': ['ax', 'ay', 'az']}}
    w = recording.load(path, logs[1], layout_map=lay).imu.report.warnings
    assert any('deg/s given as rad/s' in x for x in w) and any('g given as m/s^2' in x for x in w)
    lay['imu'].update(gyro_unit='deg/s', accel_unit='g')
    log = recording.load(path, logs[1], layout_map=lay)
    assert log.imu.report.warnings == [] and log.imu.accel[0, 2] == pytest.approx(G0)
    # Euler degrees declared as radians
    m = write(tmp_path / 'e.csv', 't,r,p,y,vn,ve,vd,lat,lon,h',
              [f'{1 + k * DT!r},1.0,2.0,120.0,0,0,0,40,116,0' for k in range(21)])
    mlay = {'master': {'time': 't', 'attitude': 'ned_frd_321', 'euler': ['r', 'p', 'y'], 'nav_frame': 'NED',
                       'body_axes': 'FRD', 'velocity': ['vn', 've', 'vd'], 'position': ['lat', 'lon', 'h']}}
    assert 'are they degrees' in recording.load(logs[0], m, layout_map=mlay).master.report.warnings[0]


def test_other_bad_files(logs, tmp_path):
    with pytest.raises(LogError, match='header row of column names is required'):
        recording.load(write(tmp_path / 'i.csv', imu_rows()[0], imu_rows()[1:]), logs[1])
    with pytest.raises(LogError, match='line 3: 6 fields, expected 7'):
        recording.load(write(tmp_path / 'i.csv', IMU_HEAD, [imu_rows()[0], '1.1,0,0,0,0,0']), logs[1])
    with pytest.raises(LogError, match="line 4: 'x' is not a number"):
        rows = imu_rows()
        rows[2] = rows[2].replace(',0.0,', ',x,', 1)
        recording.load(write(tmp_path / 'i.csv', IMU_HEAD, rows), logs[1])
    with pytest.raises(LogError, match='unknown key.*gyros'):
        recording.load(*logs, layout_map={'imu': {'gyros': [0, 1, 2]}})
    with pytest.raises(LogError, match="unit 'g' is not a unit of rate"):
        recording.load(*logs, layout_map={'imu': {'kind': 'rates', 'gyro_unit': 'g'}})
    with pytest.raises(LogError, match='latitude beyond 90 deg'):
        recording.load(*logs, layout_map={'master': {'position_unit': 'rad'}})
    imu0 = write(tmp_path / 'i0.csv', IMU_HEAD, imu_rows(t0=345600.0))
    with pytest.raises(LogError, match='imu times 345600.01 .. 345600.2 s and master times 1 .. 1.2 s do not overlap'):
        recording.load(imu0, logs[1])
    with pytest.raises(LogError, match='no such file'):
        recording.load(tmp_path / 'none.csv', logs[1])


def test_mat_files_by_matrix_and_by_vectors(logs, tmp_path):
    t = 1.0 + DT * np.arange(1, 21)
    gyro = np.tile([0.1, 0.0, 0.0], (20, 1))       # deg/s
    accel = np.tile([0.0, 0.0, -1.0], (20, 1))     # g, FRD (down)
    savemat(tmp_path / 'imu.mat', {'IMU': np.column_stack([t, gyro, accel])})
    lay = {'imu': {'variable': 'IMU', 'kind': 'rates', 'body_axes': 'FRD', 'time': 0, 'gyro': [1, 2, 3],
                   'gyro_unit': 'deg/s', 'accel': [4, 5, 6], 'accel_unit': 'g'}}
    log = recording.load(tmp_path / 'imu.mat', logs[1], layout_map=lay)
    assert log.imu.gyro[0] == pytest.approx([0.1 * DEG, 0, 0]) and log.imu.accel[0] == pytest.approx([0, 0, G0])
    savemat(tmp_path / 'imu2.mat', {'t': t, 'wx': gyro[:, 0], 'wy': gyro[:, 1], 'wz': gyro[:, 2],
                                    'fx': accel[:, 0], 'fy': accel[:, 1], 'fz': accel[:, 2]})
    lay = {'imu': {'kind': 'rates', 'body_axes': 'FRD', 'time': 't', 'gyro': ['wx', 'wy', 'wz'],
                   'gyro_unit': 'deg/s', 'accel': ['fx', 'fy', 'fz'], 'accel_unit': 'g'}}
    assert recording.load(tmp_path / 'imu2.mat', logs[1], layout_map=lay).imu.accel[0] == pytest.approx([0, 0, G0])
    lay['imu']['gyro'] = ['wx', 'wy', 'omega_z']
    with pytest.raises(LogError, match="no column named 'omega_z'"):
        recording.load(tmp_path / 'imu2.mat', logs[1], layout_map=lay)


def test_ldv_rows_without_a_measurement(logs, tmp_path):
    ldv = write(tmp_path / 'l.csv', 't_s,v_x_mps,v_y_mps,v_z_mps,sigma_mps',
                ['1.0,0.1,0.0,0.0,0.01', '1.01,,,,-1', '1.02,nan,0,0,0.01', '1.03,0.2,0,0,0.01'])
    v = recording.load(*logs, ldv=ldv).ldv
    assert list(v.valid) == [True, False, True] and v.report.skipped == 1     # the NaN row with a sigma
    assert v.v[1] == pytest.approx([0, 0, 0]) and np.isnan(v.sigma[1])
    v = recording.load(*logs, ldv=ldv, layout_map={'ldv': {'sigma_mps': 0.02, 'sigma_unit': 'ft/s'}}).ldv
    assert v.sigma == pytest.approx([0.02, 0.02]) and v.report.skipped == 2     # sigma_mps: m/s whatever the unit
    v = recording.load(*logs, ldv=ldv, layout_map={'ldv': {'sigma': 1}}).ldv    # an integer: column 1
    assert v.sigma == pytest.approx([0.1, 0.2]) and list(v.valid) == [True, True]
    with pytest.raises(LogError, match=r'ldv.sigma: 0.02: a column .* is `sigma_mps: 0.02`'):
        recording.load(*logs, ldv=ldv, layout_map={'ldv': {'sigma': 0.02}})
    with pytest.raises(LogError, match='sigma .a column. and sigma_mps .one for every row. both given'):
        recording.load(*logs, ldv=ldv, layout_map={'ldv': {'sigma': 'sigma_mps', 'sigma_mps': 0.02}})


def test_the_maps_of_the_docs_are_valid():
    import re
    from pathlib import Path

    import yaml

    from alignment_core.recorded.layout import read_map
    text = (Path(__file__).resolve().parents[2] / 'docs/own-data.md').read_text()
    blocks = re.findall(r'```yaml\n(.*?)```', text, re.S)
    assert len(blocks) == 3
    for b in blocks:
        read_map(yaml.safe_load(b))


def test_a_skipped_increment_row_leaves_a_gap_and_the_next_row_its_own_interval(logs, tmp_path):
    # every row: 0.001 rad/s and g over its own 10 ms; row 4 (line 5) NaN: rows 3 and 5 kept,
    # 20 ms apart, and row 5's increment is still over its own 10 ms (rate 0.001, accel g, not half)
    rows = imu_rows()
    rows[3] = rows[3].replace(',0.0,0.0,', ',nan,0.0,', 1)
    log = recording.load(write(tmp_path / 'i.csv', IMU_HEAD, rows), logs[1])
    assert log.imu.t_ns[3] - log.imu.t_ns[2] == 20_000_000
    assert log.imu.gyro[:, 0] == pytest.approx(np.full(19, 0.001), rel=1e-12)
    assert log.imu.accel[:, 2] == pytest.approx(np.full(19, G0), rel=1e-12)
    # a row whose time is missing: the next row's interval is unknown, the median spacing (10 ms)
    rows = imu_rows()
    rows[3] = ',' + rows[3].split(',', 1)[1]
    log = recording.load(write(tmp_path / 'i.csv', IMU_HEAD, rows), logs[1])
    assert log.imu.accel[:, 2] == pytest.approx(np.full(19, G0), rel=1e-12)
