"""The data exchanged between stages: exactly the numbers the ROS messages carry.

Each stage of the batch pipeline consumes and produces these records, and each node
converts them to and from messages field by field (float64 in, float64 out), so the graph
and the batch pipeline see bit-identical inputs. Times are integer nanoseconds of
simulation time, like ROS stamps. Vectors are float64 arrays of shape (3,), quaternions
(x, y, z, w) of shape (4,).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class ShipSample:
    """Ship truth at the master INS point (/ship/odom + /ship/accel).

    p_w: position in the `world` tangent plane (ENU at the scenario origin), m.
    q_nb: attitude of the ship body (FLU) w.r.t. the local-level ENU nav frame.
    v_b: ground velocity in body axes; w_b: body rate w.r.t. the nav frame (omega_nb^b);
    a_b: nav-frame derivative of the ground velocity, in body axes; wdot_b: d(w_b)/dt.
    """
    t_ns: int
    p_w: np.ndarray
    q_nb: np.ndarray
    v_b: np.ndarray
    w_b: np.ndarray
    a_b: np.ndarray
    wdot_b: np.ndarray


@dataclass(frozen=True, slots=True)
class ImuSample:
    """Slave IMU output (/aircraft/imu): mean rate and mean specific force over the interval
    (t_ns - dt_ns, t_ns], i.e. increment / interval (FLU body axes, rad/s and m/s^2)."""
    t_ns: int
    gyro: np.ndarray
    accel: np.ndarray


@dataclass(frozen=True, slots=True)
class MasterSample:
    """Master INS solution (/master/odom): p_w world position (m), q_nb attitude (nav <- body),
    v_b velocity in body axes (m/s), w_b body rate w.r.t. nav (rad/s)."""
    t_ns: int
    p_w: np.ndarray
    q_nb: np.ndarray
    v_b: np.ndarray
    w_b: np.ndarray


@dataclass(frozen=True, slots=True)
class LdvSample:
    """Aircraft velocity relative to the deck, in ship axes (/ldv/twist); `valid` is False when
    the aircraft is out of the LDV's range (published with covariance[0] = -1). A beam LDV
    (`beam`: its unit line of sight, ship axes) measures only the component along it: v_s is
    that component times `beam`, sigma its noise (sensors/ldv_beam.py)."""
    t_ns: int
    v_s: np.ndarray
    sigma: float
    valid: bool
    beam: np.ndarray | None = None


@dataclass(frozen=True, slots=True)
class AircraftTruth:
    """Aircraft truth (/truth/aircraft/odom and /truth/misalignment). misalignment: (3,) rad, the
    IMU axes relative to the master's (ship body) axes, rotation vector: the mounting plus the
    deck's flexure and the airframe's motion on its gear, what the filter estimates."""
    t_ns: int
    p_w: np.ndarray
    q_nb: np.ndarray
    v_b: np.ndarray
    w_b: np.ndarray
    misalignment: np.ndarray
    on_deck: bool


@dataclass(frozen=True, slots=True)
class ShipBatch:
    """K ship samples as arrays (the same fields as ShipSample, with a leading K axis)."""
    t_ns: np.ndarray
    p_w: np.ndarray
    q_nb: np.ndarray
    v_b: np.ndarray
    w_b: np.ndarray
    a_b: np.ndarray
    wdot_b: np.ndarray

    @staticmethod
    def of(samples: list[ShipSample]) -> ShipBatch:
        return ShipBatch(t_ns=np.array([s.t_ns for s in samples], dtype=np.int64),
                         **{f: np.array([getattr(s, f) for s in samples])
                            for f in ('p_w', 'q_nb', 'v_b', 'w_b', 'a_b', 'wdot_b')})

    def __len__(self) -> int:
        return len(self.t_ns)

    def sample(self, k: int) -> ShipSample:
        return ShipSample(t_ns=int(self.t_ns[k]), p_w=self.p_w[k], q_nb=self.q_nb[k], v_b=self.v_b[k],
                          w_b=self.w_b[k], a_b=self.a_b[k], wdot_b=self.wdot_b[k])

    def slice(self, sl: slice | np.ndarray) -> ShipBatch:
        """The rows a slice, an index array or a boolean mask selects."""
        return ShipBatch(*(getattr(self, f)[sl] for f in ShipBatch.__slots__))



@dataclass(frozen=True, slots=True)
class DopplerSample:
    """Doppler radar reading (/doppler/twist): ground velocity in aircraft body axes (FLU,
    m/s) and its 1-sigma per axis; `valid` False means no measurement (covariance[0] = -1)."""
    t_ns: int
    v_b: np.ndarray
    sigma: float
    valid: bool
