"""Section II as math: the inertially decoupling change of coordinates (:mod:`.decoupling`,
numpy, also on Drake's AutoDiff path), the kinematic tree read from a plant
(:mod:`.kinematic_tree`, for the compiled law), and configurations realising a task
(:mod:`.equilibrium`, Drake's ``InverseKinematics``)."""
