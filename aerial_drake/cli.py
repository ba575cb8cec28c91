"""Command line: ``aerial-drake run SCENARIO``, ``plot RUN_DIR ...``, ``scenarios [show NAME]``,
``compare SCENARIO``, ``info``, ``analyze``, ``study FILE`` and ``study-plot TABLE``.

``SCENARIO`` is a shipped scenario name (``nominal``) or a path to a YAML file.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import TextIO

import numpy as np

from aerial_drake.studies.cli_study import add_study_parsers
from aerial_drake.studies.reporting import report_error

# (The standard library only: importing it starts and compiles nothing.)
from aerial_drake.viz.live import WAIT_TIMEOUT_S


def _cmd_info(args: argparse.Namespace) -> int:
    from aerial_drake.robots.description import load_robot_description, shipped_robots
    from aerial_drake.robots.models import make_plant
    from aerial_drake.simulation.scenarios import shipped_scenarios

    for name in shipped_robots():
        robot = load_robot_description(name)
        print(f"robot '{name}': task {list(robot.task)}")
        for variant in robot.variant_names():
            _print_variant(make_plant(variant, robot=robot), variant)
    print(f"shipped scenarios: {sorted(shipped_scenarios())}")
    return 0


def _print_variant(manip, variant: str) -> None:
    """One plant variant's sizes, mass and joints (``aerial-drake info``)."""
    plant = manip.plant
    ctx = plant.CreateDefaultContext()
    print(f"  plant variant '{variant}': {plant.num_bodies() - 1} bodies, "
          f"{plant.num_positions()} positions, {plant.num_velocities()} velocities, "
          f"{plant.num_actuators()} actuators, total mass "
          f"{plant.CalcTotalMass(ctx):.3f} kg")
    I = manip.base_body.CalcSpatialInertiaInBodyFrame(ctx).CalcRotationalInertia()
    print(f"    vehicle body '{manip.base_body.name()}': mass "
          f"{manip.base_body.get_mass(ctx):.3f} kg, inertia diag "
          f"{np.round(np.diag(I.CopyToFullMatrix3()), 4).tolist()} kg m^2")
    print(f"    arm joints: {[j.name() for j in manip.arm_joints]}")
    print(f"    arm effort limits (N m): {manip.arm_effort_limits().tolist()}")
    if manip.rotor_joints:
        print(f"    rotor joints: {[j.name() for j in manip.rotor_joints]}")


def _table(header: list[str], rows: list[list[str]]) -> str:
    """Columns right-aligned under ``header`` (the first column left-aligned)."""
    widths = [max(len(r[k]) for r in [header, *rows]) for k in range(len(header))]
    lines = ["  ".join(c.ljust(w) if k == 0 else c.rjust(w)
                       for k, (c, w) in enumerate(zip(row, widths))).rstrip()
             for row in [header, *rows]]
    return "\n".join(lines)


def format_summary(m: dict) -> str:
    """One run's metrics as text: the run, the largest errors per phase, the assumptions'
    margins and the saturated time per input, as tables at meaningful precision."""
    lines = [f"scenario '{m['scenario']}': simulated {m['simulated_time_s']:.2f} s in "
             f"{m['wall_time_s']:.2f} s wall (real-time factor {m['real_time_factor']:.1f}x)"]
    rows = [[f"{p['start_s']:g}-{p['end_s']:g}",
             f"{1e3 * p['ee_position_error_m']['max']:.3f}",
             f"{1e3 * p['ee_orientation_error_rad']['max']:.3f}",
             f"{1e3 * p['com_position_error_m']['max']:.3f}",
             f"{1e3 * p['base_attitude_error_rad']['max']:.3f}"]
            for p in m["phases"] if p["samples"] > 0]
    lines.append(_table(["phase (s)", "EE pos max (mm)", "EE rot max (mrad)", "CoM max (mm)",
                         "base att max (mrad)"], rows))
    lines.append(f"min sigma_min(J_3) = {m['min_sigma_min_J3']:.4f} (Assumption 1: > 0); "
                 f"min |f_d| = {m['min_f_d_norm_N']:.1f} N (Assumption 2: > 0)")
    late = next((k for k in m if k.startswith("saturated_s_after")), None)
    sat = [k for k, v in m["saturated_s_total"].items() if v > 0]
    if not sat:
        lines.append("saturated time: none (no input reached a limit)")
    else:
        after = late.removeprefix("saturated_s_after_") if late else ""
        header = ["input at a limit", "whole run (s)"] + ([f"after {after} (s)"] if late else [])
        lines.append(_table(header, [
            [k, f"{m['saturated_s_total'][k]:.3f}"] + ([f"{m[late][k]:.3f}"] if late else [])
            for k in sat]))
    return "\n".join(lines)


