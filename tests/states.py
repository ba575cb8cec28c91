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


def symmetric_cases(count: int = 400, seed: int = 7):
    """``(k, S)``: 7x7 symmetric matrices for smallest-eigenvalue solvers, from the same draws
    each time: a spread, a tiny, a double or a zero smallest singular value of a random
    matrix, half of them as S = J^T J (positive semi-definite), half indefinite."""
    rng = np.random.default_rng(seed)
    for k in range(count):
        J = rng.normal(size=(7, 7))
        U, _, Vt = np.linalg.svd(J)
        s = np.sort(rng.uniform(0.1, 3.0, 7))
        if k % 4 == 1:
            s[0] = 10.0 ** rng.uniform(-8, 0)
        elif k % 4 == 2:
            s[1] = s[0]
        elif k % 4 == 3:
            s[0] = 0.0
        S = (U * s) @ Vt
        yield k, (S.T @ S if k % 8 < 4 else 0.5 * (J + J.T))
