"""A MultibodyPlant's kinematic tree as flat numpy arrays, for the compiled control law.

:mod:`aerial_drake.control.compiled` computes kinematics, Jacobians and the decomposition of
Section II itself (numba), so that one control-law evaluation costs no Drake calls. It needs the
plant's tree in plain arrays: :meth:`KinematicTree.from_plant` reads them once from a finalized
MultibodyPlant (double) and refuses, with :class:`UnsupportedTree`, what the kernels do not
handle. The callers then keep Drake's own path (:mod:`aerial_drake.dynamics.decoupling`).

Supported: one ``QuaternionFloatingJoint`` from World to the base body whose velocities come
first, and revolute and weld joints elsewhere, every body reached through one joint.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex, RigidBody

#: Joint kinds in :attr:`KinematicTree.joint_type`.
WELD, REVOLUTE, FREE = 0, 1, 2
_KINDS = {"weld": WELD, "revolute": REVOLUTE, "quaternion_floating": FREE}


class UnsupportedTree(ValueError):
    """The plant has a structure the compiled kernels do not handle."""


@dataclass(frozen=True)
class KinematicTree:
    """Bodies in parent-before-child order (World excluded; ``parent`` -1 means World).

    Each body C hangs from its parent P by a joint with frames F (on P) and M (on C):
    ``X_PC = X_PF X_FM(q) X_MC``. A weld's fixed ``X_FM`` is folded into ``X_PF``.
    """

    body_indices: tuple[int, ...]  # Drake BodyIndex of each entry
    parent: np.ndarray  # (nb,) int, index into these arrays, -1 = World
    joint_type: np.ndarray  # (nb,) int: WELD, REVOLUTE or FREE
    q_start: np.ndarray  # (nb,) int, first position of the joint (-1 for a weld)
    v_start: np.ndarray  # (nb,) int, first velocity of the joint (-1 for a weld)
    R_PF: np.ndarray  # (nb, 3, 3)
    p_PF: np.ndarray  # (nb, 3)
    R_MC: np.ndarray  # (nb, 3, 3)
    p_MC: np.ndarray  # (nb, 3)
    axis_F: np.ndarray  # (nb, 3) revolute axis (unit, in F = M); zero otherwise
    spatial_inertia: np.ndarray  # (nb, 6, 6) about the body origin, body frame, [w; v]
    mass: np.ndarray  # (nb,)
    com_B: np.ndarray  # (nb, 3) centre of mass in the body frame
    reflected_inertia: np.ndarray  # (nv,) drive inertia added to M's diagonal
    gravity_W: np.ndarray  # (3,)

    def index_of(self, body: RigidBody) -> int:
        """Position of ``body`` in these arrays."""
        try:
            return self.body_indices.index(int(body.index()))
        except ValueError:
            raise ValueError(f"body '{body.name()}' is not in the tree") from None

    @classmethod
    def from_plant(cls, plant: MultibodyPlant, base_body: RigidBody) -> "KinematicTree":
        """Read the tree of a finalized double ``plant`` whose free base is ``base_body``."""
        if not isinstance(plant, MultibodyPlant) or not plant.is_finalized():
            raise UnsupportedTree("a finalized MultibodyPlant (double) is needed")
        world = int(plant.world_body().index())
        inbound = {}
        for j in plant.GetJointIndices():
            joint = plant.get_joint(j)
            if joint.type_name() not in _KINDS:
                raise UnsupportedTree(
                    f"joint '{joint.name()}' is a {joint.type_name()} joint; the compiled "
                    f"kernels handle {', '.join(_KINDS)}")
            inbound[int(joint.child_body().index())] = joint
        order, frontier = [], [world]
        while frontier:  # breadth-first from World: parents before children
            parent = frontier.pop(0)
            children = sorted(c for c, joint in inbound.items()
                              if int(joint.parent_body().index()) == parent)
            order += children
            frontier += children
        missing = [plant.get_body(BodyIndex(b)).name() for b in range(plant.num_bodies())
                   if b != world and b not in order]
        if missing:
            raise UnsupportedTree(f"bodies not connected to World by joints: {missing}")
        base_joint = inbound.get(int(base_body.index()))
        if (base_joint is None or base_joint.type_name() != "quaternion_floating"
                or base_joint.velocity_start() != 0 or base_joint.position_start() != 0):
            raise UnsupportedTree("the base must hang from World by a quaternion floating "
                                  "joint whose coordinates come first")

        nb, nv = len(order), plant.num_velocities()
        position = {b: i for i, b in enumerate(order)}
        arrays = dict(parent=np.full(nb, -1), joint_type=np.zeros(nb, dtype=np.int64),
                      q_start=np.full(nb, -1), v_start=np.full(nb, -1),
                      R_PF=np.zeros((nb, 3, 3)), p_PF=np.zeros((nb, 3)),
                      R_MC=np.zeros((nb, 3, 3)), p_MC=np.zeros((nb, 3)),
                      axis_F=np.zeros((nb, 3)), spatial_inertia=np.zeros((nb, 6, 6)),
                      mass=np.zeros(nb), com_B=np.zeros((nb, 3)))
        context = plant.CreateDefaultContext()
        for i, b in enumerate(order):
            joint, body = inbound[b], plant.get_body(BodyIndex(b))
            kind = _KINDS[joint.type_name()]
            parent = int(joint.parent_body().index())
            arrays["parent"][i] = -1 if parent == world else position[parent]
            arrays["joint_type"][i] = kind
            X_PF = joint.frame_on_parent().GetFixedPoseInBodyFrame()
            if kind == WELD:
                X_PF = X_PF @ joint.X_FM()
            else:
                arrays["q_start"][i] = joint.position_start()
                arrays["v_start"][i] = joint.velocity_start()
            if kind == REVOLUTE:
                arrays["axis_F"][i] = joint.revolute_axis()
            if kind == FREE and not (X_PF.IsExactlyIdentity() and joint.frame_on_child()
                                     .GetFixedPoseInBodyFrame().IsExactlyIdentity()):
                raise UnsupportedTree("the floating joint's frames must be the World and base "
                                      "body frames")
            X_MC = joint.frame_on_child().GetFixedPoseInBodyFrame().inverse()
            arrays["R_PF"][i], arrays["p_PF"][i] = X_PF.rotation().matrix(), X_PF.translation()
            arrays["R_MC"][i], arrays["p_MC"][i] = X_MC.rotation().matrix(), X_MC.translation()
            if body.default_mass() > 0.0:
                M_B = body.CalcSpatialInertiaInBodyFrame(context)
                arrays["spatial_inertia"][i] = M_B.CopyToFullMatrix6()
                arrays["mass"][i] = M_B.get_mass()
                arrays["com_B"][i] = M_B.get_com()
        reflected = np.zeros(nv)
        for a in plant.GetJointActuatorIndices():
            actuator = plant.get_joint_actuator(a)
            reflected[actuator.joint().velocity_start()] += actuator.default_reflected_inertia()
        arrays = {k: np.ascontiguousarray(v) for k, v in arrays.items()}
        return cls(body_indices=tuple(order), reflected_inertia=reflected,
                   gravity_W=np.array(plant.gravity_field().gravity_vector(), dtype=float),
                   **arrays)
