"""numba's cache on the first run after installing (aerial_drake.simulation.kernel_cache): the
cold check, a cold ``aerial-drake run`` on the reference implementation while the cache is
compiled in the background, a background compile stopped half-way, the compile lock, and one
test (slow) that lets the background compile finish and runs again on the compiled law.

A fresh install is simulated with an empty ``NUMBA_CACHE_DIR`` in a child process (numba
reads it at import). Only the slow test pays the compile (about 35 s of one core)."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from aerial_drake.control.compiled import reference_law_reason
from aerial_drake.simulation import kernel_cache
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.trajectories import paper

ROOT = Path(__file__).resolve().parents[2]


def _env(cache: Path) -> dict[str, str]:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env.pop("AERIAL_DRAKE_RESTARTED_AFTER_COMPILE", None)
    return env


def _python(cache: Path, code: str, timeout: float = 300) -> str:
    """``code`` run in a child process on ``cache``; its stdout (it must succeed)."""
    done = subprocess.run([sys.executable, "-c", code], env=_env(cache), capture_output=True,
                          text=True, timeout=timeout, cwd=cache.parent)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def _cli(cache: Path, out: Path, *args: str) -> subprocess.CompletedProcess:
    """``aerial-drake run nominal`` (0.05 s) as a user starts it, on ``cache``."""
    done = subprocess.run([sys.executable, "-m", "aerial_drake", "run", "nominal", "--duration",
                           "0.05", "--no-plots", "--quiet", "--out", str(out), *args],
                          env=_env(cache), capture_output=True, text=True, timeout=300,
                          cwd=cache.parent)
    assert done.returncode == 0, done.stderr[-3000:]
    return done


_STATE = ("from aerial_drake.simulation.kernel_cache import kernels_cache_is_cold, "
          "compile_is_under_way, lock_path\n"
          "print(kernels_cache_is_cold(), compile_is_under_way(), lock_path())")


def _state(cache: Path) -> tuple[bool, bool, str]:
    cold, busy, lock = _python(cache, _STATE).split()
    return cold == "True", busy == "True", lock


def _hold_lock(lock: str) -> subprocess.Popen:
    """A process holding the compile lock ``lock`` (a compile "under way") until killed."""
    holder = subprocess.Popen([sys.executable, "-c", (
        "import fcntl, sys, time\n"
        f"f = open({lock!r}, 'a+'); fcntl.flock(f.fileno(), fcntl.LOCK_EX)\n"
        "print('held', flush=True); time.sleep(600)")], stdout=subprocess.PIPE, text=True)
    assert holder.stdout.readline().strip() == "held"
    return holder


def test_an_empty_cache_is_cold_and_the_package_cache_is_warm(tmp_path):
    cold, busy, _ = _state(tmp_path / "cache")
    assert cold and not busy
    kernel_cache.compile_kernels()  # this process's cache: loaded (the suite runs warm)
    assert not kernel_cache.kernels_cache_is_cold()


# In a child process on an empty cache: a short run on the reference implementations compiles
# nothing (no kernel gains a signature, the cache stays cold), says why in metrics.json's terms,
# and the switch is off again after the block.
_REFERENCE_RUN = """
import json
from numba.core.registry import CPUDispatcher
from aerial_drake.control.compiled import kernels, kinematics, linalg, views
from aerial_drake.control.compiled import reference_law_reason
from aerial_drake.trajectories import paper
from aerial_drake.simulation import kernel_cache
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario

with kernel_cache.reference_implementations("testing"):
    result = run_scenario(load_scenario("nominal", overrides={"duration": 0.05}), progress=False)
compiled = sorted(f"{m.__name__}.{name}" for m in (views, linalg, kinematics, kernels, paper)
                  for name, obj in vars(m).items()
                  if isinstance(obj, CPUDispatcher) and obj.signatures)
print(json.dumps({"compiled": compiled, "cold": kernel_cache.kernels_cache_is_cold(),
                  "control_law": result.metrics.get("control_law"),
                  "after": reference_law_reason(), "interpreted": bool(paper._INTERPRETED)}))