def _say(args: argparse.Namespace) -> TextIO:
    """Where the human-readable lines go: stdout, or stderr with --json (stdout then holds the
    JSON alone)."""
    return sys.stderr if getattr(args, "json", False) else sys.stdout


def _print_summary(result, stream: TextIO) -> None:
    print(format_summary(result.metrics), file=stream)
    if result.out_dir is not None:
        print(f"wrote {result.out_dir / 'log.npz'} and {result.out_dir / 'metrics.json'}",
              file=stream)


def _write_run_figures(out: Path, args: argparse.Namespace) -> None:
    """The run's own Figs. 3-6 into its folder (after the metrics are written: they are
    drawn from the files, so they cannot change them). Matplotlib is imported only here."""
    if args.no_plots or not (out / "log.npz").is_file():
        return
    from aerial_drake.viz.run_plots import write_run_figures
    written = write_run_figures(out)
    print(f"wrote {len(written)} figures ({', '.join(p.name for p in written)}) in {out}",
          file=_say(args))


# Set in the restarted process, so that it never restarts again.
_RESTARTED = "AERIAL_DRAKE_RESTARTED_AFTER_COMPILE"


def _compile_first(args: argparse.Namespace) -> None:
    """On the first run after installing, compile the numba kernels, then restart the command.

    numba keeps what compiling the control law allocated (about 200 MB) for the rest of the
    process: compiled in the middle of a run, it stays under everything the run allocates
    after it, and that first run peaked near 600 MB against 300-400 MB for every later one
    (docs/performance.md, Memory). So the command compiles first, before the run builds
    anything, and re-executes itself exactly as it was started (``sys.orig_argv``: the same
    script or ``-m``, so the same installed package and cache; same process id); the run
    proper then loads the cached machine code like any later run. Nothing to do when the
    cache is warm, when :func:`main` was called from Python with arguments (never replace a
    caller's process), or off POSIX; if the cache could not be written, the run goes on here."""
    if not args.restartable or os.environ.get(_RESTARTED) or os.name != "posix":
        return
    from aerial_drake.control.compiled import law_cache_is_cold
    from aerial_drake.simulation.runner import compile_kernels
    if not law_cache_is_cold():
        return
    compile_kernels()  # says on stderr that it compiles
    if law_cache_is_cold():
        return
    print("aerial_drake: compiled and cached; restarting the command to run with the cached "
          "code", file=sys.stderr, flush=True)
    sys.stdout.flush()
    os.environ[_RESTARTED] = "1"
    os.execv(sys.executable, [sys.executable, *sys.orig_argv[1:]])


def check_options(args: argparse.Namespace) -> dict:
    """The run options as scenario overrides, after the checks argparse cannot make; raises
    ScenarioError naming the option."""
    from aerial_drake.simulation.scenarios import ScenarioError

    overrides: dict = {}
    if args.duration is not None:
        overrides["duration"] = args.duration
    if args.max_log_mb is not None:
        overrides["max_log_mb"] = args.max_log_mb
    if args.realtime_rate is not None:  # the range of simulator.target_realtime_rate
        from aerial_drake.simulation.scenarios.checks import REALTIME, number
        number("--realtime-rate", args.realtime_rate, REALTIME)
    if args.meshcat_port is not None and not 0 <= args.meshcat_port <= 65535:
        raise ScenarioError(f"--meshcat-port must be a port number, 0 to 65535; got "
                            f"{args.meshcat_port}", "--meshcat-port")
    if args.seed is not None and args.seed < 0:
        raise ScenarioError(f"--seed must be >= 0; got {args.seed}", "--seed")
    if not str(args.out).strip():
        raise ScenarioError("--out must name a folder; got ''", "--out")
    return overrides


def _option_note(err, overrides: dict) -> str:
    """Which command-line option set the field an error names, if one did."""
    field = getattr(err, "field", None)
    if isinstance(field, str) and field in overrides:
        return f" (set by --{field.replace('_', '-')})"
    return ""


