"""``aerial-drake run SCENARIO``: one scenario (:func:`aerial_drake.simulation.runner.
run_scenario`), watched live or recorded with Meshcat if asked, its summary printed and its
figures drawn (:func:`aerial_drake.viz.run_plots.write_run_figures`, the only step that
imports matplotlib); ``run paper`` goes to :mod:`aerial_drake.cli.paper`."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TextIO

from aerial_drake.cli.errors import report_error
from aerial_drake.cli.overrides import option_note, scenario_overrides
from aerial_drake.cli.paper import cmd_paper
from aerial_drake.cli.restart import cold_start, compile_first

# (The standard library only: importing it starts and compiles nothing.)
from aerial_drake.viz.live import WAIT_TIMEOUT_S

#: The longest simulated time (s) a first run on a cold numba cache runs on the reference law
#: while the law compiles in the background: the reference law costs about 1 s more per
#: simulated second (its evaluations and the tracking errors'), the compile 30 s to a minute
#: once (docs/performance.md, "Cold start"); a longer run compiles first.
COLD_REFERENCE_MAX_S = 30.0


def _say(args: argparse.Namespace) -> TextIO:
    """Where the human-readable lines go: stdout, or stderr with --json (stdout then holds the
    JSON alone)."""
    return sys.stderr if getattr(args, "json", False) else sys.stdout


def _print_summary(result, stream: TextIO) -> None:
    from aerial_drake.studies.summary import format_summary
    print(format_summary(result.metrics), file=stream)
    _warn_past_limits(result, stream)
    if result.out_dir is not None:
        print(f"wrote {result.out_dir / 'log.npz'} and {result.out_dir / 'metrics.json'}",
              file=stream)


def _warn_past_limits(result, stream: TextIO) -> None:
    """One line where a run went past the arm's limits that its joint_limits only report."""
    from aerial_drake.simulation.joint_limits import exceeded_summary
    modes = result.scenario.joint_limits
    kinds = tuple(kind for kind, mode in (("position", modes.positions),
                                          ("velocity", modes.velocities)) if mode == "report")
    past = exceeded_summary(result.metrics, kinds)
    if past:
        print(f"warning: past the arm's joint limits (joint_limits report; max q/limit, "
              f"|v|/v_max): {past}", file=stream)


def _write_run_figures(out: Path, args: argparse.Namespace) -> None:
    """The run's own Figs. 3-6 into its folder (after the metrics are written: they are
    drawn from the files, so they cannot change them). Matplotlib is imported only here."""
    if args.no_plots or not (out / "log.npz").is_file():
        return
    from aerial_drake.viz.run_plots import write_run_figures
    written = write_run_figures(out)
    print(f"wrote {len(written)} figures ({', '.join(p.name for p in written)}) in {out}",
          file=_say(args))


def check_options(args: argparse.Namespace) -> dict:
    """The run options as scenario overrides (:func:`aerial_drake.cli.overrides.
    scenario_overrides`), after the checks argparse cannot make; raises ScenarioError naming
    the option."""
    from aerial_drake.simulation.scenarios import ScenarioError

    overrides = scenario_overrides(args)
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


def cmd_run(args: argparse.Namespace) -> int:
    """``aerial-drake run SCENARIO`` (one scenario, optionally watched in Meshcat) and
    ``aerial-drake run paper`` (:func:`aerial_drake.cli.paper.cmd_paper`)."""
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
        compile_first(args.restartable)  # before anything is built (the peak is the compile's)
        return cmd_paper(args, overrides)
    try:
        scenario = load_scenario(args.scenario, overrides=overrides)
        if args.seed is not None:
            from aerial_drake.studies.paper import perturb_initial
            scenario = perturb_initial(scenario, args.seed)
    except ScenarioError as err:
        return report_error(args, 2, ScenarioError(f"{err}{option_note(err, overrides, args)}",
                                                   err.field))
    # A cold cache's run goes on at once on the reference law (cold_start, below), unless asked
    # to wait or long enough for the compile to cost less than the reference law would.
    wait = args.wait_compile or scenario.duration > COLD_REFERENCE_MAX_S
    # The law kernel the scenario chooses (controller.kernel) is one of the run's kernels.
    law_kernels = (scenario.controller.kernel,)
    if wait:
        # after the scenario's checks, before Meshcat starts
        compile_first(args.restartable, law_kernels)
    with cold_start(wait, sys.stderr, law_kernels) as compile_note:
        status = _run_one(args, scenario)
    compile_note()
    return status


def _run_one(args: argparse.Namespace, scenario) -> int:
    """``run SCENARIO`` once its scenario is loaded and checked (:func:`cmd_run`)."""
    from aerial_drake.dynamics.equilibrium import UnreachablePose
    from aerial_drake.simulation.interrupts import Interrupted
    from aerial_drake.simulation.outputs import OutputError, ResultsNotWritten
    from aerial_drake.simulation.runner import SimulationFailed, SimulationInterrupted, run_scenario
    from aerial_drake.simulation.scenarios import ScenarioError

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
        cause = (err.result.metrics.get("failure_cause") or {}) if err.result else {}
        why = f"cause: {cause['detail']}\n" if "detail" in cause else ""
        return report_error(args, 1, err, f"{why}logs up to the failure are in {out}")
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
