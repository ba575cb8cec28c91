"""Where the model files (SDF, ``package.xml``) are, installed or in a checkout. (The scenario
YAML files ship beside :mod:`aerial_drake.simulation.scenarios`, which finds them itself.)"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

# aerial_drake/robots/resources.py -> the checkout's root, which holds models/sdf/.
_CHECKOUT_ROOT = Path(__file__).resolve().parents[2]


def model_directory() -> Path:
    """The folder holding ``package.xml`` and the SDF models.

    In a source checkout this is ``models/sdf/``; in an installed wheel the same files are
    shipped as the data package ``aerial_drake.sdf``.
    """
    candidates = [_CHECKOUT_ROOT / "models" / "sdf"]
    try:
        candidates.append(Path(str(resources.files("aerial_drake.sdf"))))
    except ModuleNotFoundError:
        pass
    for folder in candidates:
        if (folder / "package.xml").is_file():
            return folder
    raise FileNotFoundError(
        "aerial_drake model files not found (looked for package.xml in "
        + ", ".join(str(c) for c in candidates)
        + "). Reinstall the package with `pip install .` from a full checkout."
    )

