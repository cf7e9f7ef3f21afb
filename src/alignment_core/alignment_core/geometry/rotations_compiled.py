"""The float forms of rotations.py compiled (compiled.py), for the kernels that call them: the
same functions, so a kernel's rotations are the interpreted code's, bit for bit."""
from __future__ import annotations

from alignment_core.compiled import kernel
from alignment_core.geometry import rotations

quat_to_dcm_k = kernel(rotations.quat_to_dcm_f)
cross_k = kernel(rotations.cross_f)
quat_mul_k = kernel(rotations.quat_mul_f)
normalized_k = kernel(rotations.normalized_f)
rotvec_to_quat_k = kernel(rotations.rotvec_to_quat_f)
rotvec_to_dcm_k = kernel(rotations.rotvec_to_dcm_f)
dcm_to_rotvec_k = kernel(rotations.dcm_to_rotvec_f)
