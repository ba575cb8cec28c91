"""The closed loop analysed with Drake's tools (docs/analysis.md).

- :func:`hover_equilibrium`: a hover configuration (Drake's ``InverseKinematics`` through
  :func:`aerial_drake.dynamics.equilibrium.solve_configuration`) and the inputs that hold it.
- :func:`linearize_closed_loop`: Drake's ``Linearize`` of the continuous closed loop (no
  sampling, lag or saturation) at that equilibrium, on an ``RpyFloatingJoint`` base, with the
  controller converted to AutoDiffXd (``DecoupledController_[AutoDiffXd]``); its eigenvalues
  beside the predicted ones (docs/analysis.md, section 3) (:func:`predicted_eigenvalues`).
- :func:`linearize_open_loop` and :func:`controllability`: the plant alone at hover with the
  inputs ``[f, mu, tau]``, Drake's ``IsControllable`` / ``IsStabilizable``, and where the
  rank of the input matrix falls short (underactuation).
- :func:`lee_conditions`: the conditions of Lee et al. on ``gamma1``, ``gamma2`` of (25).
- :func:`lyapunov_study`: ``V(t)`` of (24)-(25) along the nominal trajectory without
  disturbances, continuous feedback, no saturation, an error-controlled integrator.
- :func:`region_of_attraction`: the fraction of runs that converge from sampled initial
  offsets of growing size.
- :func:`analyze`: all of it, written to a folder as ``analysis.json`` and plots.

One module per job (:mod:`.equilibria`, :mod:`.linearization`, :mod:`.controllability`,
:mod:`.lyapunov`, :mod:`.region_of_attraction`, :mod:`.figures`, :mod:`.report`, with
:mod:`.settings`); their public names are re-exported here, so ``from aerial_drake import
analysis`` then ``analysis.hover_equilibrium(...)`` reads as one toolbox. Importing this
package does not import matplotlib (the figures import it when drawn).
"""

from aerial_drake.analysis.controllability import (
    controllability,
    linearize_open_loop,
    unactuated_directions,
)
from aerial_drake.analysis.equilibria import (
    HoverEquilibrium,
    UnreachablePose,
    default_equilibria,
    hover_equilibrium,
    hover_inputs,
)
from aerial_drake.analysis.figures import (
    figure_eigenvalues,
    figure_lyapunov,
    figure_region_of_attraction,
)
from aerial_drake.analysis.linearization import (
    ClosedLoopLinearization,
    HoverLoop,
    build_hover_loop,
    compare_eigenvalues,
    linearize_closed_loop,
    predicted_eigenvalues,
)
from aerial_drake.analysis.lyapunov import (
    LyapunovResult,
    lee_conditions,
    lyapunov_scenario,
    lyapunov_study,
    trajectory_accel_bound,
)
from aerial_drake.analysis.region_of_attraction import (
    ROA_UNIT,
    RegionOfAttraction,
    region_of_attraction,
)
from aerial_drake.analysis.report import (
    analyze,
    format_eigenvalue_table,
    format_report,
)
from aerial_drake.analysis.settings import (
    FAST_SETTINGS,
    FULL_SETTINGS,
    AnalysisSettings,
)

__all__ = [
    "AnalysisSettings",
    "FAST_SETTINGS",
    "FULL_SETTINGS",
    "HoverEquilibrium",
    "UnreachablePose",
    "default_equilibria",
    "hover_equilibrium",
    "hover_inputs",
    "ClosedLoopLinearization",
    "HoverLoop",
    "build_hover_loop",
    "compare_eigenvalues",
    "linearize_closed_loop",
    "predicted_eigenvalues",
    "controllability",
    "linearize_open_loop",
    "unactuated_directions",
    "LyapunovResult",
    "lee_conditions",
    "lyapunov_scenario",
    "lyapunov_study",
    "trajectory_accel_bound",
    "ROA_UNIT",
    "RegionOfAttraction",
    "region_of_attraction",
    "figure_eigenvalues",
    "figure_lyapunov",
    "figure_region_of_attraction",
    "analyze",
    "format_eigenvalue_table",
    "format_report",
]
