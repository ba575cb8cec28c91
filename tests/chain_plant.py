"""A random floating base + 7-joint chain, to check the dynamics layer beyond our own model."""

import numpy as np
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import FixedOffsetFrame, RevoluteJoint, SpatialInertia, UnitInertia


def make_random_chain(seed: int = 0, n: int = 7) -> MultibodyPlant:
    rng = np.random.default_rng(seed)
    plant = MultibodyPlant(0.0)

    def body(name, mass):
        c = rng.uniform(-0.1, 0.1, 3)
        Icm = UnitInertia.SolidBox(*rng.uniform(0.1, 0.5, 3))
        return plant.AddRigidBody(
            name, SpatialInertia.MakeFromCentralInertia(
                mass, c, Icm.ReExpress(RotationMatrix.MakeFromOneVector(rng.normal(size=3), 2))
                * mass))

    parent = body("base", 30.0)
    for k in range(n):
        child = body(f"link{k}", rng.uniform(1.0, 3.0))
        axis = rng.normal(size=3)
        X_PJ = RigidTransform(RotationMatrix.MakeFromOneVector(rng.normal(size=3), 2),
                              rng.uniform(-0.3, 0.3, 3))
        frame = plant.AddFrame(FixedOffsetFrame(f"j{k}_parent", parent.body_frame(), X_PJ))
        plant.AddJoint(RevoluteJoint(
            f"j{k}", frame, child.body_frame(), axis / np.linalg.norm(axis)))
        parent = child
    plant.Finalize()
    return plant


#: The plants the compiled kernels are checked on (:func:`kernel_test_plant`).
KERNEL_TEST_PLANTS = ("model", "rotors", "quadrotor_ur3e", "chain")


def kernel_test_plant(which: str) -> MultibodyPlant:
    """One of :data:`KERNEL_TEST_PLANTS`: our model, the rotors variant (a tree: rotors and
    arm both hang from the base), the second shipped robot, a random chain (arbitrary joint
    axes and offsets)."""
    from aerial_drake.robots.description import load_robot_description
    from aerial_drake.robots.models import make_plant
    if which == "model":
        return make_plant("rigid").plant
    if which == "rotors":
        return make_plant("rotors").plant
    if which == "quadrotor_ur3e":
        return make_plant(robot=load_robot_description("quadrotor_ur3e")).plant
    return make_random_chain(5)
