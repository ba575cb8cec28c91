"""``robot check``'s push margins against simulated pushes: the numbers of docs/robots.md,
"robot check".

    python tools/push_margins.py tests_hover.yaml            # a scenario
    python tools/push_margins.py my_robot.robot.yaml         # with my_robot_hover.yaml
    python tools/push_margins.py quadrotor_ur3e --directions +y -z --json out.json

For each direction (heading frame) the check's largest static push F_max on the vehicle
(aerial_drake.analysis.onboarding.margins) is flown at F_max and at FACTOR x F_max (default
1.3) as a slow staircase after the hover (aerial_drake.analysis.onboarding.push_validation).
Printed per run: survived or the run's failure cause, the largest and the final CoM
deflection against the check's static prediction at F_max, the end effector's largest error;
for a FACTOR x run that survives, why: the limits its final state breaks at rest, which a
run does not stop on (the end-effector hold, an input clipped at its saturation).
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np

from aerial_drake.analysis.onboarding.check_subject import load_subject
from aerial_drake.analysis.onboarding.loaded_rest import RestLoop
from aerial_drake.analysis.onboarding.margins import DIRECTIONS, direction_margins
from aerial_drake.analysis.onboarding.push_validation import simulate_push


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file", help="a scenario (path or shipped name) or NAME.robot.yaml")
    parser.add_argument("--scenario", help="the scenario of a robot description")
    parser.add_argument("--factor", type=float, default=1.3)
    parser.add_argument("--directions", nargs="*", default=[d[0] for d in DIRECTIONS],
                        help="some of +x -x +y -y +z -z")
    parser.add_argument("--json", type=Path, help="write the rows there too")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # the scenario's gain-design warning, said once by check
    subject = load_subject(Path(args.file), args.scenario)
    loop = RestLoop(subject)
    margins = {m.direction: m for m in direction_margins(loop, "vehicle push", sys.stderr)}
    H = subject.heading_axes
    rows = []
    for label, axis, sign in DIRECTIONS:
        if label not in args.directions:
            continue
        m = margins[label]
        u = sign * H[:, axis]
        predicted = float(np.linalg.norm(m.com_deflection))
        for factor in (1.0, args.factor):
            run = simulate_push(subject, factor * m.largest * u, loop)
            row = {"direction": label, "factor": factor, "F_max_N": m.largest,
                   "binding": m.binding, "predicted_com_deflection_m": predicted,
                   "predicted_ee_displacement_m": float(np.linalg.norm(m.ee_displacement)),
                   **run.to_json()}
            rows.append(row)
            outcome = "survived" if run.survived else f"FAILED ({run.cause}, t = " \
                f"{run.stopped_at:.2f} s)"
            print(f"{label} {factor:.2f} x {m.largest:.4g} N = {factor * m.largest:.4g} N: "
                  f"{outcome}; CoM {1000 * run.com_deflection_end:.1f} mm at the end, "
                  f"{1000 * run.com_deflection_max:.1f} mm max (predicted at F_max "
                  f"{1000 * predicted:.1f} mm); end effector {1000 * run.ee_error_max:.1f} mm "
                  f"max; sigma_min(J_3) >= {run.sigma_min_min:.3g}")
            if factor != 1.0 and run.survived:
                why = "; ".join(run.violated_at_end) or "no limit broken at its final state"
                print(f"    survived past F_max (binding: {m.binding}): at its end {why}")
            elif factor != 1.0:
                print(f"    {run.failure}")
            sys.stdout.flush()
    if args.json is not None:
        args.json.write_text(json.dumps(rows, indent=2, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
