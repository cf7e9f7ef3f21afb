"""The float forms of rotations.py compiled (compiled.py), for the kernels that call them: the
same functions, so a kernel's rotations are the interpreted code's, bit for bit. Also the
error-state models' attitude feedback on arrays (rotate_attitude), their composition compiled."""
from __future__ import annotations

import numpy as np

from alignment_core.compiled import as_float64, kernel
from alignment_core.geometry import rotations

quat_to_dcm_k = kernel(rotations.quat_to_dcm_f)
cross_k = kernel(rotations.cross_f)
quat_mul_k = kernel(rotations.quat_mul_f)
normalized_k = kernel(rotations.normalized_f)
rotvec_to_quat_k = kernel(rotations.rotvec_to_quat_f)
rotvec_to_dcm_k = kernel(rotations.rotvec_to_dcm_f)
dcm_to_rotvec_k = kernel(rotations.dcm_to_rotvec_f)
quat_to_rotvec_k = kernel(rotations.quat_to_rotvec_f)


def rotate_attitude(q_nb: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """exp([phi x]) C_b^n as a unit quaternion (4,): the attitude q_nb turned by the nav-frame
    rotation vector phi (3,) and renormalised (the error-state models' attitude feedback)."""
    return rotate_attitude_k(as_float64(q_nb), as_float64(phi))


@kernel
def rotate_attitude_k(q_nb, phi):
    """rotate_attitude on float64 arrays q_nb (4,), phi (3,): one call for the float forms'
    composition (their numpy-free arithmetic costs a few microseconds interpreted)."""
    q = (q_nb[0], q_nb[1], q_nb[2], q_nb[3])
    return np.array(normalized_k(quat_mul_k(rotvec_to_quat_k(phi[0], phi[1], phi[2]), q)))
