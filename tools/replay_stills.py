"""Stills of a run's recorded replay (``replay.html``) at chosen times, for the docs.

    python tools/replay_stills.py SCENARIO [--times 6.0] [--out docs/img]
        [--camera X Y Z --target X Y Z] [--replay-out DIR]

Runs SCENARIO (a shipped name or a YAML path) recorded with the Meshcat view of
``aerial_drake.viz.meshcat_view`` (as ``aerial-drake run SCENARIO --record``), then opens its
``replay.html`` from ``file://`` in headless Chromium (``aerial_drake.viz.screenshot``), stops
the animation at each time and photographs it: what a reader of the replay sees. Writes
``<out>/replay_<scenario>_<t>s.png``. ``--camera``/``--target`` (World, m) replace the view's
camera (``aerial_drake.viz.camera.camera_for``), e.g. to look from the robot's side of a wall.
The run stops 0.1 s after the last time. Needs Chromium (Debian: apt-get install chromium).

The wall press of docs/contact.md (docs/img/replay_wall_press_6s.png):

    python tools/replay_stills.py wall_press --times 6.0 \
        --camera 0.1 -1.7 1.15 --target 0.75 0 1.45
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.viz.meshcat_view import PUBLISH_PERIOD, REPLAY_FILE, MeshcatView
from aerial_drake.viz.screenshot import colourful_fraction, replay_time_script, screenshot


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario", help="scenario name or YAML")
    parser.add_argument("--times", type=float, nargs="+", default=[4.5])
    parser.add_argument("--out", default="docs/img")
    parser.add_argument("--size", type=int, nargs=2, default=[960, 640])
    parser.add_argument("--camera", type=float, nargs=3, default=None)
    parser.add_argument("--target", type=float, nargs=3, default=None)
    parser.add_argument("--replay-out", default=None,
                        help="keep the run's folder (log, replay.html) here")
    args = parser.parse_args(argv)
    if (args.camera is None) != (args.target is None):
        parser.error("--camera and --target go together")

    scenario = load_scenario(args.scenario)
    # Whole frames; the run ends a little after the last still.
    duration = min(scenario.duration, max(args.times) + 0.1)
    scenario = load_scenario(args.scenario, overrides={
        "duration": round(duration / PUBLISH_PERIOD) * PUBLISH_PERIOD})
    view = MeshcatView(scenario, port=0, live=False)

    def configure(builder, loop):
        view.configure(builder, loop)
        if args.camera is not None:
            view.meshcat.SetCameraPose(np.array(args.camera), np.array(args.target))

    out = Path(args.out)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.replay_out or tmp)
        result = run_scenario(scenario, out_dir=folder, progress=True, configure=configure,
                              extra_files=view.finish)
        replay = result.out_dir / REPLAY_FILE
        print(f"recorded {replay}")
        for t in args.times:
            png = out / f"replay_{scenario.name}_{t:g}s.png"
            screenshot(replay.resolve().as_uri(), png, size=tuple(args.size), wait=6.0,
                       script=replay_time_script(t))
            print(f"  t = {t:g} s: wrote {png} ({100 * colourful_fraction(png):.1f} % "
                  "coloured pixels)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