def _cmd_run(args: argparse.Namespace) -> int:
    from aerial_drake.dynamics.equilibrium import UnreachablePose
    from aerial_drake.simulation.interrupts import Interrupted
    from aerial_drake.simulation.outputs import OutputError, ResultsNotWritten
    from aerial_drake.simulation.runner import SimulationFailed, SimulationInterrupted, run_scenario
    from aerial_drake.simulation.scenarios import ScenarioError, load_scenario

    try:
        overrides = check_options(args)
    except ScenarioError as err:
        return report_error(args, 2, err)
    if (args.no_wait or args.hold or args.wait_timeout != WAIT_TIMEOUT_S) and not args.meshcat:
        return report_error(args, 2, "--no-wait, --wait-timeout and --hold are for the live "
                            "view; add --meshcat")
    # Both of Section IV's runs and Figs. 3-6 (aerial_drake.studies.paper).
    if args.scenario == "paper":
        if args.meshcat or args.record or args.realtime_rate is not None:
            return report_error(args, 2, "--meshcat, --record and --realtime-rate watch one "
                                "scenario; use 'aerial-drake run nominal --meshcat' or 'run "
                                "disturbed --meshcat'")
        _compile_first(args)  # before importing matplotlib (the peak is the compile's)
        from aerial_drake.studies.paper import cli_run
        return cli_run(args, overrides)
    try:
        scenario = load_scenario(args.scenario, overrides=overrides)
        if args.seed is not None:
            from aerial_drake.studies.paper import perturb_initial
            scenario = perturb_initial(scenario, args.seed)
    except ScenarioError as err:
        return report_error(args, 2, ScenarioError(f"{err}{_option_note(err, overrides)}",
                                                   err.field))
    _compile_first(args)  # after the scenario's checks, before Meshcat starts
    out = Path(args.out) / scenario.folder_name
    view = None
    if args.meshcat or args.record:  # aerial_drake.viz.meshcat_view
        from aerial_drake.viz.meshcat_view import MeshcatPortInUse, MeshcatView
        try:
            port = args.meshcat_port
            if port is None and not args.meshcat:
                port = 0  # recording only: leave 7000-7099 to live views
            from aerial_drake.viz.live import quiet_drake_info
            with quiet_drake_info():  # Drake's own "listening at URL": printed once, below
                view = MeshcatView(scenario, live=args.meshcat, host=args.meshcat_host,
                                   port=port)
        except (MeshcatPortInUse, ValueError) as err:
            return report_error(args, 2, err)
        if args.meshcat:
            print(f"Meshcat: open {view.url} in a browser", file=_say(args), flush=True)
    before_start = None
    if view is not None and args.meshcat and not args.no_wait:
        from aerial_drake.viz.live import wait_for_browser

        def before_start():
            wait_for_browser(view.meshcat, timeout=args.wait_timeout, stream=sys.stderr)
    realtime = args.realtime_rate
    if realtime is None and args.meshcat:
        realtime = 1.0
    print(f"running scenario '{scenario.name}' ({scenario.duration:g} s) -> {out}",
          file=_say(args), flush=True)
    try:
        # The replay is written with the run's files, inside the folder's lock: never into a
        # folder the run was refused, nor after a stop before the simulation.
        result = run_scenario(scenario, out_dir=out, progress=not args.quiet,
                              configure=view.configure if view else None,
                              realtime_rate=realtime, before_start=before_start,
                              extra_files=view.finish if view else None)
    except (ScenarioError, UnreachablePose) as err:  # found before the simulation starts
        return report_error(args, 2, err)
    except ResultsNotWritten as err:
        return report_error(args, 3, err)
    except OutputError as err:  # the folder, checked before the simulation starts
        return report_error(args, 2, err)
    except SimulationInterrupted as err:
        return report_error(args, err.exit_status, err,
                            f"logs up to the interruption are in {out}")
    except SimulationFailed as err:
        _write_run_figures(out, args)  # the figures of the log up to the failure
        return report_error(args, 1, err, f"logs up to the failure are in {out}")
    except Interrupted as err:  # before the simulation started (building the model)
        return report_error(args, err.exit_status, f"interrupted ({err}) before the "
                            "simulation; nothing written")
    _print_summary(result, _say(args))
    if args.json:  # metrics.json as written; before the figures, which cannot lose it
        print((out / "metrics.json").read_text(), flush=True)
    _write_run_figures(out, args)
    if view is not None and args.meshcat and args.hold:
        from aerial_drake.viz.live import hold
        hold(view.meshcat, stream=sys.stderr)
    return 0


