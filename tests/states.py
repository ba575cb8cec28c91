"""Random states of a plant and the decomposition at them: shared by the tests of Section II
(tests/dynamics/) and of the compiled law (tests/control/)."""

import numpy as np

N_STATES = 12


def random_states(plant, seed=0):
    """Random configurations and velocities, half of them fast (up to 10 rad/s, 10 m/s)."""
    rng = np.random.default_rng(seed)
    for k in range(N_STATES):
        q = rng.normal(size=plant.num_positions())
        q[:4] /= np.linalg.norm(q[:4])
        q[7:] = rng.uniform(-2.0, 2.0, plant.num_positions() - 7)
        scale = 1.0 if k % 2 else 10.0
        yield q, rng.uniform(-scale, scale, plant.num_velocities())


def at_state(plant, dd, q, v):
    ctx = plant.CreateDefaultContext()
    plant.SetPositions(ctx, q)
    plant.SetVelocities(ctx, v)
    return ctx, dd.compute(ctx)



def rel(a, b):
    return np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300)
