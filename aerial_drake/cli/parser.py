"""The ``aerial-drake`` argument parser: every command, option, help text and default. Each
subcommand's ``func`` is the ``cmd_*`` function of its command module in
:mod:`aerial_drake.cli` (``run``, which hands ``run paper`` to ``paper``; ``compare``,
``plot``, ``info``, ``analyze``, ``study``), looked up when the parser is built."""

from __future__ import annotations

import argparse
from typing import Any

from aerial_drake.cli import analyze as analyze_command
from aerial_drake.cli import compare as compare_command
from aerial_drake.cli import info as info_command
from aerial_drake.cli import plot as plot_command
from aerial_drake.cli import robot as robot_command
from aerial_drake.cli import run as run_command
from aerial_drake.cli import study as study_command

# (The standard library only: importing it starts and compiles nothing.)
from aerial_drake.viz.live import WAIT_TIMEOUT_S


class _Defaults(argparse.ArgumentDefaultsHelpFormatter):
    """Shows each option's default, except for flags (False) and options without one."""

    def _get_help_string(self, action):
        if action.default is None or action.default is False or "(default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)


#: The help of ``--set`` (run, compare).
SET_HELP = ("set any scenario field, KEY a dotted name, VALUE read as YAML (e.g. --set "
            "gains.k_R=300 --set initial.base_position_offset=[0.1,0,0]); repeatable")