def _cmd_plot(args: argparse.Namespace) -> int:
    from aerial_drake.viz.run_plots import write_overlay
    try:
        written = write_overlay(args.run_dirs, args.out, formats=tuple(args.formats))
    except (FileNotFoundError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    for path in written:
        print(f"wrote {path}")
    return 0


def _first_line(text: str) -> str:
    """The first sentence of a description, on one line."""
    flat = " ".join(text.split())
    end = flat.find(": ")
    return flat if end < 0 else flat[:end]


def _cmd_scenarios(args: argparse.Namespace) -> int:
    from aerial_drake.simulation.scenarios import ScenarioError, load_scenario, shipped_scenarios
    shipped = shipped_scenarios()
    if args.action is None:
        width = max(len(n) for n in shipped)
        for name in shipped:
            sc = load_scenario(name)
            print(f"{name:<{width}}  {_first_line(sc.description)} ({sc.plant_variant} plant, "
                  f"{sc.duration:g} s, {len(sc.disturbances)} disturbance windows)")
        print("\n'aerial-drake scenarios show NAME > my.yaml' prints one to edit; "
              "'aerial-drake run my.yaml' runs it.")
        return 0
    if args.name is None:
        return report_error(args, 2, "'scenarios show' needs a NAME; shipped scenarios: "
                            f"{sorted(shipped)}")
    if args.name not in shipped:
        return report_error(args, 2, f"no shipped scenario '{args.name}'. Valid names are: "
                            f"{sorted(shipped)}")
    try:
        load_scenario(args.name)  # the shipped file as shipped: it loads
    except ScenarioError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    # The file itself, comments (units, sources) included: ready to save and edit.
    sys.stdout.write(shipped[args.name].read_text())
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    from aerial_drake.simulation.scenarios import ScenarioError, load_scenario
    try:  # a misspelt scenario fails at once, not after the first-run compile
        load_scenario(args.scenario)
    except ScenarioError as err:
        return report_error(args, 2, err)
    _compile_first(args)
    from aerial_drake.studies.compare import cli_compare
    return cli_compare(args)


def _cmd_analyze(args: argparse.Namespace) -> int:
    from aerial_drake.analysis import cli_analyze
    return cli_analyze(args)


class _Defaults(argparse.ArgumentDefaultsHelpFormatter):
    """Shows each option's default, except for flags (False) and options without one."""

    def _get_help_string(self, action):
        if action.default is None or action.default is False or "(default" in (action.help or ""):
            return action.help
        return super()._get_help_string(action)


def build_parser() -> argparse.ArgumentParser:
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
    run.add_argument("--no-wait", action="store_true",
                     help="with --meshcat: start the simulation at once, without waiting for a "
                          "browser to open the page")
    run.add_argument("--wait-timeout", type=float, default=WAIT_TIMEOUT_S,
                     help="with --meshcat: seconds to wait for a browser before starting "
                          f"anyway (default: {WAIT_TIMEOUT_S:g})")
    run.add_argument("--hold", action="store_true",
                     help="with --meshcat: keep serving the finished run (its replay under "
                          "Open Controls > Animations) until Ctrl-C")
    run.set_defaults(func=_cmd_run)
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
    compare.add_argument("--out", default="out", help="output folder; runs go to "
                         "OUT/compare/SCENARIO/CONTROLLER (default: ./out)")
    compare.add_argument("--quiet", action="store_true", help="no progress lines")
    compare.add_argument("--json", action="store_true", help="also print comparison.json")
    compare.add_argument("--undisturbed", action="store_true",
                         help="run the scenario without its disturbance windows (named "
                              "NAME_undisturbed): the reference for how far a disturbance "
                              "moves the end effector (tools/compare_displacement.py)")
    compare.set_defaults(func=_cmd_compare)
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
    plot.set_defaults(func=_cmd_plot)
    scenarios = sub.add_parser(
        "scenarios", parents=[common],
        help="list the shipped scenarios, or print one as YAML to edit",
        description="Without arguments: the shipped scenarios and what each is. 'show NAME': "
                    "the scenario's YAML file, comments included (save it, edit it, run it "
                    "with 'aerial-drake run FILE.yaml').")
    scenarios.add_argument("action", nargs="?", choices=["show"], default=None,
                           help="'show' prints the scenario NAME")
    scenarios.add_argument("name", nargs="?", default=None, help="a shipped scenario's name")
    scenarios.set_defaults(func=_cmd_scenarios)
    info = sub.add_parser("info", parents=[common],
                          help="print a summary of the models and scenarios")
    info.set_defaults(func=_cmd_info)
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
    analyze.set_defaults(func=_cmd_analyze)
    add_study_parsers(sub, common)  # study, study-plot (aerial_drake.studies.cli_study)
    return parser


def main(argv: list[str] | None = None) -> int:
    from aerial_drake.simulation.interrupts import exit_status_of, handling

    args = build_parser().parse_args(argv)
    # Run as a program (its arguments from the command line): _compile_first may restart it.
    args.restartable = argv is None
    try:
        with handling():  # SIGINT, SIGTERM, SIGHUP: aerial_drake.simulation.interrupts
            return args.func(args)
    except KeyboardInterrupt as err:
        # One in the simulation is handled by the runner (logs written, exit 128 + signal);
        # this is one before it started (loading, compiling, solving the initial pose).
        return report_error(args, exit_status_of(err), f"interrupted ({str(err) or 'Ctrl-C'}) "
                            "outside the simulation; nothing more written")
    except Exception as err:  # a bug, or a fault not foreseen: one line unless --debug
        if args.debug:
            raise
        return report_error(args, 1, f"unexpected {type(err).__name__}: {err} (rerun with "
                            "--debug for the traceback, and please report it)")


if __name__ == "__main__":
    sys.exit(main())
