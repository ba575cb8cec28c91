"""The controller gains of Table II and their one rule set.

:class:`Gains` is the scenario's ``gains:`` section; :meth:`Gains.validate` holds every rule a
gain must meet (sizes, finite, in (0, 1e6], equal orientation entries of K_y), written once:
the scenario's validation pass calls it, and so does :meth:`GainMatrices.from_gains` for a
controller built without a scenario. :class:`GainMatrices` is the validated gains as numpy
diagonals for the law's hot path.
"""


import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from aerial_drake.robots.task import POSE_ROW_LABELS, orientation_positions

#: The allowed interval of every gain entry, (GAIN_LOW, GAIN_HIGH], and the hint for a value
#: outside it. Proposition 1 needs positive definite gains; the upper bound catches a typo
#: (1e300) before it overflows the law.
GAIN_LOW, GAIN_HIGH = 0.0, 1e6
GAIN_FIX = "Table II's gains are 0.36 to 800; Proposition 1 needs every gain > 0"
GAIN_RULE = f"> {GAIN_LOW:g} and <= {GAIN_HIGH:g}"
_DIAGONALS = ("K_x", "D_x", "Lambda2_bar", "K_y", "K_z")
_SCALARS = ("k_R", "k_w", "lyapunov_gamma1", "lyapunov_gamma2")


class GainError(ValueError):
    """A gain breaks its rule; ``field`` is its dotted name (``gains.k_R``)."""

    def __init__(self, message: str, field: str) -> None:
        super().__init__(message)
        self.field = field


def show(value: Any) -> str:
    """A value as the user wrote it: plain floats and lists, no numpy reprs; YAML's words."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float) or hasattr(value, "dtype"):
        try:
            x = float(value)
        except (TypeError, ValueError):
            return repr(value)
        if math.isnan(x):
            return ".nan"
        if math.isinf(x):
            return ".inf" if x > 0 else "-.inf"
        return repr(x)
    if isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
        items = value.tolist() if hasattr(value, "tolist") else value
        if isinstance(items, list):
            return "[" + ", ".join(show(v) for v in items) + "]"
    return repr(value)


def _allowed(v: Any) -> bool:
    return (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
            and GAIN_LOW < v <= GAIN_HIGH)


@dataclass
class Gains:
    """Controller gains of Table II (values live in the scenario YAML). Diagonal matrices are
    given by their diagonals, as Proposition 1 requires diagonal positive definite gains."""

    # CoM stiffness K_x, diagonal (N/m).
    K_x: list[float] = field(default_factory=list)
    # CoM damping D_x, diagonal (N s/m).
    D_x: list[float] = field(default_factory=list)
    # Attitude stiffness k_R (N m).
    k_R: float = float("nan")
    # Attitude damping k_w (N m s/rad).
    k_w: float = float("nan")
    # Desired closed-loop attitude inertia Lambda_2 bar, diagonal (kg m^2).
    Lambda2_bar: list[float] = field(default_factory=list)
    # Task error gain K_y, diagonal (1/s), one entry per task row in the robot's task order
    # (the paper's: 3 position, 3 orientation, then q3).
    K_y: list[float] = field(default_factory=list)
    # Task velocity gain K_z, diagonal.
    K_z: list[float] = field(default_factory=list)
    # The small constants gamma_1, gamma_2 of the Lyapunov function V1 (25); they do not
    # enter the control law. For Table II's gains gamma_1 = 20 meets Lee et al.'s CoM
    # conditions (< 82) and gamma_2 = 0.4 their attitude bound (< 0.44); the condition that
    # couples the two cannot be met with Table II's gains (docs/analysis.md, section 5).
    lyapunov_gamma1: float = 20.0
    lyapunov_gamma2: float = 0.4

    def validate(self, n_task: int, prefix: str = "gains",
                 task_rows: tuple[int, ...] | None = None) -> "Gains":
        """Raise :class:`GainError` naming the field (``prefix.K_x``) if a gain is missing, of
        the wrong size, not finite or outside (0, 1e6], or (given the task's rows of
        ``y_full``) if K_y's orientation entries differ. Returns self."""
        sizes = {"K_x": 3, "D_x": 3, "Lambda2_bar": 3, "K_y": n_task, "K_z": n_task}
        for name in _DIAGONALS:
            value, where = getattr(self, name), f"{prefix}.{name}"
            if not isinstance(value, (list, tuple)) or len(value) != sizes[name]:
                raise GainError(f"{where} must be a list of {sizes[name]} diagonal entries; "
                                f"got {show(value)} (set it in the scenario YAML)", where)
            for i, v in enumerate(value):
                if not _allowed(v):
                    raise GainError(
                        f"{where} = {show(value)} is not positive definite with bounded "
                        f"entries: entry {i} must be finite, {GAIN_RULE}; got {show(v)} "
                        f"({GAIN_FIX})", where)
        for name in _SCALARS:
            value, where = getattr(self, name), f"{prefix}.{name}"
            if not _allowed(value):
                number = isinstance(value, (int, float)) and not isinstance(value, bool)
                rule = f"finite, {GAIN_RULE}" if number else f"a number {GAIN_RULE}"
                raise GainError(f"{where} must be {rule}; got {show(value)} ({GAIN_FIX})",
                                where)
        if task_rows is not None:
            _check_orientation_gains(self.K_y, task_rows, f"{prefix}.K_y")
        return self


