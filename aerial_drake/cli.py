"""Command line: ``aerial-drake run SCENARIO``, ``aerial-drake compare SCENARIO``,
``aerial-drake info``, ``aerial-drake analyze``.

``SCENARIO`` is a shipped scenario name (``nominal``) or a path to a YAML file.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

from aerial_drake.studies.reporting import report_error


def _cmd_info(args: argparse.Namespace) -> int:
    from aerial_drake.robots.models import PLANT_VARIANTS, make_plant
    from aerial_drake.simulation.scenarios import shipped_scenarios

    for variant in PLANT_VARIANTS:
        manip = make_plant(variant)
        plant = manip.plant
        ctx = plant.CreateDefaultContext()
        print(f"plant variant '{variant}': {plant.num_bodies() - 1} bodies, "
              f"{plant.num_positions()} positions, {plant.num_velocities()} velocities, "
              f"{plant.num_actuators()} actuators, total mass "
              f"{plant.CalcTotalMass(ctx):.3f} kg")
        I = manip.base_body.CalcSpatialInertiaInBodyFrame(ctx).CalcRotationalInertia()
        print(f"  base body '{manip.base_body.name()}': mass "
              f"{manip.base_body.get_mass(ctx):.3f} kg, inertia diag "
              f"{np.round(np.diag(I.CopyToFullMatrix3()), 4).tolist()} kg m^2")
        print(f"  arm joints: {[j.name() for j in manip.arm_joints]}")
        print(f"  arm effort limits (N m): {manip.arm_effort_limits().tolist()}")
        if manip.rotor_joints:
            print(f"  rotor joints: {[j.name() for j in manip.rotor_joints]}")
    print(f"shipped scenarios: {sorted(shipped_scenarios())}")
    return 0


def _print_summary(result) -> None:
    m = result.metrics
    print(f"scenario '{m['scenario']}': simulated {m['simulated_time_s']:.2f} s in "
          f"{m['wall_time_s']:.2f} s wall (real-time factor {m['real_time_factor']:.1f}x)")
    header = f"{'phase (s)':>14} {'EE pos max (mm)':>16} {'EE rot max (mrad)':>18} " \
             f"{'CoM max (mm)':>13} {'base att max (mrad)':>20}"
    print(header)
    for p in m["phases"]:
        if p["samples"] == 0:
            continue
        print(f"{p['start_s']:6.1f}-{p['end_s']:<6.1f} "
              f"{1e3 * p['ee_position_error_m']['max']:16.3f} "
              f"{1e3 * p['ee_orientation_error_rad']['max']:18.3f} "
              f"{1e3 * p['com_position_error_m']['max']:13.3f} "
              f"{1e3 * p['base_attitude_error_rad']['max']:20.3f}")
    print(f"min sigma_min(J3) = {m['min_sigma_min_J3']:.4f}, min |f_d| = "
          f"{m['min_f_d_norm_N']:.1f} N")
    sat = {k: v for k, v in m["saturated_s_total"].items() if v > 0}
    print(f"saturated time (s): {sat if sat else 'none'}")
    if result.out_dir is not None:
        print(f"wrote {result.out_dir / 'log.npz'} and {result.out_dir / 'metrics.json'}")


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
    if args.realtime_rate is not None and not 0 <= args.realtime_rate <= 1000:
        raise ScenarioError(f"--realtime-rate must be >= 0 and <= 1000 (1 = real time); got "
                            f"{args.realtime_rate}", "--realtime-rate")
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
            view = MeshcatView(scenario, live=args.meshcat, host=args.meshcat_host, port=port)
        except (MeshcatPortInUse, ValueError) as err:
            return report_error(args, 2, err)
        if args.meshcat:
            print(f"Meshcat: open {view.url} in a browser")
    realtime = args.realtime_rate
    if realtime is None and args.meshcat:
        realtime = 1.0
    print(f"running scenario '{scenario.name}' ({scenario.duration:g} s) -> {out}", flush=True)
    try:
        result = run_scenario(scenario, out_dir=out, progress=not args.quiet,
                              configure=view.configure if view else None,
                              realtime_rate=realtime)
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
        return report_error(args, 1, err, f"logs up to the failure are in {out}")
    except Interrupted as err:  # before the simulation started (building the model)
        return report_error(args, err.exit_status, f"interrupted ({err}) before the "
                            "simulation; nothing written")
    finally:
        if view is not None:
            print(f"wrote {view.finish(out)}", file=sys.stderr)
    _print_summary(result)
    if args.json:
        from aerial_drake.simulation.outputs import strict_json
        print(strict_json(result.metrics))
    return 0


def _cmd_compare(args: argparse.Namespace) -> int:
    _compile_first(args)
    from aerial_drake.studies.compare import cli_compare
    return cli_compare(args)


def _cmd_analyze(args: argparse.Namespace) -> int:
    from aerial_drake.analysis import cli_analyze
    return cli_analyze(args)


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
    info = sub.add_parser("info", parents=[common],
                          help="print a summary of the models and scenarios")
    info.set_defaults(func=_cmd_info)
    analyze = sub.add_parser(
        "analyze", parents=[common], help="equilibria, linearisation, eigenvalues, "
        "controllability, Lyapunov function and region of attraction; writes analysis.json "
        "and plots (docs/analysis.md)")
    analyze.add_argument("--out", default="out/analysis", help="output folder")
    analyze.add_argument("--scenario", default="nominal", help="scenario whose gains and "
                         "trajectory are analysed (default: nominal)")
    analyze.add_argument("--fast", action="store_true", help="short runs (a smoke test)")
    analyze.add_argument("--seed", type=int, default=0, help="region-of-attraction draws")
    analyze.add_argument("--quiet", action="store_true", help="no progress lines")
    analyze.set_defaults(func=_cmd_analyze)
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
        print(f"interrupted ({str(err) or 'Ctrl-C'}) outside the simulation; nothing more "
              "written", file=sys.stderr)
        return exit_status_of(err)
    except Exception as err:  # a bug, or a fault not foreseen: one line unless --debug
        if args.debug:
            raise
        return report_error(args, 1, f"unexpected {type(err).__name__}: {err} (rerun with "
                            "--debug for the traceback, and please report it)")


if __name__ == "__main__":
    sys.exit(main())
