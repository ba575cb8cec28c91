"""How ``paper_plus`` shapes the references it hands to the paper's compiled law: the
integral action and the vehicle-force feed-forward as shifts of the reference's derivatives
(pure numpy; docs/control.md, "paper_plus").

The paper law (10)-(22) reads x_d and four derivatives, and y_d with two. ``paper_plus`` wants

- (10+): f_d = m x_d'' + m g e3 - K_x x~ - D_x x~' - K_I,x s_x - F^ (s_x = int x~ dt, F^ the
  estimated external force on the vehicle), i.e. x_d'' + d2 with d2 = -(K_I,x s_x + F^)/m;
- the attitude feed-forward (12)-(16) with the derivatives of that f_d: s_x' = x~,
  s_x'' = x~', F^ held constant between samples, and the model of (9a) with F^ in it,
  x_g'' = (u1 R e3 + F^)/m - g e3. The kernel forms x~'' from its own x_g'' = u1 R e3/m - g e3
  and the shifted x_d'', which makes it x~'' + K_I,x s_x/m: :func:`com_shift`'s d3, d4 undo
  that and add -K_I,x x~ and -K_I,x x~';
- (18+): z_d = y_d' - K_I,y s_y - J_1 x_g' - J_2 w_b - K_y y~ (s_y = int y~ dt), so z~ = 0
  means y~' + K_y y~ + K_I,y s_y = 0: y~'' + K_y y~' + K_I,y y~ = 0, whose rest is y~ = 0;
  a constant force on the arm leaves z~ at a constant K_z^-1-sized value, which the integral
  absorbs. That is y_d' + e1, e1 = -K_I,y s_y; the kernel's y~' (17) then carries +K_I,y s_y,
  which e2 undoes in (20), with -K_I,y y~ for s_y' and -J_1 F^/m for the model's x_g'' with
  F^ (J_1 = T^-1's CoM columns seen by the task: [E3; 0; 0] on the task's position rows, a
  pure translation of the whole robot; tests/control/test_plus.py checks it).

All shifts are zero when the integral state, its rates and F^ are zero: then ``paper_plus``
hands the law the references untouched.
"""

from __future__ import annotations

import functools

import numpy as np

from aerial_drake.trajectories.reference import TaskReferenceLayout, task_joint_count


def com_shift(m: float, K_x: np.ndarray, D_x: np.ndarray, k_I: np.ndarray, s: np.ndarray,
              rate: np.ndarray, rate_dot: np.ndarray, force: np.ndarray) -> np.ndarray:
    """(3, 3): the rows added to x_d'', x_d''', x_d'''' (module docstring).

    Args:
        m: the model's total mass (kg); K_x, D_x: (10)'s diagonals.
        k_I: the CoM integral gain (3); s: the integral of x~ (m s).
        rate, rate_dot: s' and s'' (x~ and x~' while integrating; zero while held).
        force: F^, the external force on the vehicle fed forward (N, World).
    """
    out = np.empty((3, 3))
    term = k_I * s  # N
    out[0] = -(term + force) / m
    out[1] = (D_x * term / m - k_I * rate) / m
    out[2] = (K_x * term / m - D_x * out[1] - k_I * rate_dot) / m
    return out


def task_shift(K_y: np.ndarray, k_I: np.ndarray, s: np.ndarray, rate: np.ndarray,
               rows: tuple[int, ...], accel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(e1, e2), each (n): the shifts of the task's rows of y_d' and y_d'' (module docstring).

    Args:
        K_y: (18)'s diagonal; k_I: the task integral gain (n); s: the integral of y~.
        rate: s' (y~ while integrating; zero while held).
        rows: the task's rows of y_full (:mod:`aerial_drake.robots.task`); rows 0-2 are the
            end effector's position along World x, y, z (J_1's nonzero rows).
        accel: F^/m (3), the model's extra CoM acceleration.
    """
    e1 = -k_I * s
    e2 = -k_I * rate + K_y * k_I * s
    for i, r in enumerate(rows):
        if r < 3:
            e2[i] -= accel[r]
    return e1, e2


@functools.lru_cache(maxsize=64)
def _shift_indices(task_size: int, rows: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """The entries of a packed task reference of ``task_size`` holding the task's ``rows``
    of y_d' and y_d''."""
    at = TaskReferenceLayout.of(task_joint_count(task_size))
    rows_ = np.asarray(rows, dtype=int)
    return at.full_dot.start + rows_, at.full_ddot.start + rows_


def shaped_references(com: np.ndarray, task: np.ndarray, d_com: np.ndarray, e1: np.ndarray,
                      e2: np.ndarray, rows: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Copies of the packed references ``com`` and ``task`` with the shifts added: ``d_com``
    (3, 3) to the second, third and fourth derivatives of x_d in ``com`` (entries 6-14); ``e1``,
    ``e2`` to the task's ``rows`` of y_d', y_d''."""
    com, task = np.array(com, dtype=float), np.array(task, dtype=float)
    com[6:15] += d_com.ravel()
    dot, ddot = _shift_indices(task.shape[-1], tuple(rows))
    task[dot] += e1
    task[ddot] += e2
    return com, task
