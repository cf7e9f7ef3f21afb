"""Message <-> alignment_core conversions of the air-data nodes: FADS port pressures, air-data
truth, the reference INS's odometry, INS odometry -> the estimators' InsSample, and the
air-data estimate. Field by field, float64; the only geometry is the frame each message states
(pose in the world tangent plane, attitude body FLU -> local ENU, twist in body axes, REP-105).

Covariances: a 6 x 6 block whose diagonal is -1 is not provided (as /alignment/attitude's
position and /alignment/odom's unknown axes); read back, such axes contribute nothing (0)."""
from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from geometry_msgs.msg import TwistWithCovarianceStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import FluidPressure
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from alignment_core.estimation.air_data.inputs import InsSample
from alignment_core.estimation.air_data.outputs import AirDataEstimate
from alignment_core.geometry.earth import TangentPlane
from alignment_core.geometry.rotations import quat_to_dcm
from alignment_core.sensors.reference_ins import ReferenceInsSample

from . import topics
from .air_data_topics import FADS_PORT_FRAMES
from .convert import odometry, stamp, to_ns, vector_stamped

if TYPE_CHECKING:     # a type only: the sensor's module loads the atmosphere, which a node publishing none need not
    from alignment_core.sensors.fads import FadsFrame

UNKNOWN = -1.0                  # a covariance diagonal of -1: not provided
VALUE_SIGMA = 'value|sigma'     # /air_data/state's first dimension: a row of values, a row of sigmas
VALUE = 'value'                 # /truth/air_data/state's: one row of values


# ----- FADS ports --------------------------------------------------------------------------

def port_to_msg(t_ns: int, port: int, pressure_pa: float, variance_pa2: float) -> FluidPressure:
    """/fads/port_k: absolute pressure (Pa) and its nominal variance (Pa^2), frame fads_port_k."""
    m = FluidPressure()
    m.header.stamp = stamp(t_ns)
    m.header.frame_id = FADS_PORT_FRAMES[port]
    m.fluid_pressure = float(pressure_pa)
    m.variance = float(variance_pa2)
    return m


def msg_to_port(m: FluidPressure) -> tuple[int, int, float, float]:
    """(t_ns, port (-1 if the frame_id is not a fads_port_k), pressure Pa, variance Pa^2)."""
    port = FADS_PORT_FRAMES.index(m.header.frame_id) if m.header.frame_id in FADS_PORT_FRAMES else -1
    return to_ns(m.header.stamp), port, float(m.fluid_pressure), float(m.variance)


def frame_to_msgs(f: FadsFrame) -> list[FluidPressure]:
    """One FADS frame -> the messages of /fads/port_0 .. /fads/port_(n-1), in port order."""
    return [port_to_msg(f.t_ns, k, f.pressures_pa[k], f.variance_pa2[k]) for k in range(len(f.pressures_pa))]


# ----- labelled arrays ---------------------------------------------------------------------

def labelled_array(rows: str, labels: tuple[str, ...], data: np.ndarray) -> Float64MultiArray:
    """Float64MultiArray of data (R, L): dim 0 labelled `rows` ('a|b': R = 2 rows named a, b),
    dim 1 the comma-separated labels (as /alignment/state)."""
    data = np.asarray(data, dtype=float).reshape(len(rows.split('|')), len(labels))
    m = Float64MultiArray()
    m.layout.dim = [MultiArrayDimension(label=rows, size=data.shape[0], stride=data.size),
                    MultiArrayDimension(label=','.join(labels), size=len(labels), stride=len(labels))]
    m.data = [float(x) for x in data.ravel()]
    return m


def msg_to_labelled(m: Float64MultiArray) -> tuple[tuple[str, ...], tuple[str, ...], np.ndarray]:
    """(row names, labels, data (R, L)) of a labelled_array message."""
    rows = tuple(m.layout.dim[0].label.split('|'))
    labels = tuple(m.layout.dim[1].label.split(','))
    return rows, labels, np.asarray(m.data, dtype=float).reshape(len(rows), len(labels))


def air_truth_to_msgs(f: FadsFrame) -> tuple[Float64MultiArray, Vector3Stamped]:
    """/truth/air_data/state (AirDataTruth.labels(), one row of values) and /truth/wind (ENU,
    the air mass's velocity over the ground, frame world) of a frame."""
    st = labelled_array(VALUE, f.truth.labels(), f.truth.vector())
    return st, vector_stamped(f.t_ns, topics.FRAME_WORLD, f.truth.wind_enu_mps)


# ----- INS odometry ------------------------------------------------------------------------

def _known(c: np.ndarray) -> np.ndarray:
    """A covariance block with its not-provided axes (negative diagonal) zeroed."""
    c = np.array(c, dtype=float)
    bad = np.diagonal(c) < 0.0
    c[bad, :] = 0.0
    c[:, bad] = 0.0
    return c


