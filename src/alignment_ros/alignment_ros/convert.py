"""Message <-> alignment_core record conversions (field by field, float64, no equations)."""
from __future__ import annotations

import math
from typing import SupportsFloat

import numpy as np
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import (
    AccelStamped,
    PoseWithCovarianceStamped,
    TwistWithCovarianceStamped,
    Vector3Stamped,
)
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Imu, NavSatFix, NavSatStatus
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from alignment_core.estimation.outputs import Estimate
from alignment_core.samples import AircraftTruth, DopplerSample, ImuSample, LdvSample, MasterSample, ShipSample
from alignment_core.sensors import ldv_wire

from . import topics


def stamp(t_ns: int) -> Time:
    return Time(sec=t_ns // 1_000_000_000, nanosec=t_ns % 1_000_000_000)


def to_ns(t: Time) -> int:
    return t.sec * 1_000_000_000 + t.nanosec


def _v3(msg, v) -> None:
    msg.x, msg.y, msg.z = float(v[0]), float(v[1]), float(v[2])


def _a3(msg) -> np.ndarray:
    return np.array([msg.x, msg.y, msg.z])


def _quat(msg, q) -> None:
    msg.x, msg.y, msg.z, msg.w = (float(q[0]), float(q[1]), float(q[2]), float(q[3]))


def _aq(msg) -> np.ndarray:
    return np.array([msg.x, msg.y, msg.z, msg.w])


def odometry(t_ns: int, frame: str, child: str, p_w, q_nb, v_b, w_b) -> Odometry:
    m = Odometry()
    m.header.stamp = stamp(t_ns)
    m.header.frame_id = frame
    m.child_frame_id = child
    _v3(m.pose.pose.position, p_w)
    _quat(m.pose.pose.orientation, q_nb)
    _v3(m.twist.twist.linear, v_b)
    _v3(m.twist.twist.angular, w_b)
    return m


def ship_to_msgs(s: ShipSample) -> tuple[Odometry, AccelStamped]:
    odom = odometry(s.t_ns, topics.FRAME_WORLD, topics.FRAME_SHIP, s.p_w, s.q_nb, s.v_b, s.w_b)
    acc = AccelStamped()
    acc.header.stamp = stamp(s.t_ns)
    acc.header.frame_id = topics.FRAME_SHIP
    _v3(acc.accel.linear, s.a_b)
    _v3(acc.accel.angular, s.wdot_b)
    return odom, acc


def msgs_to_ship(odom: Odometry, acc: AccelStamped | None = None) -> ShipSample:
    """Ship sample from /ship/odom and /ship/accel (accelerations zero if `acc` is None)."""
    zero = np.zeros(3)
    return ShipSample(t_ns=to_ns(odom.header.stamp), p_w=_a3(odom.pose.pose.position),
                      q_nb=_aq(odom.pose.pose.orientation), v_b=_a3(odom.twist.twist.linear),
                      w_b=_a3(odom.twist.twist.angular),
                      a_b=zero if acc is None else _a3(acc.accel.linear),
                      wdot_b=zero if acc is None else _a3(acc.accel.angular))


def navsatfix(t_ns: int, frame: str, lat_rad: SupportsFloat, lon_rad: SupportsFloat, h: SupportsFloat) -> NavSatFix:
    """A fix at geodetic lat, lon (rad) and h (m): floats, or numpy scalars (0-d arrays of to_geodetic)."""
    m = NavSatFix()
    m.header.stamp = stamp(t_ns)
    m.header.frame_id = frame
    m.status.status = NavSatStatus.STATUS_FIX
    m.latitude = math.degrees(lat_rad)
    m.longitude = math.degrees(lon_rad)
    m.altitude = float(h)
    m.position_covariance_type = NavSatFix.COVARIANCE_TYPE_UNKNOWN
    return m


def master_to_msg(m: MasterSample) -> Odometry:
    return odometry(m.t_ns, topics.FRAME_WORLD, topics.FRAME_SHIP, m.p_w, m.q_nb, m.v_b, m.w_b)


def msg_to_master(o: Odometry) -> MasterSample:
    return MasterSample(t_ns=to_ns(o.header.stamp), p_w=_a3(o.pose.pose.position),
                        q_nb=_aq(o.pose.pose.orientation), v_b=_a3(o.twist.twist.linear),
                        w_b=_a3(o.twist.twist.angular))


def imu_to_msg(s: ImuSample, gyro_var: float, accel_var: float) -> Imu:
    m = Imu()
    m.header.stamp = stamp(s.t_ns)
    m.header.frame_id = topics.FRAME_AIRCRAFT
    m.orientation_covariance[0] = -1.0           # REP-145: orientation not provided
    _v3(m.angular_velocity, s.gyro)
    _v3(m.linear_acceleration, s.accel)
    for i in (0, 4, 8):
        m.angular_velocity_covariance[i] = gyro_var
        m.linear_acceleration_covariance[i] = accel_var
    return m


def msg_to_imu(m: Imu) -> ImuSample:
    return ImuSample(t_ns=to_ns(m.header.stamp), gyro=_a3(m.angular_velocity),
                     accel=_a3(m.linear_acceleration))


def ldv_to_msg(s: LdvSample) -> TwistWithCovarianceStamped:
    """/ldv/twist (alignment_core.sensors.ldv_wire: the velocity, and a linear covariance that
    says what was measured; covariance[0] = -1: no measurement)."""
    m = TwistWithCovarianceStamped()
    m.header.stamp = stamp(s.t_ns)
    m.header.frame_id = topics.FRAME_SHIP
    linear, cov = ldv_wire.encode(s)
    if s.valid:
        _v3(m.twist.twist.linear, linear)
    for i in range(3):
        for j in range(3):
            m.twist.covariance[6 * i + j] = float(cov[i, j])
    return m


def msg_to_ldv(m: TwistWithCovarianceStamped) -> LdvSample:
    """The LdvSample of /ldv/twist (`ldv_to_msg`; a rank-1 linear covariance is a beam)."""
    cov = np.array(m.twist.covariance, dtype=float).reshape(6, 6)[:3, :3]
    return ldv_wire.decode(to_ns(m.header.stamp), _a3(m.twist.twist.linear), cov)


def doppler_to_msg(s: DopplerSample) -> TwistWithCovarianceStamped:
    """/doppler/twist: ground velocity in aircraft body axes; covariance[0] = -1: no measurement."""
    m = TwistWithCovarianceStamped()
    m.header.stamp = stamp(s.t_ns)
    m.header.frame_id = topics.FRAME_AIRCRAFT
    if s.valid:
        _v3(m.twist.twist.linear, s.v_b)
        for i in (0, 7, 14):
            m.twist.covariance[i] = s.sigma**2
        m.twist.covariance[21] = -1.0             # angular part not measured
    else:
        m.twist.covariance[0] = -1.0
    return m


def msg_to_doppler(m: TwistWithCovarianceStamped) -> DopplerSample:
    c0 = m.twist.covariance[0]
    valid = c0 >= 0.0
    return DopplerSample(t_ns=to_ns(m.header.stamp), v_b=_a3(m.twist.twist.linear),
                         sigma=math.sqrt(c0) if valid else math.nan, valid=bool(valid))


def imu_bias_to_msg(t_ns: int, gyro_bias, accel_bias) -> Imu:
    """/truth/imu_bias: the slave IMU's additive gyro (rad/s) and accelerometer (m/s^2) bias
    over the interval ending at t_ns, aircraft axes, in an Imu message (no orientation)."""
    m = Imu()
    m.header.stamp = stamp(t_ns)
    m.header.frame_id = topics.FRAME_AIRCRAFT
    m.orientation_covariance[0] = -1.0
    _v3(m.angular_velocity, gyro_bias)
    _v3(m.linear_acceleration, accel_bias)
    return m


def vector_stamped(t_ns: int, frame: str, v) -> Vector3Stamped:
    m = Vector3Stamped()
    m.header.stamp = stamp(t_ns)
    m.header.frame_id = frame
    _v3(m.vector, v)
    return m


def truth_to_msgs(a: AircraftTruth) -> tuple[Odometry, Vector3Stamped | None]:
    odom = odometry(a.t_ns, topics.FRAME_WORLD, topics.FRAME_AIRCRAFT, a.p_w, a.q_nb, a.v_b, a.w_b)
    if not a.on_deck:
        return odom, None
    mis = Vector3Stamped()
    mis.header.stamp = stamp(a.t_ns)
    mis.header.frame_id = topics.FRAME_AIRCRAFT
    _v3(mis.vector, a.misalignment)
    return odom, mis


def msg_to_truth(o: Odometry, on_deck: bool = True, misalignment=None) -> AircraftTruth:
    return AircraftTruth(t_ns=to_ns(o.header.stamp), p_w=_a3(o.pose.pose.position),
                         q_nb=_aq(o.pose.pose.orientation), v_b=_a3(o.twist.twist.linear),
                         w_b=_a3(o.twist.twist.angular),
                         misalignment=np.zeros(3) if misalignment is None else misalignment,
                         on_deck=on_deck)


def estimate_to_msgs(e: Estimate, labels: tuple[str, ...], p_w
                     ) -> tuple[Vector3Stamped, PoseWithCovarianceStamped, Float64MultiArray]:
    mis = Vector3Stamped()
    mis.header.stamp = stamp(e.t_ns)
    mis.header.frame_id = topics.FRAME_AIRCRAFT
    _v3(mis.vector, e.misalignment)
    att = PoseWithCovarianceStamped()
    att.header.stamp = stamp(e.navigation_ns)      # the slave solution's own time (its newest IMU sample)
    att.header.frame_id = topics.FRAME_WORLD
    _v3(att.pose.pose.position, p_w)
    _quat(att.pose.pose.orientation, e.q_nb)
    cov = np.zeros((6, 6))
    cov[3:, 3:] = e.attitude_cov
    cov[0, 0] = cov[1, 1] = cov[2, 2] = -1.0      # position is not estimated
    att.pose.covariance = [float(x) for x in cov.ravel()]
    return mis, att, state_msg(e, labels)


STATE_ROWS = 't_s|estimate|sigma|mu_sigma|correction'


def state_msg(e: Estimate, labels: tuple[str, ...]) -> Float64MultiArray:
    """/alignment/state: 5 x n rows over the labels (the states' published names with their SI
    unit, state_estimate.py): the stamp (s), the accumulated estimate, its 1-sigma, the
    misalignment's 1-sigma (first 3), the last correction (the a-posteriori error state before
    feedback)."""
    if len(e.x) != len(labels):
        raise ValueError(f'{len(e.x)} states but {len(labels)} labels')
    n = len(labels)
    st = Float64MultiArray()
    st.layout.dim = [MultiArrayDimension(label=STATE_ROWS, size=5, stride=5 * n),
                     MultiArrayDimension(label=','.join(labels), size=n, stride=n)]
    t = np.full(n, e.t_ns * 1e-9)
    mu_sig = np.zeros(n)
    mu_sig[:3] = e.misalignment_sigma
    est = e.state if e.state is not None else np.full(n, np.nan)
    st.data = [float(x) for x in np.concatenate([t, est, e.sigma, mu_sig, e.x])]
    return st


def frame_mismatch(m, frame: str, child: str | None = None) -> str:
    """'' if the message's header.frame_id (and child_frame_id, when given) are the expected ones,
    else what was found."""
    if m.header.frame_id != frame:
        return f"frame_id '{m.header.frame_id}', expected '{frame}'"
    if child is not None and m.child_frame_id != child:
        return f"child_frame_id '{m.child_frame_id}', expected '{child}'"
    return ''


def estimate_to_odometry(e: Estimate) -> Odometry | None:
    """/alignment/odom: the slave INS solution after the filter's corrections, stamped with its own
    time (REP-105: pose in 'world', twist in the child frame 'aircraft'); covariances as the estimate gives them (a -1
    diagonal: not estimated). None if the estimate carries no odometry."""
    if e.p_w is None or e.v_b is None or e.w_b is None or e.pose_cov is None or e.twist_cov is None:
        return None
    m = odometry(e.navigation_ns, topics.FRAME_WORLD, topics.FRAME_AIRCRAFT, e.p_w, e.q_nb, e.v_b, e.w_b)
    m.pose.covariance = [float(x) for x in np.asarray(e.pose_cov, dtype=float).ravel()]
    m.twist.covariance = [float(x) for x in np.asarray(e.twist_cov, dtype=float).ravel()]
    return m


def diagnostics(t_ns: int, name: str, level: bytes, message: str, values: dict) -> DiagnosticArray:
    d = DiagnosticArray()
    d.header.stamp = stamp(t_ns)
    s = DiagnosticStatus(level=level, name=name, message=message, hardware_id=name)
    s.values = [KeyValue(key=str(k), value=str(v)) for k, v in values.items()]
    d.status = [s]
    return d


def vec_msg_to_array(m: Vector3Stamped) -> tuple[int, np.ndarray]:
    return to_ns(m.header.stamp), _a3(m.vector)
