"""The inertially decoupled dynamics of Section II, in Drake's velocity coordinates.

Drake's velocities for a free base are ``v = [w_WB (World), v_WBo (World), qdot_arm]`` (angular
first). Every matrix of the paper is expressed in that ``v`` (docs/control.md, Coordinates):

- ``M v_dot + C v + g = J_b^T B psi + Q^T tau``                           (1)
- ``xi = [x_g_dot; w_b; rho] = T v``, ``T = [J_g; J_bw; N]``               (3)
- ``N = (Z M Z^T)^{-1} Z M``                                              (4)
- ``Lambda = T^{-T} M T^{-1}``, ``Gamma = T^{-T} (C - M T^{-1} T_dot) T^{-1}`` (5), (6)
- input map ``T^{-T} [J_b^T Q^T]``                                        (7)

``C`` is the Christoffel-consistent Coriolis matrix, assembled per body from spatial quantities
(Echeandia & Wensing 2021; docs/control.md, Coordinates). With it, ``Gamma``'s first three rows and
columns vanish, so the CoM dynamics (5a) has no velocity term.

Use :class:`DecoupledDynamics` (built once per plant) and call :meth:`DecoupledDynamics.compute`
once per state: it returns a :class:`Decomposition` holding every quantity, each computed once.
Works for a plant whose first six velocities are a free base (quaternion or RPY floating joint)
and whose other velocities are 1-DoF joints ordered parent before child, as Drake orders them.

Scalar types: a ``MultibodyPlant`` (double) gives float arrays; a ``MultibodyPlant_[AutoDiffXd]``
gives numpy object arrays of AutoDiffXd through the same code (for ``Linearize``). The few
operations numpy cannot do on object arrays go through :func:`inv` and :func:`solve`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pydrake.math
from pydrake.autodiffutils import ExtractValue
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex, Frame, JacobianWrtVariable, RigidBody
from pydrake.systems.framework import Context

_E3 = np.eye(3)


def hat(a: np.ndarray) -> np.ndarray:
    """The skew-symmetric matrix with ``hat(a) @ b == cross(a, b)``."""
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def vee(S: np.ndarray) -> np.ndarray:
    """Inverse of :func:`hat` (of the skew-symmetric part of ``S``)."""
    return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for 3-vectors (numpy's np.cross costs ~80 us of axis handling per call)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def inv(A: np.ndarray) -> np.ndarray:
    """Matrix inverse for float arrays (numpy) and AutoDiffXd object arrays (pydrake.math)."""
    return pydrake.math.inv(A) if A.dtype == object else np.linalg.inv(A)


def solve(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``A^{-1} B`` for float arrays (numpy) and AutoDiffXd object arrays."""
    if A.dtype == object or B.dtype == object:
        return pydrake.math.inv(A) @ B
    return np.linalg.solve(A, B)


