"""Axes and attitude conventions of a log, converted to the project's: body forward-left-up
(FLU), navigation frame local-level East-North-Up (ENU), attitude as the quaternion
(x, y, z, w) of C_b^n (body FLU -> ENU; Hamilton, it rotates body vectors into nav axes).

Body axes: FLU, FRD (forward-right-down), RFU (right-forward-up, the seed papers'). Navigation
frames: ENU, NED. Euler conventions (each fixes its own frames and yaw reference):

- `ned_frd_321`: aerospace yaw-pitch-roll, C_b^n = Rz(yaw) Ry(pitch) Rx(roll), body FRD in NED;
  yaw is the heading, from North, clockwise.
- `enu_flu_321`: ROS (REP-103) roll-pitch-yaw, the same product, body FLU in ENU; yaw from
  East, counter-clockwise (geometry.euler.euler_to_dcm).
- `enu_rfu_312`: the seed papers' pitch-roll-yaw, C_b^n = Rz(yaw) Rx(pitch) Ry(roll), body
  RFU in ENU; yaw from North, counter-clockwise (north-west positive).
"""
from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from alignment_core.geometry.euler import euler_to_dcm, rfu_to_flu

from .column_units import LogError

BODY_TO_FLU: dict[str, np.ndarray] = {
    'FLU': np.eye(3),
    'FRD': np.diag([1.0, -1.0, -1.0]),
    'RFU': rfu_to_flu(np.eye(3)).T,
}
"""v_FLU = BODY_TO_FLU[axes] @ v_axes."""

NAV_TO_ENU: dict[str, np.ndarray] = {
    'ENU': np.eye(3),
    'NED': np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]]),
}
"""v_ENU = NAV_TO_ENU[frame] @ v_frame."""

EULER_FRAMES: dict[str, tuple[str, str]] = {
    'ned_frd_321': ('NED', 'FRD'),
    'enu_flu_321': ('ENU', 'FLU'),
    'enu_rfu_312': ('ENU', 'RFU'),
}
"""Euler convention -> (its navigation frame, its body axes)."""

QUATERNION_ORDERS = ('wxyz', 'xyzw')


def body_to_flu(axes: str, where: str) -> np.ndarray:
    if axes not in BODY_TO_FLU:
        raise LogError(f'{where}: body axes {axes!r}: expected one of {", ".join(BODY_TO_FLU)}')
    return BODY_TO_FLU[axes]


def nav_to_enu(frame: str, where: str) -> np.ndarray:
    if frame not in NAV_TO_ENU:
        raise LogError(f'{where}: navigation frame {frame!r}: expected one of {", ".join(NAV_TO_ENU)}')
    return NAV_TO_ENU[frame]


def to_project(c_nb: np.ndarray, nav: str, body: str, where: str) -> np.ndarray:
    """C_b^n (..., 3, 3) of body `body` in nav frame `nav` -> the FLU-in-ENU C_b^n."""
    return nav_to_enu(nav, where) @ c_nb @ body_to_flu(body, where).T


def euler_dcm(convention: str, roll, pitch, yaw, where: str) -> np.ndarray:
    """C_b^n (N, 3, 3) of Euler angles (rad, (N,) each) in `convention`, in the project's
    frames (FLU in ENU)."""
    roll, pitch, yaw = (np.asarray(a, dtype=float) for a in (roll, pitch, yaw))
    if convention == 'ned_frd_321':
        c = Rotation.from_euler('ZYX', np.stack([yaw, pitch, roll], axis=-1)).as_matrix()
    elif convention == 'enu_flu_321':
        c = euler_to_dcm(roll, pitch, yaw)
    elif convention == 'enu_rfu_312':
        c = Rotation.from_euler('ZXY', np.stack([yaw, pitch, roll], axis=-1)).as_matrix()
    else:
        raise LogError(f'{where}: Euler convention {convention!r}: expected one of {", ".join(EULER_FRAMES)}')
    nav, body = EULER_FRAMES[convention]
    return to_project(c, nav, body, where)


def quaternion_dcm(q: np.ndarray, order: str, nav: str, body: str, where: str,
                   inverse: bool = False) -> np.ndarray:
    """C_b^n (N, 3, 3), FLU in ENU, of quaternions (N, 4) in `order` ('wxyz' scalar first,
    'xyzw' scalar last) of C_b^n of `body` in `nav` (`inverse`: of C_n^b). The norm must be
    1 to 1e-3 (it is then normalised)."""
    if order not in QUATERNION_ORDERS:
        raise LogError(f'{where}: quaternion order {order!r}: expected wxyz (scalar first) or xyzw (scalar last)')
    q = np.asarray(q, dtype=float)
    xyzw = q if order == 'xyzw' else q[:, [1, 2, 3, 0]]
    norm = np.linalg.norm(xyzw, axis=1)
    bad = np.flatnonzero(np.abs(norm - 1.0) > 1e-3)
    if len(bad):
        raise LogError(f'{where}: quaternion norm {norm[bad[0]]:.6g} at data row {bad[0] + 1} '
                       f'({len(bad)} rows off 1 by more than 1e-3): not a unit quaternion')
    r = Rotation.from_quat(xyzw)
    if inverse:
        r = r.inv()
    return to_project(r.as_matrix(), nav, body, where)


def dcm_to_quat(c: np.ndarray) -> np.ndarray:
    """Quaternions (N, 4), (x, y, z, w), scalar part >= 0, of C_b^n (N, 3, 3)."""
    q = Rotation.from_matrix(c).as_quat()
    return np.where(q[:, 3:4] < 0.0, -q, q)
