"""Independent oracles for the dynamics and the control law (issue 22), shared by
test_oracle_pinocchio.py and test_oracle_closed_loop.py.

Nothing here calls aerial_drake's decoupling, control or compiled code: the quantities come from
Drake's MultibodyPlant (mass matrix, Jacobians, centre of mass) and from Pinocchio, combined by
formulas written out here from the paper (equation numbers in parentheses) and the design
conventions of docs/control.md (Coordinates: Drake's v = [w_WB (World), v_WBo (World), q_arm_dot]).

- :func:`christoffel_coriolis`: the Christoffel Coriolis matrix from finite differences of
  Drake's mass matrix in holonomic coordinates (an roll-pitch-yaw base, whose q_dot are true
  derivatives), mapped to Drake's velocities. No Pinocchio needed.
- :func:`pinocchio_model`: a Pinocchio model built from the Drake plant's kinematic and inertial
  parameters (joint frames, axes, welds, spatial inertias, the drives' reflected inertia as
  armature). Pinocchio's pip wheel does not
  parse SDF, and this keeps both libraries on the same numbers (the SDF files are not read
  twice); what is compared is the rigid-body algorithms, not the parsing.
- :func:`drake_from_pinocchio`: Pinocchio's M, C, J_g, frame Jacobians (local free-flyer
  velocity [v_B; w_B], body frame) re-expressed in Drake's v.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.tree import JacobianWrtVariable

E3 = np.eye(3)


def hat(a):
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def vee_skew(S):
    """vee of the skew-symmetric part of S: (1/2 (S - S^T))^vee."""
    return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])


# --- Christoffel C from Drake's mass matrix alone ---------------------------------------------
class ChristoffelFromMassMatrix:
    """The Christoffel Coriolis matrix in Drake's velocities, from central differences of
    ``CalcMassMatrix``.

    Derivatives by the fourth-order central difference (:func:`directional_derivative`).
    In holonomic coordinates q_h = [roll, pitch, yaw, p_WB, q_arm] (an RpyFloatingJoint plant of
    the same model), with q_h_dot = S^-1 v (S from Drake's MapQDotToVelocity), the mass matrix
    is M_h = S^T M S and C_h[i, j] = sum_k 1/2 (dM_h[i,j]/dq_k + dM_h[i,k]/dq_j - dM_h[j,k]/dq_i)
    q_h_dot[k]. Re-expressed in v (M v_dot + C v = ... with v = S q_h_dot):
    C = S^-T C_h S^-1 - M S_dot S^-1. This is the one math.md section 3 asks for (the
    per-body formula transforms the same way under v = S q_dot).
    """

    def __init__(self, rpy_plant, step: float = 2e-4):
        self.plant = rpy_plant
        self.ctx = rpy_plant.CreateDefaultContext()
        self.nv = rpy_plant.num_velocities()
        self.h = step

    def rpy_positions(self, q_quat: np.ndarray) -> np.ndarray:
        """Quaternion-base positions [qw qx qy qz, p, arm] -> [rpy, p, arm]."""
        quat = np.asarray(q_quat[:4], dtype=float)
        rpy = RollPitchYaw(Quaternion(quat / np.linalg.norm(quat))).vector()
        return np.concatenate([rpy, q_quat[4:7], q_quat[7:]])

    def _S(self, q_h):
        self.plant.SetPositions(self.ctx, q_h)
        return np.column_stack([self.plant.MapQDotToVelocity(self.ctx, e)
                                for e in np.eye(self.nv)])

    def _M(self, q_h):
        self.plant.SetPositions(self.ctx, q_h)
        return self.plant.CalcMassMatrix(self.ctx)

    def _M_h(self, q_h):
        S = self._S(q_h)
        return S.T @ self._M(q_h) @ S

    def __call__(self, q_quat: np.ndarray, v: np.ndarray) -> np.ndarray:
        q_h = self.rpy_positions(q_quat)
        n, h = self.nv, self.h
        S = self._S(q_h)
        S_inv = np.linalg.inv(S)
        qd = S_inv @ v
        D = np.empty((n, n, n))  # D[k] = dM_h / dq_k
        for k in range(n):
            D[k] = directional_derivative(self._M_h, q_h, np.eye(n)[k], h)
        C_h = 0.5 * (np.einsum("kij,k->ij", D, qd) + np.einsum("jik,k->ij", D, qd)
                     - np.einsum("ijk,k->ij", D, qd))
        S_dot = directional_derivative(self._S, q_h, qd, h)
        M = self._M(q_h)
        return S_inv.T @ C_h @ S_inv - M @ S_dot @ S_inv


def directional_derivative(f, x: np.ndarray, dx: np.ndarray, h: float):
    """d/ds f(x + s dx) at s = 0, fourth-order central difference with step h."""
    return (f(x - 2 * h * dx) - 8.0 * f(x - h * dx) + 8.0 * f(x + h * dx)
            - f(x + 2 * h * dx)) / (12.0 * h)


# --- Pinocchio ---------------------------------------------------------------------------------
def _se3(pin, X: RigidTransform):
    return pin.SE3(X.rotation().matrix(), X.translation())


class PinocchioModel:
    """A Pinocchio model of a Drake plant whose base is a free body (Drake's quaternion floating
    joint, the plant's first six velocities) and whose other joints are revolute or welds.

    Built from the plant's parameters: each revolute joint at the pose of its frame on the
    parent (accumulated through welds) with Drake's axis (JointModelRevoluteUnaligned), each
    body's spatial inertia appended to the joint that carries it. ``frame(name, body, X_BF)``
    adds an operational frame.
    """

    def __init__(self, plant, base_body):
        import pinocchio as pin

        self.pin = pin
        self.plant = plant
        ctx = plant.CreateDefaultContext()
        model = pin.Model()
        base_id = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "base")
        attach = {base_body.index(): (base_id, RigidTransform())}  # body -> (joint, X_JB)
        pending = [plant.get_joint(j) for j in plant.GetJointIndices()
                   if plant.get_joint(j).child_body().index() != base_body.index()]
        self._drake_joint = {}  # pin joint id -> Drake joint
        while pending:
            progressed = False
            for J in list(pending):
                parent = J.parent_body().index()
                if parent not in attach:
                    continue
                jid_parent, X_JP = attach[parent]
                X_PF = J.frame_on_parent().GetFixedPoseInBodyFrame()
                X_MC = J.frame_on_child().GetFixedPoseInBodyFrame().inverse()
                child = J.child_body().index()
                if J.type_name() == "weld":
                    attach[child] = (jid_parent, X_JP @ X_PF @ J.X_FM() @ X_MC)
                elif J.type_name() == "revolute":
                    jid = model.addJoint(jid_parent,
                                         pin.JointModelRevoluteUnaligned(J.revolute_axis()),
                                         _se3(pin, X_JP @ X_PF), J.name())
                    self._drake_joint[jid] = J
                    attach[child] = (jid, X_MC)
                else:
                    raise NotImplementedError(f"joint type {J.type_name()}")
                pending.remove(J)
                progressed = True
            if not progressed:
                raise RuntimeError("joints not reachable from the base")
        for index, (jid, X_JB) in attach.items():
            body = plant.get_body(index)
            mass = body.default_mass()
            if not mass > 0.0:
                continue
            M_BBo_B = body.CalcSpatialInertiaInBodyFrame(ctx)
            com = M_BBo_B.get_com()
            I_cm = M_BBo_B.Shift(com).CalcRotationalInertia().CopyToFullMatrix3()
            model.appendBodyToJoint(jid, pin.Inertia(mass, com, I_cm), _se3(pin, X_JB))
        model.gravity.linear = plant.gravity_field().gravity_vector()
        self.model = model
        self._attach = attach
        self.data = model.createData()
        # Drake arm velocity index -> Pinocchio velocity index (rotors first in Drake's order).
        self.nv = model.nv
        self.v_index = np.arange(self.nv)  # v_pin[v_index[k]] <-> v_drake[k] for k >= 6
        self.q_index = np.arange(model.nq)
        for jid, J in self._drake_joint.items():
            self.v_index[J.velocity_start()] = model.joints[jid].idx_v
            self.q_index[J.position_start()] = model.joints[jid].idx_q
        self.base_index = base_body.index()
        # Drake's joint actuators' reflected inertia (rotor inertia x gear ratio^2, on the
        # joint's diagonal of M; docs/models.md "Drives") is Pinocchio's armature.
        armature = np.zeros(self.nv)
        for a in plant.GetJointActuatorIndices():
            actuator = plant.get_joint_actuator(a)
            armature[self.v_index[actuator.joint().velocity_start()]] = \
                actuator.default_reflected_inertia()
        model.armature = armature

    def add_frame(self, name: str, body, X_BF: RigidTransform) -> int:
        pin = self.pin
        jid, X_JB = self._attach[body.index()]
        fid = self.model.addFrame(pin.Frame(name, jid, _se3(pin, X_JB @ X_BF),
                                            pin.FrameType.OP_FRAME))
        self.data = self.model.createData()
        return fid

    # Drake state <-> Pinocchio state.
    def configuration(self, q_drake: np.ndarray) -> np.ndarray:
        """[qw qx qy qz, p, joints] (Drake) -> [p, qx qy qz qw, joints] (Pinocchio)."""
        q = np.zeros(self.model.nq)
        quat = q_drake[:4] / np.linalg.norm(q_drake[:4])
        q[:3] = q_drake[4:7]
        q[3:7] = [quat[1], quat[2], quat[3], quat[0]]
        for k in range(7, len(q_drake)):
            q[self.q_index[k]] = q_drake[k]
        return q

    def velocity_map(self, R: np.ndarray, w_B: np.ndarray):
        """S and S_dot with v_drake = S v_pin: v_pin = [v_B (base frame); w_B; joints in
        Pinocchio's order], v_drake = [w_W; v_W; joints in Drake's order], so w_W = R w_B,
        v_W = R v_B, and S_dot has R hat(w_B) where S has R."""
        n = self.nv
        S, S_dot = np.zeros((n, n)), np.zeros((n, n))
        S[0:3, 3:6], S[3:6, 0:3] = R, R
        Rw = R @ hat(w_B)
        S_dot[0:3, 3:6], S_dot[3:6, 0:3] = Rw, Rw
        for k in range(6, n):
            S[k, self.v_index[k]] = 1.0
        return S, S_dot

    def drake_quantities(self, q_drake: np.ndarray, v_drake: np.ndarray, frames=()) -> dict:
        """M, C (Pinocchio's computeCoriolisMatrix), J_g, J_g_dot v, and for each frame id the
        World-aligned Jacobian [v; w] and its time derivative, all in Drake's v."""
        pin, model, data = self.pin, self.model, self.data
        q = self.configuration(q_drake)
        quat = q_drake[:4] / np.linalg.norm(q_drake[:4])
        R = Quaternion(quat).rotation()
        w_B = R.T @ v_drake[0:3]
        S, S_dot = self.velocity_map(R, w_B)
        S_inv = np.linalg.inv(S)
        v = S_inv @ v_drake
        M_p = pin.crba(model, data, q)
        M_p = np.triu(M_p) + np.triu(M_p, 1).T  # crba fills the upper triangle
        C_p = pin.computeCoriolisMatrix(model, data, q, v)
        J_g_p = pin.jacobianCenterOfMass(model, data, q)
        pin.centerOfMass(model, data, q, v, np.zeros(model.nv))
        a_com_p = data.acom[0].copy()  # J_g_dot v (a = 0)
        M = S_inv.T @ M_p @ S_inv
        out = {
            "M": M,
            "C": S_inv.T @ C_p @ S_inv - M @ S_dot @ S_inv,
            "J_g": J_g_p @ S_inv,
            # d/dt (J_g_p S^-1) v = J_g_p_dot v_p - J_g_p S^-1 S_dot v_p
            "J_g_dot_v": a_com_p - J_g_p @ S_inv @ S_dot @ v,
            "p_WG": data.com[0].copy(),
            "R": R,
            "frames": {},
        }
        pin.computeJointJacobians(model, data, q)
        pin.computeJointJacobiansTimeVariation(model, data, q, v)
        pin.updateFramePlacements(model, data)
        lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        for fid in frames:
            J_p = pin.getFrameJacobian(model, data, fid, lwa)
            J_p_dot = pin.getFrameJacobianTimeVariation(model, data, fid, lwa)
            out["frames"][fid] = (J_p @ S_inv, J_p_dot @ S_inv - J_p @ S_inv @ S_dot @ S_inv,
                                  data.oMf[fid].translation.copy(),
                                  data.oMf[fid].rotation.copy())
        return out


# --- Section II from plain matrices (the paper's formulas, written here) ----------------------
def decoupling_transform(M: np.ndarray, J_g: np.ndarray, R: np.ndarray) -> dict:
    """(3)-(4) with the null-space base of aerial_drake.dynamics.decoupling: J_bw = [R^T 0 0],
    Z = [0, -A_q^T, E_n] (A_q = J_g's joint columns), N = (Z M Z^T)^-1 Z M, T = [J_g; J_bw; N],
    Lambda = T^-T M T^-1."""
    nv = M.shape[0]
    n = nv - 6
    J_bw = np.zeros((3, nv))
    J_bw[:, :3] = R.T
    Z = np.zeros((n, nv))
    Z[:, 3:6] = -J_g[:, 6:].T
    Z[:, 6:] = np.eye(n)
    N = np.linalg.solve(Z @ M @ Z.T, Z @ M)
    T = np.vstack([J_g, J_bw, N])
    T_inv = np.linalg.inv(T)
    return {"T": T, "T_inv": T_inv, "Lambda": T_inv.T @ M @ T_inv, "J_bw": J_bw}


def task_space_mobility(M: np.ndarray, J_g: np.ndarray, R: np.ndarray, J_y: np.ndarray):
    """J_z and Lambda_z of (19) without T^-1: with A = [J_g; J_bw] (the CoM and base-rotation
    rows of T), J1 xg_dot + J2 w_b is the part of y_dot that A v determines through
    M^-1 A^T (A M^-1 A^T)^-1, so z = J3 rho = J_z v with
    J_z = J_y (E - M^-1 A^T (A M^-1 A^T)^-1 A), and Lambda_z^-1 = J_z M^-1 J_z^T (the third
    diagonal block of (T' M^-1 T'^T) for T' = [J_g; J_bw; J_z], block diagonal since
    J_z M^-1 A^T = 0)."""
    nv = M.shape[0]
    J_bw = np.zeros((3, nv))
    J_bw[:, :3] = R.T
    A = np.vstack([J_g, J_bw])
    Minv = np.linalg.inv(M)
    P = np.eye(nv) - Minv @ A.T @ np.linalg.solve(A @ Minv @ A.T, A)
    J_z = J_y @ P
    Lambda_z = np.linalg.inv(J_z @ Minv @ J_z.T)
    return J_z, Lambda_z, Minv


# --- Drake's own task kinematics ---------------------------------------------------------------
def task_jacobian(plant, ctx, frame, q3_v: int) -> np.ndarray:
    """J_y: rows [v_WE (World); w_WE (World); q3_dot] from Drake's frame Jacobian."""
    J = plant.CalcJacobianSpatialVelocity(ctx, JacobianWrtVariable.kV, frame, np.zeros(3),
                                          plant.world_frame(), plant.world_frame())
    row = np.zeros((1, plant.num_velocities()))
    row[0, q3_v] = 1.0
    return np.vstack([J[3:], J[:3], row])


def central_difference(x: np.ndarray, dt: float) -> np.ndarray:
    """Fourth-order central difference along axis 0 (samples dt apart); the first and last two
    samples are NaN."""
    out = np.full_like(x, np.nan, dtype=float)
    out[2:-2] = (x[:-4] - 8.0 * x[1:-3] + 8.0 * x[3:-1] - x[4:]) / (12.0 * dt)
    return out
