"""The task y of a robot: which end-effector and joint coordinates the controller tracks.

The paper assumes no redundancy: the task has as many coordinates as the arm has joints, n.
A task is a list of components, each naming rows of the *full task*::

    y_full = [p_E (3, World); e_o (3, World); q_j (one per joint component)]

where ``e_o = vee(skew(R_E R_ed^T))`` is the orientation error (its rate is ``w_E - w_ed`` at
zero error, :mod:`aerial_drake.control.law`). The components:

- ``position``: rows 0-2 (p_E); ``position_x``, ``position_y``, ``position_z``: one of them;
- ``orientation``: rows 3-5 (e_o), all three. Single rows of e_o are refused: with the other
  orientation rows free, R_E R_ed^T is far from the identity and a row of vee(R_E R_ed^T)
  no longer has the row of w_E as its rate, so (17)-(20) would feed the law the wrong
  derivative (a run with ``orientation_z`` alone spun the wrist and lost Assumption 1 within
  0.5 s). An Euler-angle coordinate with its analytic Jacobian would be the way to add one;
  until then use a joint component (e.g. the wrist's angle) for the fourth coordinate of a
  4-joint arm;
- ``joint:NAME``: the angle of the arm joint NAME (the paper's q3 is ``joint:lwr_joint_3``).

The task vector is the rows in the order listed; gains K_y, K_z are given in that order. This
module is pure data: joint indices are resolved when the plant is built
(:func:`aerial_drake.robots.models.add_aerial_manipulator`).
"""

from __future__ import annotations

from dataclasses import dataclass

#: Pose components -> their rows in y_full.
POSE_COMPONENTS: dict[str, tuple[int, ...]] = {
    "position": (0, 1, 2),
    "position_x": (0,),
    "position_y": (1,),
    "position_z": (2,),
    "orientation": (3, 4, 5),
}
#: Components refused, with the reason (the module docstring).
REFUSED_COMPONENTS = {
    name: "a single row of the orientation error is not a coordinate whose rate is the row of "
          "w_E when the other rows are free; use orientation (all three rows) or a joint "
          "component (joint:<name>) instead"
    for name in ("orientation_x", "orientation_y", "orientation_z", "yaw")
}
JOINT_PREFIX = "joint:"
#: Short names of y_full's pose rows, for plots and metrics.
POSE_ROW_LABELS = ("p_x", "p_y", "p_z", "o_x", "o_y", "o_z")
POSE_ROWS = 6


class TaskError(ValueError):
    """A task list that does not describe a task (unknown or repeated component)."""


@dataclass(frozen=True)
class TaskComponents:
    """A parsed task list: rows into y_full for the pose part, and the joint names."""

    components: tuple[str, ...]
    #: Rows of y_full in task order; a joint component k has row ``POSE_ROWS + k``.
    rows: tuple[int, ...]
    joint_names: tuple[str, ...]

    @property
    def size(self) -> int:
        return len(self.rows)


def parse_task(components: list[str] | tuple[str, ...]) -> TaskComponents:
    """Parse a task list (see the module docstring).

    Raises:
        TaskError: an unknown component, a row asked for twice, a joint named twice, or an
            empty task; the message lists the valid components.
    """
    if not components:
        raise TaskError(f"the task is empty: list its components, e.g. [position, orientation]"
                        f" (valid: {valid_components()})")
    rows: list[int] = []
    joints: list[str] = []
    for component in components:
        if not isinstance(component, str):
            raise TaskError(f"task component {component!r} is not text; valid: "
                            f"{valid_components()}")
        if component.startswith(JOINT_PREFIX):
            name = component[len(JOINT_PREFIX):].strip()
            if not name:
                raise TaskError(f"task component '{component}' names no joint: write "
                                "joint:<the joint's name in the model>")
            if name in joints:
                raise TaskError(f"task component '{component}' is listed twice")
            rows.append(POSE_ROWS + len(joints))
            joints.append(name)
            continue
        if component in REFUSED_COMPONENTS:
            raise TaskError(f"task component '{component}' is not supported: "
                            f"{REFUSED_COMPONENTS[component]}")
        if component not in POSE_COMPONENTS:
            raise TaskError(f"unknown task component '{component}'; valid: {valid_components()}")
        for row in POSE_COMPONENTS[component]:
            if row in rows:
                raise TaskError(f"task component '{component}' repeats the row "
                                f"{POSE_ROW_LABELS[row]} of an earlier component")
            rows.append(row)
    return TaskComponents(tuple(components), tuple(rows), tuple(joints))


def orientation_positions(rows: tuple[int, ...]) -> tuple[int, ...]:
    """Where the orientation rows (3-5 of y_full) sit in a task vector with ``rows``: the
    entries of K_y, K_z that act on the orientation error e_o."""
    return tuple(k for k, r in enumerate(rows) if 3 <= r < POSE_ROWS)


def valid_components() -> str:
    return ", ".join([*POSE_COMPONENTS, "joint:<name>"])


@dataclass(frozen=True)
class TaskLayout:
    """A robot's task with its joints resolved in the plant: what the controller, the
    reference and the logs need.

    ``rows`` index y_full = [p_E (3); e_o (3); q_j (n_joints)]; ``joint_positions`` and
    ``joint_velocities`` are the task joints' indices in the plant's q and v.
    """

    components: tuple[str, ...]
    rows: tuple[int, ...]
    joint_names: tuple[str, ...]
    joint_positions: tuple[int, ...]
    joint_velocities: tuple[int, ...]

    @property
    def n(self) -> int:
        """The task's dimension (= the arm's number of joints)."""
        return len(self.rows)

    @property
    def n_joints(self) -> int:
        """How many task coordinates are joint angles."""
        return len(self.joint_names)

    @property
    def labels(self) -> tuple[str, ...]:
        """One short name per task row, in task order (``p_x`` ... ``o_z``, joint names)."""
        return tuple(POSE_ROW_LABELS[r] if r < POSE_ROWS else self.joint_names[r - POSE_ROWS]
                     for r in self.rows)

    @property
    def has_full_position(self) -> bool:
        return all(r in self.rows for r in (0, 1, 2))

    @property
    def has_full_orientation(self) -> bool:
        return all(r in self.rows for r in (3, 4, 5))