def build_parser() -> argparse.ArgumentParser:
    """The ``aerial-drake`` parser: one subcommand per command, each with ``func`` (its
    module's ``cmd_*``, which calls the library and prints)."""
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--debug", action="store_true",
                        help="print the traceback of an unexpected error")
    parser = argparse.ArgumentParser(
        prog="aerial-drake", parents=[common],
        description="Task-space tracking control for underactuated aerial manipulators, on Drake.")
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", parents=[common],
                         help="simulate a scenario and write log.npz and metrics.json")
    run.add_argument("scenario", help="shipped scenario name (e.g. nominal), a YAML file, or "
                     "'paper' (nominal and disturbed, and the paper's figures, in OUT/paper)")
    run.add_argument("--duration", type=float, default=None, help="override the duration (s)")
    run.add_argument("--set", dest="assignments", action="append", default=[],
                     metavar="KEY=VALUE", help=SET_HELP)
    run.add_argument("--out", default="out", help="output folder (default: ./out)")
    run.add_argument("--quiet", action="store_true", help="no progress line")
    run.add_argument("--json", action="store_true",
                     help="also print metrics.json (on failure: a JSON error object)")
    run.add_argument("--max-log-mb", type=float, default=None,
                     help="refuse a run whose estimated log exceeds this (MB; default: the "
                          "scenario's max_log_mb, 1000)")
    run.add_argument("--meshcat", action="store_true",
                     help="watch it live in a browser (prints the URL) and write replay.html")
    run.add_argument("--record", action="store_true",
                     help="write replay.html (a self-contained 3D replay) without watching")
    run.add_argument("--realtime-rate", type=float, default=None,
                     help="pace the simulation (1.0 = real time; default 1.0 with --meshcat, "
                          "else as fast as possible)")
    run.add_argument("--meshcat-host", default="localhost",
                     help="interface Meshcat listens on (default: localhost only; '*' = all)")
    run.add_argument("--meshcat-port", type=int, default=None,
                     help="Meshcat's port (default: the first free of 7000-7099; 0 = any "
                          "free port; a busy port is an error)")
    run.add_argument("--seed", type=int, default=None,
                     help="perturb the initial offsets by a reproducible uniform draw from "
                          "numpy.random.default_rng(SEED) (bounds: aerial_drake.studies.paper."
                          "SEED_BOUNDS); without it runs are deterministic")
    run.add_argument("--no-plots", action="store_true",
                     help="do not draw the run's Figs. 3-6 (PNG in the run's folder)")
    run.add_argument("--wait-compile", action="store_true",
                     help="on the first run after installing (numba's cache cold), compile "
                          "the control law first (about a minute) instead of running at once "
                          "on its reference implementation (equal to round-off, not to the "
                          "bit) and compiling in the background after it; 'run paper' and "
                          "runs longer than 30 s always do")
    run.add_argument("--no-wait", action="store_true",
                     help="with --meshcat: start the simulation at once, without waiting for a "
                          "browser to open the page")
    run.add_argument("--wait-timeout", type=float, default=WAIT_TIMEOUT_S,
                     help="with --meshcat: seconds to wait for a browser before starting "
                          f"anyway (default: {WAIT_TIMEOUT_S:g})")
    run.add_argument("--hold", action="store_true",
                     help="with --meshcat: keep serving the finished run (its replay under "
                          "Open Controls > Animations) until Ctrl-C")
    run.set_defaults(func=run_command.cmd_run)
    compare = sub.add_parser(
        "compare", parents=[common], help="run a scenario with several controllers; overlay "
        "figures and a metrics table (docs/baselines.md)")
    compare.add_argument("scenario", help="shipped scenario name or a YAML file")
    compare.add_argument("--controllers", default="paper,uncoupled,static_compensation",
                         help="comma-separated controller types (default: %(default)s)")
    compare.add_argument("--jobs", type=int, default=None,
                         help="parallel processes (default: one per controller, at most the "
                              "number of CPUs; 1 = one after the other, with progress)")
    compare.add_argument("--duration", type=float, default=None, help="override the duration")
    compare.add_argument("--set", dest="assignments", action="append", default=[],
                         metavar="KEY=VALUE", help=SET_HELP)
    compare.add_argument("--out", default="out", help="output folder; runs go to "
                         "OUT/compare/SCENARIO/CONTROLLER (default: ./out)")
    compare.add_argument("--quiet", action="store_true", help="no progress lines")
    compare.add_argument("--json", action="store_true", help="also print comparison.json")
    compare.add_argument("--undisturbed", action="store_true",
                         help="run the scenario without its disturbance windows (named "
                              "NAME_undisturbed): the reference for how far a disturbance "
                              "moves the end effector (tools/compare_displacement.py)")
    compare.set_defaults(func=compare_command.cmd_compare)
    plot = sub.add_parser(
        "plot", parents=[common], help="overlay runs: Figs. 3-5 of all, Fig. 6 of each",
        description="Draw Figs. 3-5 with every run overlaid (labelled by run name, each run's "
                    "reference dashed with its own legend entry) and Fig. 6 of each run, from "
                    "run folders written by 'aerial-drake run'.",
        formatter_class=_Defaults)
    plot.add_argument("run_dirs", nargs="+", metavar="RUN_DIR",
                      help="run folders (log.npz, metrics.json, scenario.yaml), e.g. out/nominal")
    plot.add_argument("--out", default="out/plots", help="where to write the figures")
    plot.add_argument("--formats", nargs="+", default=["png"], choices=["png", "pdf", "svg"],
                      help="file formats")
    plot.set_defaults(func=plot_command.cmd_plot)
    scenarios = sub.add_parser(
        "scenarios", parents=[common],
        help="list the shipped scenarios, or print one as YAML to edit",
        description="Without arguments: the shipped scenarios and what each is. 'show NAME': "
                    "the scenario's YAML file, comments included (save it, edit it, run it "
                    "with 'aerial-drake run FILE.yaml').")
    scenarios.add_argument("action", nargs="?", choices=["show"], default=None,
                           help="'show' prints the scenario NAME")
    scenarios.add_argument("name", nargs="?", default=None, help="a shipped scenario's name")
    scenarios.set_defaults(func=info_command.cmd_scenarios)
    info = sub.add_parser("info", parents=[common],
                          help="print a summary of the models and scenarios")
    info.set_defaults(func=info_command.cmd_info)
    analyze = sub.add_parser(
        "analyze", parents=[common], help="equilibria, linearisation, eigenvalues, "
        "controllability, Lyapunov function and region of attraction; writes analysis.json and "
        "plots (docs/analysis.md)",
        description="Stability analysis of a scenario's controller (docs/analysis.md): hover "
        "equilibria, Drake's Linearize of the closed loop and its eigenvalues against the "
        "predicted ones, controllability of the open loop, Lee et al.'s sufficient conditions "
        "on the Lyapunov constants, the Lyapunov function along a run and a sampled region of "
        "attraction. Writes analysis.json, eigenvalues.png, lyapunov.png and "
        "region_of_attraction.png to OUT and prints a report that explains each verdict.",
        formatter_class=_Defaults)
    analyze.add_argument("--out", default="out/analysis", help="output folder")
    analyze.add_argument("--scenario", default="nominal", help="scenario whose gains and "
                         "trajectory are analysed")
    analyze.add_argument("--fast", action="store_true", help="short runs and few samples (a "
                         "smoke test, not a result)")
    analyze.add_argument("--seed", type=int, default=0, help="seed of the region-of-attraction "
                         "draws")
    analyze.add_argument("--quiet", action="store_true", help="no progress lines")
    analyze.set_defaults(func=analyze_command.cmd_analyze)
    _add_study_parsers(sub, common)
    _add_robot_parsers(sub, common)
    return parser


