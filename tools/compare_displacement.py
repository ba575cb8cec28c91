"""How far each disturbance moved the end effector and the CoM, per controller: the
"moved by" rows of docs/baselines.md.

    aerial-drake compare nominal
    aerial-drake compare nominal --undisturbed
    python tools/compare_displacement.py out/compare/nominal out/compare/nominal_undisturbed

Reads the two compare folders (one run folder per controller in each) and prints, per
controller and window, the largest end-effector and CoM displacement between the disturbed and
the undisturbed run (aerial_drake.studies.compare.disturbance_displacement), in mm.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from aerial_drake.simulation.run_folder import load_run
from aerial_drake.studies.compare import disturbance_displacement


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("disturbed", type=Path, help="a compare folder (out/compare/NAME)")
    parser.add_argument("undisturbed", type=Path, help="its --undisturbed compare folder")
    args = parser.parse_args()
    for folder in sorted(p for p in args.disturbed.iterdir() if (p / "log.npz").is_file()):
        if not (args.undisturbed / folder.name / "log.npz").is_file():
            continue
        rows = disturbance_displacement(load_run(folder), load_run(args.undisturbed / folder.name))
        cells = "  ".join(f"{r['window_s'][0]:g}-{r['window_s'][1]:g} s: EE "
                          f"{1e3 * r['ee_moved_max_m']:.2f}, CoM {1e3 * r['com_moved_max_m']:.1f}"
                          for r in rows if r["ee_moved_max_m"] is not None)
        print(f"{folder.name:20s} {cells}")


if __name__ == "__main__":
    main()
