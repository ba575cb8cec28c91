"""What ``robot check FILE`` checks: the robot, the gains and the hover point, from a robot
description (``NAME.robot.yaml``, with the hover scenario ``NAME_hover.yaml`` beside it that
``robot init`` writes, or the scenario of ``--scenario``) or from a scenario file (its robot,
its gains, its reference at t = 0 as the hover point), and the nominal posture: the
configuration that realises that point (:func:`~aerial_drake.control.reference_pose.
realising_targets`, as a run's start, :func:`~aerial_drake.simulation.runner.
set_initial_state`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from aerial_drake.analysis.onboarding.errors import OnboardingError
from aerial_drake.control.reference_pose import mass_and_gravity, realising_targets
from aerial_drake.dynamics.equilibrium import UnreachablePose, solve_configuration
from aerial_drake.robots.models import AerialManipulator, make_plant
from aerial_drake.simulation.scenarios import Scenario, load_scenario
from aerial_drake.simulation.scenarios.robot import robot_description
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.reference import ReferenceSample

#: The suffix of a robot description file (docs/robots.md).
DESCRIPTION_SUFFIX = ".robot.yaml"
#: The hover scenario ``robot init`` writes beside ``NAME.robot.yaml``: ``NAME`` + this.
HOVER_SUFFIX = "_hover.yaml"


@dataclass(frozen=True)
class CheckSubject:
    """The robot, the law's gains and limits (a scenario's) and the hover point to check."""

    file: Path  # the FILE given
    scenario: Scenario  # where the gains, limits and hover come from
    scenario_source: str  # the scenario's file (or shipped name), for the report
    model: AerialManipulator  # the controller's model (quaternion base)
    hover: ReferenceSample  # the reference at t = 0, every derivative zero
    q0: np.ndarray  # the nominal posture: positions realising ``hover``
    mass: float  # kg
    gravity: float  # m/s^2

    @property
    def references(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The packed (com, task, heading) vectors of the constant hover reference."""
        return self.hover.to_vectors()

    @property
    def heading_axes(self) -> np.ndarray:
        """Columns b1d, e3 x b1d, e3 (World): the heading frame the directions are in."""
        b1 = self.hover.b1d[0]
        return np.column_stack([b1, np.cross([0.0, 0.0, 1.0], b1), [0.0, 0.0, 1.0]])

    @property
    def weight(self) -> float:
        """m g (N)."""
        return self.mass * self.gravity


def hover_description_path(description: Path) -> Path:
    """``NAME_hover.yaml`` beside ``NAME.robot.yaml``."""
    name = description.name[:-len(DESCRIPTION_SUFFIX)]
    return description.with_name(name + HOVER_SUFFIX)


def _scenario_for(file: Path, scenario: str | None) -> tuple[Scenario, str]:
    """The scenario the check takes its gains and hover from (module docstring)."""
    is_description = file.name.endswith(DESCRIPTION_SUFFIX)
    if not is_description:
        if scenario is not None:
            raise OnboardingError(
                f"--scenario {scenario}: only for a robot description (FILE = "
                f"NAME{DESCRIPTION_SUFFIX}); FILE {file} is a scenario, whose own gains and "
                "hover are checked: drop --scenario", "--scenario")
        if file.suffix and not file.exists():
            raise OnboardingError(f"FILE {file}: no such file; give a robot description "
                                  f"(NAME{DESCRIPTION_SUFFIX}) or a scenario (.yaml)", "FILE")
        return load_scenario(file), str(file)
    if not file.exists():
        raise OnboardingError(f"FILE {file}: no such robot description; write one with "
                              "`aerial-drake robot init MODEL` (docs/robots.md)", "FILE")
    source = Path(scenario) if scenario is not None else hover_description_path(file)
    if not source.exists():
        if scenario is not None:
            raise OnboardingError(f"--scenario {scenario}: no such file", "--scenario")
        raise OnboardingError(
            f"FILE {file}: the check takes the gains and the hover point from {source} "
            f"(written by `aerial-drake robot init` beside the description), which does not "
            f"exist: run `aerial-drake robot init` on the model, or give a scenario flying "
            f"this robot with --scenario S", "FILE")
    # The description given is the robot checked, whatever the scenario's ``robot`` says.
    return (load_scenario(source, overrides={"robot": str(file.resolve())}), str(source))


def hover_sample(scenario: Scenario, model: AerialManipulator) -> ReferenceSample:
    """The scenario's reference at t = 0 held still: its CoM, end-effector pose, task joints
    and heading, every derivative zero (a trajectory's start velocity would tilt R_d)."""
    ref = reference_of(scenario.trajectory, model.task_joint_nominal()).evaluate(0.0)
    com = np.zeros((5, 3))
    com[0] = ref.com[0]
    b1d = np.zeros((3, 3))
    b1d[0] = ref.b1d[0]
    z3 = np.zeros(3)
    zj = np.zeros_like(ref.q_jd)
    return ReferenceSample(com=com, p_ed=ref.p_ed.copy(), v_ed=z3, a_ed=z3,
                           R_ed=ref.R_ed.copy(), w_ed=z3, dw_ed=z3, q_jd=ref.q_jd.copy(),
                           q_jd_dot=zj, q_jd_ddot=zj, b1d=b1d)


def load_subject(file: Path, scenario: str | None = None) -> CheckSubject:
    """The :class:`CheckSubject` of ``robot check FILE [--scenario S]`` (module docstring).

    Raises:
        OnboardingError: FILE or S missing, or no configuration realises the hover point.
        ScenarioError: the scenario or the description is invalid (naming the field).
    """
    file = Path(file)
    s, source = _scenario_for(file, scenario)
    model = make_plant(robot=robot_description(s.robot))
    hover = hover_sample(s, model)
    m, g = mass_and_gravity(model)
    try:
        # As the run's start: the joint limits are the check's to report, not the solver's.
        q0 = solve_configuration(model, **realising_targets(model, hover, (m, g)),
                                 respect_joint_limits=False)
    except UnreachablePose as err:
        raise OnboardingError(f"{source}: trajectory: no configuration realises the "
                              f"reference at t = 0 ({err})", "trajectory") from None
    return CheckSubject(file=file, scenario=s, scenario_source=source, model=model,
                        hover=hover, q0=q0, mass=m, gravity=g)