def _check_orientation_gains(K_y: list[float], rows: tuple[int, ...], where: str) -> None:
    """Refuse unequal K_y entries on the orientation rows (docs/control.md, "The orientation
    error and K_y").

    The orientation error e = vee(skew(R_E R_ed^T)) has the rate w_E - w_ed + w_ed x e +
    O(|e|^2), while the law's task velocity error is w_E - w_ed (17): the error vector turns
    with w_ed, so (23d) holds for e only in norm, and only with equal gains k:
    d/dt |e|^2 / 2 = -k |e|^2 + e . z~ as (23d) has it, since e . (w_ed x e) = 0. With unequal
    gains the derivative of (24)'s y~^T K_y K_z y~ keeps e^T K_y K_z (w_ed x e), a term the
    proof of Proposition 1 does not cancel."""
    at = orientation_positions(rows)
    values = [K_y[k] for k in at]
    if values and max(values) != min(values):
        labels = ", ".join(POSE_ROW_LABELS[rows[k]] for k in at)
        raise GainError(
            f"{where} = {show(K_y)}: its orientation entries (task rows "
            f"{', '.join(str(k + 1) for k in at)}: {labels}) are unequal, {show(values)}. "
            "The orientation error vee(skew(R_E R_ed^T)) changes at w_E - w_ed + w_ed x e, "
            "not at the velocity error w_E - w_ed the law drives, so the error turns with "
            "the reference's angular velocity: with equal gains its norm still decays as "
            "(23d) says, with unequal ones (23d) fails and the Lyapunov derivative of "
            "(24)-(26) keeps an uncancelled term (measured: 1.7 % of the decaying term with "
            "[4, 8, 16]). Make the orientation entries equal (e.g. all "
            f"{show(float(values[0]))}; docs/control.md)", where)


@dataclass(frozen=True)
class GainMatrices:
    """Validated gains as numpy diagonals, for the control law's hot path."""

    K_x: np.ndarray
    D_x: np.ndarray
    k_R: float
    k_w: float
    Lambda2_bar: np.ndarray
    Lambda2_bar_inv: np.ndarray
    K_y: np.ndarray
    K_z: np.ndarray
    gamma1: float
    gamma2: float

    @classmethod
    def from_gains(cls, gains: Gains, n_task: int) -> "GainMatrices":
        """The matrices of ``gains`` for a task of ``n_task`` rows, after
        :meth:`Gains.validate` (the same rules as the scenario's check)."""
        gains = dataclasses.replace(gains).validate(n_task)
        L2 = np.asarray(gains.Lambda2_bar, dtype=float)
        return cls(K_x=np.asarray(gains.K_x, float), D_x=np.asarray(gains.D_x, float),
                   k_R=float(gains.k_R), k_w=float(gains.k_w), Lambda2_bar=L2,
                   Lambda2_bar_inv=1.0 / L2, K_y=np.asarray(gains.K_y, float),
                   K_z=np.asarray(gains.K_z, float), gamma1=float(gains.lyapunov_gamma1),
                   gamma2=float(gains.lyapunov_gamma2))