def reference_ins_to_msg(s: ReferenceInsSample, plane: TangentPlane) -> Odometry:
    """/reference_ins/odom: position in the world tangent plane (frame world), attitude body FLU
    -> local ENU, ground velocity in body axes (child frame aircraft). Pose covariance: the height
    variance on z (the reference INS has no horizontal position error: 0 on x, y), att_cov on
    the attitude; twist: C^T vel_cov C, the body rate not provided (-1)."""
    c = quat_to_dcm(s.q_nb)
    p_w = np.asarray(plane.from_geodetic(s.lat, s.lon, s.h), dtype=float).reshape(3)
    m = odometry(s.t_ns, topics.FRAME_WORLD, topics.FRAME_AIRCRAFT, p_w, s.q_nb, c.T @ s.v_enu, np.zeros(3))
    pose = np.zeros((6, 6))
    pose[2, 2] = s.height_var
    pose[3:, 3:] = s.att_cov
    twist = np.zeros((6, 6))
    twist[:3, :3] = c.T @ s.vel_cov @ c
    twist[3, 3] = twist[4, 4] = twist[5, 5] = UNKNOWN
    m.pose.covariance = [float(x) for x in pose.ravel()]
    m.twist.covariance = [float(x) for x in twist.ravel()]
    return m


def msg_to_ins(m: Odometry, plane: TangentPlane, t0_ns: int = 0) -> InsSample:
    """An INS Odometry (world tangent plane pose, body twist) -> InsSample at (stamp - t0_ns) s:
    lat, h from the tangent plane, v_enu = C_b^n v_body, vel_cov = C twist_cov C^T."""
    p = m.pose.pose.position
    o = m.pose.pose.orientation
    q = np.array([o.x, o.y, o.z, o.w])
    lat, _, h = plane.to_geodetic(np.array([p.x, p.y, p.z]))
    c = quat_to_dcm(q)
    v = m.twist.twist.linear
    pose = np.asarray(m.pose.covariance, dtype=float).reshape(6, 6)
    twist = np.asarray(m.twist.covariance, dtype=float).reshape(6, 6)
    return InsSample((to_ns(m.header.stamp) - t0_ns) * 1e-9, q, c @ np.array([v.x, v.y, v.z]), float(h),
                     float(lat), _known(pose[3:, 3:]), c @ _known(twist[:3, :3]) @ c.T,
                     max(float(pose[2, 2]), 0.0))


# ----- the air-data estimate ---------------------------------------------------------------

class AirDataMsgs(NamedTuple):
    velocity: TwistWithCovarianceStamped
    static_pressure: FluidPressure
    total_pressure: FluidPressure
    wind: TwistWithCovarianceStamped
    state: Float64MultiArray


def _twist(t_ns: int, frame: str, v: np.ndarray, cov: np.ndarray) -> TwistWithCovarianceStamped:
    m = TwistWithCovarianceStamped()
    m.header.stamp = stamp(t_ns)
    m.header.frame_id = frame
    m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.linear.z = (float(x) for x in v)
    full = np.zeros((6, 6))
    full[:3, :3] = cov
    full[3, 3] = full[4, 4] = full[5, 5] = UNKNOWN           # no angular part
    m.twist.covariance = [float(x) for x in full.ravel()]
    return m


def _pressure(t_ns: int, p: float, sigma: float) -> FluidPressure:
    m = FluidPressure()
    m.header.stamp = stamp(t_ns)
    m.header.frame_id = topics.FRAME_AIRCRAFT
    m.fluid_pressure = float(p)
    m.variance = float(sigma) ** 2
    return m


def estimate_finite(e: AirDataEstimate) -> bool:
    """Every number the messages would carry is finite."""
    return bool(e.finite() and all(np.all(np.isfinite(a)) for a in (e.v_air_body, e.v_air_cov, e.wind_enu,
                                                                     e.wind_cov))
                and np.isfinite(e.total_pressure_pa) and np.isfinite(e.total_pressure_sigma_pa))


def air_data_to_msgs(t_ns: int, e: AirDataEstimate) -> AirDataMsgs:
    """/air_data/velocity (air-relative, body FLU, frame aircraft), static and total pressure,
    /air_data/wind (ENU, frame world) and /air_data/state ('value|sigma' rows over e.labels)."""
    return AirDataMsgs(
        velocity=_twist(t_ns, topics.FRAME_AIRCRAFT, e.v_air_body, e.v_air_cov),
        static_pressure=_pressure(t_ns, e.get('static_pressure_pa'), e.sigma_of('static_pressure_pa')),
        total_pressure=_pressure(t_ns, e.total_pressure_pa, e.total_pressure_sigma_pa),
        wind=_twist(t_ns, topics.FRAME_WORLD, e.wind_enu, e.wind_cov),
        state=labelled_array(VALUE_SIGMA, e.labels, np.stack([e.value, e.sigma])))


def msg_to_twist(m: TwistWithCovarianceStamped) -> tuple[int, np.ndarray, np.ndarray]:
    """(t_ns, linear (3,), its covariance (3, 3))."""
    v = m.twist.twist.linear
    return (to_ns(m.header.stamp), np.array([v.x, v.y, v.z]),
            np.asarray(m.twist.covariance, dtype=float).reshape(6, 6)[:3, :3].copy())


def msg_to_pressure(m: FluidPressure) -> tuple[int, float, float]:
    """(t_ns, pressure Pa, variance Pa^2)."""
    return to_ns(m.header.stamp), float(m.fluid_pressure), float(m.variance)