def _add_study_parsers(sub: Any, common: argparse.ArgumentParser) -> None:
    """Add ``study`` and ``study-plot`` to the command line's subparsers."""
    study = sub.add_parser(
        "study", parents=[common], help="run a study (parameter grid, Monte Carlo draws) on "
        "Dask; one row per run in OUT/results.csv (docs/studies.md)",
        description="Run a study file's runs on a local Dask cluster (default: one worker "
        "process per CPU) or on an existing cluster (--scheduler). Rows are written as runs "
        "finish; run the same command again to resume an interrupted study (of the same "
        "spec: a changed one is refused, docs/studies.md).")
    study.add_argument("file", help="a shipped study's name ("
                       f"{', '.join(study_command.shipped_study_names())}) or a study YAML "
                       "file")
    study.add_argument("--workers", type=int, default=None,
                       help="worker processes of the local cluster (default: one per CPU)")
    study.add_argument("--scheduler", default=None,
                       help="address of an existing Dask scheduler (e.g. tcp://host:8786)")
    study.add_argument("--out", default=None,
                       help="output folder (default: out/studies/NAME)")
    study.add_argument("--duration", type=float, default=None,
                       help="override every run's duration (s)")
    study.add_argument("--draws", type=int, default=None, help="override the number of draws")
    study.add_argument("--show-run", default=None, metavar="RUN",
                       help="print the scenario of one run (its run_id or index in the "
                            "table) as YAML, to reproduce it with 'aerial-drake run FILE.yaml'; "
                            "runs nothing")
    study.add_argument("--restart", action="store_true",
                       help="discard the folder's results.csv and provenance.json and run "
                       "the study from the start (e.g. after changing its spec)")
    study.add_argument("--quiet", action="store_true", help="no progress bar")
    study.add_argument("--json", action="store_true", help="also print a JSON summary")
    study.set_defaults(func=study_command.cmd_study)
    plot = sub.add_parser(
        "study-plot", parents=[common], help="histograms, box plots per phase and maps of a "
        "study's results table")
    plot.add_argument("table", help="a study's results.csv")
    plot.add_argument("--out", default=None, help="where to write (default: TABLE's folder/"
                      "plots)")
    plot.add_argument("--formats", nargs="+", default=["png", "svg"], choices=["png", "svg",
                                                                                "pdf"])
    plot.set_defaults(func=study_command.cmd_study_plot)


def _add_robot_parsers(sub: Any, common: argparse.ArgumentParser) -> None:
    """Add ``robot init`` and ``robot check`` (docs/robots.md, "From a URDF to a flying
    scenario")."""
    robot = sub.add_parser(
        "robot", parents=[common], help="onboard a robot of your own: 'robot init MODEL' writes "
        "a robot description and a hover scenario; 'robot check FILE' prints its margins",
        description="'robot init MODEL.urdf|sdf' finds the vehicle, the arm and the end "
        "effector, chooses a nominal posture, computes the CoM offset, the locked inertia, "
        "input limits and gains, and writes NAME.robot.yaml and NAME_hover.yaml, which run as "
        "written. 'robot check FILE' prints the margins at the nominal posture (docs/robots.md).")
    actions = robot.add_subparsers(dest="robot_command", required=True)
    init = actions.add_parser(
        "init", parents=[common], formatter_class=_Defaults,
        help="write NAME.robot.yaml and NAME_hover.yaml from a URDF or SDF model")
    init.add_argument("model", help="the model file (.urdf or .sdf): a free vehicle body and a "
                      "serial arm of actuated revolute joints below it")
    init.add_argument("--vehicle", default=None, help="the vehicle's body (default: the free "
                      "body the arm hangs from; asked for when the model has several)")
    init.add_argument("--end-effector", default=None, metavar="FRAME",
                      help="the end-effector frame or body (default: the tip of the arm's "
                      "chain; the candidates are listed)")
    init.add_argument("--name", default=None, help="the robot's name (default: the model's)")
    init.add_argument("--out", default=None, help="where to write (default: the model's "
                      "folder)")
    init.add_argument("--thrust-to-weight", type=float, default=2.0,
                      help="the vehicle's maximum thrust over the whole robot's weight")
    init.add_argument("--body-torque", nargs=3, default=None, metavar=("X", "Y", "Z"),
                      help="body torque bounds (N m; default: from the vehicle's size and "
                      "the thrust, docs/robots.md)")
    init.add_argument("--tool-axis", default="z", choices=["x", "y", "z", "-x", "-y", "-z"],
                      help="the end-effector frame's axis that --tool-direction points")
    init.add_argument("--tool-direction", default="any", help="where the tool axis points at "
                      "the nominal posture: down, forward, any, or a World vector 'x,y,z'")
    init.add_argument("--task", default=None, help="the task's components, comma-separated "
                      "(default: the pose, with joint components for arms of other than 6 "
                      "joints, docs/robots.md)")
    init.add_argument("--force", action="store_true", help="overwrite existing files")
    init.add_argument("--quiet", action="store_true", help="no progress lines")
    init.add_argument("--json", action="store_true", help="also print the result as JSON")
    init.set_defaults(func=robot_command.cmd_robot_init)
    check = actions.add_parser(
        "check", parents=[common], formatter_class=_Defaults,
        help="the margins at the nominal posture: Assumption 1, reach, pushes, wrench, roots")
    check.add_argument("file", help="a robot description (NAME.robot.yaml; its gains from "
                       "NAME_hover.yaml beside it) or a scenario YAML")
    check.add_argument("--scenario", default=None, help="the scenario whose gains and hover "
                       "are checked (default: NAME_hover.yaml beside the description)")
    check.add_argument("--quiet", action="store_true", help="no progress lines")
    check.add_argument("--json", action="store_true", help="also print the report as JSON")
    check.set_defaults(func=robot_command.cmd_robot_check)
