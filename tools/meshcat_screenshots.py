"""Screenshots of the live Meshcat view of a run at chosen times, for the README.

    python tools/meshcat_screenshots.py [SCENARIO] [--times 0 4.5 9.5] [--out docs/img]

Runs SCENARIO (default: ``disturbed``, the spinning-rotor plant) with the Meshcat view of
``aerial_drake.viz.meshcat_view``; at each time the simulation pauses while headless Chromium
(``aerial_drake.viz.screenshot``) photographs the live page, as a browser would show it then.
Writes ``<out>/meshcat_<scenario>_<t>s.png``. Needs Chromium (Debian: apt-get install chromium).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from pydrake.systems.framework import EventStatus, LeafSystem

from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.viz.meshcat_view import PUBLISH_PERIOD, MeshcatView
from aerial_drake.viz.screenshot import colourful_fraction, screenshot

#: The snapshot system checks the times on this grid (s); a multiple of the 1 ms steps.
TICK = PUBLISH_PERIOD  # shots fall on the overlay's frames


class Snapshots(LeafSystem):
    """At each of ``times`` (multiples of TICK), photograph ``url``. Added after the
    visualizers, so Drake publishes it after they have sent that instant's frame."""

    def __init__(self, url: str, times: list[float], out: Path, stem: str, size):
        super().__init__()
        self._url, self._out, self._stem, self._size = url, out, stem, size
        self._pending = sorted(round(t / TICK) for t in times)
        self.written: list[Path] = []
        self.DeclarePeriodicPublishEvent(TICK, 0.0, self._publish)

    def _publish(self, context) -> EventStatus:
        tick = round(context.get_time() / TICK)
        if self._pending and tick == self._pending[0]:
            self._pending.pop(0)
            t = tick * TICK
            png = self._out / f"{self._stem}_{t:g}s.png"
            screenshot(self._url, png, size=self._size, wait=5.0)
            print(f"  t = {t:g} s: wrote {png} ({100 * colourful_fraction(png):.1f} % "
                  "coloured pixels)", flush=True)
            self.written.append(png)
        return EventStatus.Succeeded()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario", nargs="?", default=None,
                        help="scenario name or YAML (default: disturbed)")
    parser.add_argument("--times", type=float, nargs="+", default=[0.0, 4.5, 9.5])
    parser.add_argument("--out", default="docs/img")
    parser.add_argument("--size", type=int, nargs=2, default=[960, 640])
    args = parser.parse_args(argv)

    name, overrides = args.scenario or "disturbed", {}
    scenario = load_scenario(name, overrides=overrides)
    overrides["duration"] = min(scenario.duration, max(args.times) + 0.5)
    # The paths and the camera cover the whole scenario, the run stops after the last shot.
    view = MeshcatView(scenario, port=0)
    scenario = load_scenario(name, overrides=overrides)
    print(f"Meshcat at {view.url}; running '{scenario.name}' to {scenario.duration:g} s")
    out = Path(args.out)
    snapshots = Snapshots(view.url, args.times, out, f"meshcat_{scenario.name}",
                          tuple(args.size))

    def configure(builder, loop):
        view.configure(builder, loop)
        builder.AddSystem(snapshots).set_name("snapshots")

    with tempfile.TemporaryDirectory() as tmp:
        run_scenario(scenario, out_dir=tmp, progress=True, configure=configure)
    return 0 if len(snapshots.written) == len(args.times) else 1


if __name__ == "__main__":
    sys.exit(main())