def value_of(a) -> np.ndarray:
    """The float values of a float or AutoDiffXd (object) array or scalar."""
    a = np.asarray(a)
    return ExtractValue(a).reshape(a.shape) if a.dtype == object else a


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of 3-vectors stacked along axis -2: a, b of shape (..., 3, k)."""
    a0, a1, a2 = a[..., 0, :], a[..., 1, :], a[..., 2, :]
    b0, b1, b2 = b[..., 0, :], b[..., 1, :], b[..., 2, :]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-2)


def _hat_batch(a: np.ndarray) -> np.ndarray:
    """hat() of each row of ``a`` (k, 3) -> (k, 3, 3)."""
    out = np.zeros(a.shape[:-1] + (3, 3), dtype=a.dtype)
    out[..., 0, 1], out[..., 0, 2] = -a[..., 2], a[..., 1]
    out[..., 1, 0], out[..., 1, 2] = a[..., 2], -a[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -a[..., 1], a[..., 0]
    return out


def _crm_batch(V: np.ndarray) -> np.ndarray:
    """Spatial motion cross product matrices crm(V) = [[w x, 0], [v x, w x]], V = [w; v]."""
    out = np.zeros(V.shape[:-1] + (6, 6), dtype=V.dtype)
    W = _hat_batch(V[..., :3])
    out[..., :3, :3] = W
    out[..., 3:, 3:] = W
    out[..., 3:, :3] = _hat_batch(V[..., 3:])
    return out


def _crm_times(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """crm(a) b for stacks of spatial vectors along axis -2: a, b of shape (..., 6, k)."""
    aw, av = a[..., :3, :], a[..., 3:, :]
    bw, bv = b[..., :3, :], b[..., 3:, :]
    top = cross_rows(aw, bw)
    bottom = cross_rows(av, bw) + cross_rows(aw, bv)
    return np.concatenate([top, bottom], axis=-2)


@dataclass(frozen=True)
class Decomposition:
    """Every quantity of Section II at one state, in Drake's velocity coordinates.

    Shapes use ``nv = 6 + n``. Blocks of ``xi = T v`` are ``[0:3]`` (CoM velocity),
    ``[3:6]`` (base angular velocity in the base frame) and ``[6:]`` (``rho``).
    """

    m: float  # total mass (kg)
    R: np.ndarray  # R_WB, base orientation (3x3)
    p_WB: np.ndarray  # base origin in World (3)
    p_WG: np.ndarray  # system centre of mass in World (3)
    v: np.ndarray  # generalized velocity (nv)
    M: np.ndarray  # mass matrix (nv x nv), (1)
    C: np.ndarray  # Christoffel-consistent Coriolis matrix, C v = bias term, M_dot = C + C^T
    g: np.ndarray  # gravity vector on the left of (1): g = -tau_g
    J_b: np.ndarray  # base twist [v_b; w_b] in the base frame = J_b v (6 x nv)
    Q: np.ndarray  # selects the joint velocities (n x nv)
    J_g: np.ndarray  # CoM velocity Jacobian (3 x nv)
    J_g_dot: np.ndarray
    J_bw: np.ndarray  # base angular velocity in base frame (3 x nv)
    J_bw_dot: np.ndarray
    Z: np.ndarray  # null-space base, Z [J_g^T J_bw^T] = 0 (n x nv)
    N: np.ndarray  # dynamically consistent null-space projector (4)
    N_dot: np.ndarray
    T: np.ndarray  # (3)
    T_inv: np.ndarray
    T_dot: np.ndarray
    M_dot: np.ndarray  # C + C^T
    Lambda: np.ndarray  # T^{-T} M T^{-1}, block diagonal (5)
    Gamma: np.ndarray  # T^{-T} (C - M T^{-1} T_dot) T^{-1}
    xi: np.ndarray  # T v = [x_g_dot; w_b; rho]
    # Per-body quantities, kept so task Jacobians reuse them (bodies in DecoupledDynamics order).
    body_J: np.ndarray  # (nb, 6, nv) spatial velocity Jacobians, body frame, about body origin
    body_J_dot: np.ndarray
    body_R: np.ndarray  # (nb, 3, 3) R_WBi

    @property
    def n(self) -> int:
        return self.M.shape[0] - 6

    @property
    def input_map(self) -> np.ndarray:
        """``T^{-T} [J_b^T Q^T]`` of (7): maps ``[f e3; mu; tau]`` (base wrench in the base
        frame, then joint torques) to ``u'``. Its first three rows are ``[R 0 0]``."""
        return self.T_inv.T @ np.hstack([self.J_b.T, self.Q.T])

    @property
    def transformed_gravity(self) -> np.ndarray:
        """``T^{-T} g`` = ``[m g e3; 0; 0]``."""
        return self.T_inv.T @ self.g

    @property
    def rho(self) -> np.ndarray:
        return self.xi[6:]

    @property
    def w_b(self) -> np.ndarray:
        """Base angular velocity, base frame."""
        return self.xi[3:6]

    @property
    def x_g_dot(self) -> np.ndarray:
        return self.xi[:3]

    def Lambda_block(self, i: int, j: int) -> np.ndarray:
        """Block (i, j) of Lambda, 1-based as in the paper (1: CoM, 2: base rotation, 3: arm)."""
        return self.Lambda[_BLOCKS[i - 1], _BLOCKS[j - 1]]

    def Gamma_block(self, i: int, j: int) -> np.ndarray:
        """Block (i, j) of Gamma, 1-based as in the paper."""
        return self.Gamma[_BLOCKS[i - 1], _BLOCKS[j - 1]]