"""


def test_the_reference_implementations_compile_nothing(tmp_path):
    seen = json.loads(_python(tmp_path / "cache", _REFERENCE_RUN).splitlines()[-1])
    assert seen["compiled"] == [] and seen["cold"]
    assert seen["control_law"] == "reference implementation (numpy): testing"
    assert seen["after"] is None and not seen["interpreted"]


def test_the_reference_law_agrees_with_the_compiled_one_to_round_off():
    scenario = load_scenario("nominal", overrides={"duration": 0.1})
    compiled = run_scenario(scenario, progress=False)
    with kernel_cache.reference_implementations("testing"):
        reference = run_scenario(scenario, progress=False)
    assert reference_law_reason() is None
    assert "control_law" not in compiled.metrics
    assert reference.metrics["control_law"].endswith("testing")
    for name in ("plant_state", "applied_command", "tracking"):
        a, b = compiled.log[name], reference.log[name]
        assert a.shape == b.shape
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-9, err_msg=name)


def test_the_interpreted_paper_reference_is_the_compiled_one_to_the_bit():
    params = load_scenario("nominal").trajectory
    times = np.linspace(0.0, 30.0, 3001)
    compiled = paper.PaperReference(params).packed(times)
    paper.use_interpreted_reference(True)
    try:
        source = paper.PaperReference(params)
        interpreted = source.packed(times[::10])
        one = np.empty(source.size)
        source.fill(7.3, one)
    finally:
        paper.use_interpreted_reference(False)
    assert np.array_equal(interpreted, compiled[::10])
    assert np.array_equal(one, paper.PaperReference(params).packed(np.array([7.3]))[0])


def test_a_cold_run_goes_on_with_the_reference_law_and_says_so(tmp_path):
    cache = tmp_path / "cache"
    _, _, lock = _state(cache)
    holder = _hold_lock(lock)  # a compile "under way": this test starts none
    try:
        done = _cli(cache, tmp_path / "out")
    finally:
        holder.kill()
        holder.wait()
    assert "numba's cache is cold" in done.stderr
    assert "by a compile already under way" in done.stderr
    assert "reference implementation" in done.stderr
    assert "the background compile still under way" in done.stderr
    metrics = json.loads((tmp_path / "out" / "nominal" / "metrics.json").read_text())
    assert metrics["control_law"].startswith("reference implementation")
    assert metrics["completed"]
    assert _state(cache)[0]  # still cold: nothing compiled in the run


def test_a_background_compile_stopped_half_way_leaves_a_usable_cache(tmp_path):
    cache = tmp_path / "cache"
    pid = int(_python(cache, "from aerial_drake.simulation.kernel_cache import "
                             "start_background_compile\nprint(start_background_compile())"))
    log = Path(_python(cache, "from aerial_drake.simulation.kernel_cache import log_path\n"
                              "print(log_path())").strip())
    try:
        deadline = time.monotonic() + 120
        while f"process {pid}: compiling" not in (log.read_text() if log.exists() else ""):
            assert time.monotonic() < deadline, "the background compile never started"
            time.sleep(0.2)
        assert _state(cache)[1]  # it holds the lock
    finally:
        # Killed as soon as it says it compiles: wherever it has got to (no fixed wait: a
        # test must not depend on how fast the machine compiles).
        os.killpg(pid, signal.SIGKILL)  # the process group it leads
    deadline = time.monotonic() + 30
    while _state(cache)[1]:  # the system releases its lock
        assert time.monotonic() < deadline
        time.sleep(0.2)
    cold = _state(cache)[0]
    assert _reap(pid)
    # and a run on it goes on: on the reference law if the compile had not finished (its own
    # background compile held off), on the compiled law if it had; never a broken cache.
    holder = _hold_lock(_state(cache)[2])
    try:
        done = _cli(cache, tmp_path / "out")
    finally:
        holder.kill()
        holder.wait()
    assert done.returncode == 0, done.stderr
    assert ("reference implementation" in done.stderr) == cold


def _reap(pid: int) -> bool:
    """Wait for ``pid`` to be gone or a zombie (not this process's child: its parent exited,
    and a container's first process may never reap it)."""
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return True
        if state in ("Z", "X"):
            return True
        time.sleep(0.1)
    return False


def test_the_lock_lets_one_hold_it_and_says_who(tmp_path):
    with kernel_cache.compile_lock() as held:
        assert held
        assert Path(kernel_cache.lock_path()).read_text().strip() == str(os.getpid())
    holder = _hold_lock(str(kernel_cache.lock_path()))
    try:
        assert kernel_cache.compile_is_under_way()
        with kernel_cache.compile_lock(wait=False) as held:
            assert not held
    finally:
        holder.kill()
        holder.wait()
    assert not kernel_cache.compile_is_under_way()


def test_the_background_compile_is_let_go_when_the_run_ends(monkeypatch):
    # It waits for the end of its standard input: at the end of the run (cold_start), not at
    # the end of a Python caller's process (cli.main from a notebook) that goes on after it.
    waiting = subprocess.Popen([sys.executable, "-c", "import sys; sys.stdin.read()"],
                               stdin=subprocess.PIPE)
    monkeypatch.setattr(kernel_cache, "_STARTED", [waiting])
    monkeypatch.setattr(kernel_cache, "kernels_cache_is_cold", lambda *kernels: True)
    monkeypatch.setattr(kernel_cache, "start_background_compile", lambda *kernels: waiting.pid)
    from aerial_drake.cli.restart import cold_start
    with cold_start(False, io.StringIO()) as note:
        assert reference_law_reason() == kernel_cache.COLD_REASON
        time.sleep(0.2)
        assert waiting.poll() is None  # still held during the run
    note()
    assert waiting.wait(timeout=30) == 0
    assert reference_law_reason() is None


def test_the_ticker_reports_while_the_block_runs():
    stream = io.StringIO()
    with kernel_cache.Ticker(stream, "compiling", every=0.05):
        deadline = time.monotonic() + 60  # until it has ticked (a guard against a hang only)
        while len(stream.getvalue().splitlines()) < 2:
            assert time.monotonic() < deadline
            time.sleep(0.05)
    lines = stream.getvalue().splitlines()
    assert lines[0] == "compiling ... "
    assert any(line.endswith(" s") for line in lines[1:-1])
    assert lines[-1].startswith("compiling ... done (")


@pytest.mark.slow
def test_the_background_compile_warms_the_cache_for_the_next_run(tmp_path):
    """The one test that pays the compile: a first run on an empty cache starts the
    background compile and runs on the reference law; once the compile has finished, the
    same command runs on the compiled law (loaded, not compiled: its process stays small),
    and the two runs agree to round-off."""
    cache, out = tmp_path / "cache", tmp_path / "out"
    first = _cli(cache, out)
    assert "built in the background when this run ends (process" in first.stderr
    cold_log = dict(np.load(out / "nominal" / "log.npz"))
    cold_metrics = json.loads((out / "nominal" / "metrics.json").read_text())
    assert "control_law" in cold_metrics
    # Wait for it (its lock), then the cache is warm.
    assert _python(cache, "from aerial_drake.simulation.kernel_cache import compile_lock, "
                          "kernels_cache_is_cold\nwith compile_lock():\n"
                          "    print(kernels_cache_is_cold())", timeout=900).split() == ["False"]
    second = _cli(cache, out)
    assert "numba's cache is cold" not in second.stderr
    assert "compiling" not in second.stderr
    warm_metrics = json.loads((out / "nominal" / "metrics.json").read_text())
    assert "control_law" not in warm_metrics
    warm_log = dict(np.load(out / "nominal" / "log.npz"))
    np.testing.assert_allclose(cold_log["plant_state"], warm_log["plant_state"], rtol=1e-9,
                               atol=1e-9)


def test_the_cold_check_counts_the_law_kernel_a_run_chooses(monkeypatch):
    """controller.kernel: fast makes the fast law one of the run's kernels: cold while it is
    not cached, whatever the default kernels' state; the default check does not look at it."""
    from aerial_drake.control.compiled import law
    kernel_cache.compile_kernels()  # this process's cache: loaded (the suite runs warm)
    monkeypatch.setattr(law, "is_cached", lambda kernel, signature: kernel is not law._law_fast)
    assert not kernel_cache.kernels_cache_is_cold()
    assert not kernel_cache.kernels_cache_is_cold(("exact",))
    assert kernel_cache.kernels_cache_is_cold(("fast",))


def test_run_passes_the_scenario_kernel_to_the_cold_start(monkeypatch, tmp_path):
    from aerial_drake.cli import main
    seen = []

    def warm_or_started(stream, law_kernels=()):
        seen.append(law_kernels)
        return True, lambda: None

    monkeypatch.setattr(kernel_cache, "warm_or_started", warm_or_started)
    assert main(["run", "nominal", "--duration", "0.05", "--no-plots", "--quiet", "--out",
                 str(tmp_path), "--set", "controller.kernel=fast"]) == 0
    assert seen == [("fast",)]
