"""``kind: hover``: a constant reference (the system's CoM at rest, the arm holding
its task)."""

from __future__ import annotations

import numpy as np

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.heading import heading_reference, rotated_offset
from aerial_drake.trajectories.orientation import end_effector_rotation
from aerial_drake.trajectories.params import HoverParams
from aerial_drake.trajectories.reference import ReferenceSample

__all__ = ["HoverReference"]


class HoverReference(ReferenceSource):
    """Constant CoM, heading and task; every derivative zero. Without ``com`` the CoM is
    rule (33) at the hover point, ee_position + R3(heading) ``com_offset``. ``params``
    already checked (:func:`aerial_drake.trajectories.kinds.reference_of` does)."""

    kind = "hover"

    def __init__(self, params: HoverParams, joint_targets: np.ndarray,
                 com_offset: np.ndarray) -> None:
        joint_targets = np.asarray(joint_targets, dtype=float)
        super().__init__(joint_targets.size)
        phi = np.array([float(params.heading), 0.0, 0.0, 0.0, 0.0])
        p = np.asarray(params.ee_position, dtype=float)
        com = np.zeros((5, 3))
        com[0] = params.com if params.com else p + rotated_offset(phi, com_offset)[0]
        zero = np.zeros(3)
        empty = np.zeros_like(joint_targets)
        sample = ReferenceSample(
            com=com, p_ed=p, v_ed=zero, a_ed=zero,
            R_ed=end_effector_rotation(params.ee_rpy, params.ee_orientation), w_ed=zero, dw_ed=zero,
            q_jd=joint_targets, q_jd_dot=empty, q_jd_ddot=empty,
            b1d=heading_reference(phi))
        self._packed = np.concatenate(sample.to_vectors())

    def fill(self, t: float, out: np.ndarray) -> None:
        out[:] = self._packed