_BLOCKS = (slice(0, 3), slice(3, 6), slice(6, None))


class DecoupledDynamics:
    """Computes :class:`Decomposition` for one plant; construct once, call ``compute`` per state.

    Args:
        plant: a finalized MultibodyPlant (double or AutoDiffXd) whose velocities start with
            the base's six.
        base_body: the floating base; defaults to the plant's only floating base body, or the
            body named "helicopter".
    """

    def __init__(self, plant: MultibodyPlant, base_body: RigidBody | None = None):
        if not plant.is_finalized():
            raise ValueError("DecoupledDynamics needs a finalized plant (call plant.Finalize()).")
        self.plant = plant
        self.base_body = base_body if base_body is not None else _find_base(plant)
        nv = plant.num_velocities()
        if nv < 7:
            raise ValueError(f"plant has {nv} velocities; a free base plus at least one joint "
                             "needed")
        base_joints = [
            plant.get_joint(j) for j in plant.GetJointIndices()
            if plant.get_joint(j).child_body().index() == self.base_body.index()
        ]
        free = [j for j in base_joints if j.num_velocities() == 6]
        if base_joints and not free or (free and free[0].velocity_start() != 0):
            raise ValueError("the base must be attached to World by a 6-DoF floating joint whose "
                             "velocities come first")
        self.nv, self.n = nv, nv - 6
        world = plant.world_body().index()
        bodies = [plant.get_body(BodyIndex(b)) for b in range(plant.num_bodies())]
        self.bodies = [b for b in bodies if b.index() != world
                       and b.default_mass() > 0.0]
        if self.base_body not in self.bodies:
            raise ValueError(f"base body '{self.base_body.name()}' must have mass")
        self._base_pos = self.bodies.index(self.base_body)
        default_context = plant.CreateDefaultContext()
        # Arrays of the plant's scalar: float, or object for AutoDiffXd.
        self._dtype = float if isinstance(plant, MultibodyPlant) else object
        # Constant spatial inertias in each body's frame about its origin, [w; v] ordering.
        self._I = np.array([
            value_of(b.CalcSpatialInertiaInBodyFrame(default_context).CopyToFullMatrix6())
            for b in self.bodies
        ])
        self._mass = np.array([b.default_mass() for b in self.bodies])
        self.m = float(self._mass.sum())
        self._com_B = np.array([
            value_of(b.CalcSpatialInertiaInBodyFrame(default_context).get_com())
            for b in self.bodies
        ])
        # P_i = [-(c_i x), E3] maps a body spatial velocity to its CoM's translational velocity.
        self._P = np.concatenate([-_hat_batch(self._com_B),
                                  np.broadcast_to(_E3, (len(self.bodies), 3, 3))],
                                 axis=2)
        self.Q = np.hstack([np.zeros((self.n, 6)), np.eye(self.n)])
        self._world = plant.world_frame()
        self._frames = [b.body_frame() for b in self.bodies]
        self._gravity_z = -float(plant.gravity_field().gravity_vector()[2])

    @property
    def gravity(self) -> float:
        """Magnitude of gravity along -z (m/s^2)."""
        return self._gravity_z

    def compute(self, context: Context) -> Decomposition:
        """All of Section II's quantities at the state in ``context``."""
        plant, nv, n, dtype = self.plant, self.nv, self.n, self._dtype
        v = plant.GetVelocities(context)
        nb = len(self.bodies)
        kV = JacobianWrtVariable.kV
        J = np.empty((nb, 6, nv), dtype=dtype)
        R_all = np.empty((nb, 3, 3), dtype=dtype)
        p_all = np.empty((nb, 3), dtype=dtype)
        for i, frame in enumerate(self._frames):
            J[i] = plant.CalcJacobianSpatialVelocity(context, kV, frame, np.zeros(3),
                                                     self._world, frame)
            X = plant.EvalBodyPoseInWorld(context, self.bodies[i])
            R_all[i] = X.rotation().matrix()
            p_all[i] = X.translation()
        R = R_all[self._base_pos]
        V = J @ v  # (nb, 6) body spatial velocities
        J_dot = self._jacobian_derivatives(J, V, v, R_all)

        # Christoffel-consistent Coriolis matrix (docs/control.md, Coordinates).
        I = self._I
        crmV = _crm_batch(V)
        crfV = -np.swapaxes(crmV, 1, 2)
        h = np.einsum("bij,bj->bi", I, V)
        Hbar = np.zeros((nb, 6, 6), dtype=dtype)
        kx, px = _hat_batch(h[:, :3]), _hat_batch(h[:, 3:])
        Hbar[:, :3, :3], Hbar[:, :3, 3:], Hbar[:, 3:, :3] = -kx, -px, -px
        inner = I @ J_dot + 0.5 * (crfV @ I + I @ crmV + Hbar) @ J
        C = np.einsum("bki,bkj->ij", J, inner)

        M = plant.CalcMassMatrix(context)
        g = -plant.CalcGravityGeneralizedForces(context)

        # CoM Jacobian and its derivative: J_g = sum m_i/m R_i P_i J_i.
        mass_frac = self._mass / self.m
        RP = R_all @ self._P  # (nb, 3, 6)
        J_g = np.einsum("b,bij,bjk->ik", mass_frac, RP, J)
        W_hat = _hat_batch(V[:, :3])
        J_g_dot = np.einsum("b,bij,bjk->ik", mass_frac, R_all @ W_hat @ self._P, J) + \
            np.einsum("b,bij,bjk->ik", mass_frac, RP, J_dot)
        p_WG = np.einsum("b,bi->i", mass_frac, p_all + np.einsum("bij,bj->bi", R_all, self._com_B))

        RT = R.T
        w_b = RT @ v[:3]
        J_bw = np.zeros((3, nv), dtype=dtype)
        J_bw[:, :3] = RT
        J_bw_dot = np.zeros((3, nv), dtype=dtype)
        J_bw_dot[:, :3] = -hat(w_b) @ RT
        J_b = np.zeros((6, nv), dtype=dtype)
        J_b[:3, 3:6] = RT
        J_b[3:, :3] = RT

        # Closed-form null-space base: Z = [0, -A_q^T, E_n] (the paper's (3)-(4), Section II).
        A_q, A_q_dot = J_g[:, 6:], J_g_dot[:, 6:]
        Z = np.zeros((n, nv), dtype=dtype)
        Z[:, 3:6] = -A_q.T
        Z[:, 6:] = np.eye(n)
        Z_dot = np.zeros((n, nv), dtype=dtype)
        Z_dot[:, 3:6] = -A_q_dot.T

        M_dot = C + C.T
        ZM = Z @ M
        ZMZ = ZM @ Z.T
        N = solve(ZMZ, ZM)  # (4)
        ZdM = Z_dot @ M
        ZMd = Z @ M_dot
        ZMZ_dot = ZdM @ Z.T + ZMd @ Z.T + ZM @ Z_dot.T
        N_dot = solve(ZMZ, ZdM + ZMd - ZMZ_dot @ N)

        T = np.vstack([J_g, J_bw, N])  # (3)
        T_dot = np.vstack([J_g_dot, J_bw_dot, N_dot])
        T_inv = inv(T)
        Lambda = T_inv.T @ M @ T_inv
        Gamma = T_inv.T @ (C - M @ T_inv @ T_dot) @ T_inv
        xi = T @ v
        return Decomposition(
            m=self.m, R=R, p_WB=p_all[self._base_pos], p_WG=p_WG, v=v, M=M, C=C, g=g, J_b=J_b,
            Q=self.Q, J_g=J_g, J_g_dot=J_g_dot, J_bw=J_bw, J_bw_dot=J_bw_dot, Z=Z, N=N,
            N_dot=N_dot, T=T, T_inv=T_inv, T_dot=T_dot, M_dot=M_dot, Lambda=Lambda, Gamma=Gamma,
            xi=xi, body_J=J, body_J_dot=J_dot, body_R=R_all)

    def _jacobian_derivatives(self, J: np.ndarray, V: np.ndarray, v: np.ndarray,
                              R_all: np.ndarray) -> np.ndarray:
        """d/dt of each body-frame Jacobian, in closed form (docs/control.md, Coordinates)."""
        # 1-DoF joint column k: crm(J[:, k]) sum_{m > k} J[:, m] v_m (parent-before-child order).
        J_dot = np.empty_like(J)
        # Only the joints' columns (6:): the free joint's are set below.
        Jv = J[:, :, 6:] * v[6:]  # columns scaled by their velocity
        after = np.cumsum(Jv[:, :, ::-1], axis=2)[:, :, ::-1] - Jv  # sum over m > k
        J_dot[:, :, 6:] = _crm_times(J[:, :, 6:], after)
        # Free joint's six columns: -crm(V_i) J_i[:, free], plus [0; R_BiW (v_WBo x)] on the
        # angular ones.
        J_dot[:, :, :6] = -_crm_batch(V) @ J[:, :, :6]
        J_dot[:, 3:, :3] += np.swapaxes(R_all, 1, 2) @ hat(v[3:6])
        return J_dot

    def frame_jacobian(self, d: Decomposition, frame: Frame) -> tuple[np.ndarray, np.ndarray]:
        """World-expressed Jacobian of ``frame`` (rows ``[v_WE; w_WE]``, translational first)
        and its time derivative, reusing the decomposition's per-body quantities."""
        body = frame.body()
        try:
            i = self.bodies.index(body)
        except ValueError:
            raise ValueError(f"frame '{frame.name()}' is on a massless body; not supported")
        X_BE = frame.GetFixedPoseInBodyFrame()
        p = X_BE.translation()
        Ji, Ji_dot, Ri = d.body_J[i], d.body_J_dot[i], d.body_R[i]
        w_i = Ji[:3] @ d.v
        Pp = np.hstack([-hat(p), _E3])  # velocity of the point E from the body twist
        top, top_dot = Pp @ Ji, Pp @ Ji_dot
        Jw, Jw_dot = Ji[:3], Ji_dot[:3]
        Rw = Ri @ hat(w_i)
        J_out = np.vstack([Ri @ top, Ri @ Jw])
        J_out_dot = np.vstack([Rw @ top + Ri @ top_dot, Rw @ Jw + Ri @ Jw_dot])
        return J_out, J_out_dot


def _find_base(plant: MultibodyPlant) -> RigidBody:
    floating = [plant.get_body(b) for b in plant.GetFloatingBaseBodies()]
    if len(floating) == 1:
        return floating[0]
    # A floating joint added explicitly (e.g. RpyFloatingJoint for linearising): the one
    # six-velocity joint from World.
    world = plant.world_body().index()
    joints = [plant.get_joint(j) for j in plant.GetJointIndices()]
    free = [j.child_body() for j in joints
            if j.parent_body().index() == world and j.num_velocities() == 6]
    if len(free) == 1 and not floating:
        return free[0]
    raise ValueError("cannot tell the floating base: pass base_body= explicitly "
                     f"(floating bodies: {[b.name() for b in floating]})")


def decompose(plant: MultibodyPlant, context: Context) -> Decomposition:
    """One-shot convenience: ``DecoupledDynamics(plant).compute(context)``.

    In a loop, build :class:`DecoupledDynamics` once instead (it caches constant inertias).
    """
    return DecoupledDynamics(plant).compute(context)
