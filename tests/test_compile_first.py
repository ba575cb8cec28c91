"""The first run after installing, for the commands that wait for the compiled law (run paper,
compare, run --wait-compile): the command line compiles the numba kernels before the run and
restarts itself (aerial_drake.cli.restart.compile_first), so that compile's memory is not under
the run (plain 'run SCENARIO' does not wait: tests/simulation/test_kernel_cache.py). Here:
runner.compile_kernels compiles every kernel a run calls from Python (nothing is left to
compile during the run), and when the command restarts and when it does not."""

import contextlib
import json
import os
import subprocess
import sys

import pytest

from aerial_drake import cli
from aerial_drake.cli import info, restart
from aerial_drake.simulation import kernel_cache

# In a fresh process: compile_kernels, then a short closed-loop run; print every numba
# dispatcher of the package's kernel modules that gained a signature during the run.
_RUN_AFTER_COMPILE = """
import json
from numba.core.registry import CPUDispatcher
from aerial_drake.control.compiled import kernels, kinematics, linalg, views
from aerial_drake.trajectories import paper
from aerial_drake.simulation.runner import compile_kernels, run_scenario
from aerial_drake.simulation.scenarios import load_scenario

def signatures():
    return {f"{m.__name__}.{name}": [str(s) for s in obj.signatures]
            for m in (views, linalg, kinematics, kernels, paper) for name, obj in vars(m).items()
            if isinstance(obj, CPUDispatcher)}

compile_kernels()
before = signatures()
for name in ("nominal", "disturbed"):
    run_scenario(load_scenario(name, overrides={"duration": 0.01}), progress=False)
after = signatures()
print(json.dumps({k: sorted(set(v) - set(before[k])) for k, v in after.items()
                  if set(v) - set(before[k])}))
"""


def test_compile_kernels_leaves_nothing_to_compile_in_a_run():
    done = subprocess.run([sys.executable, "-c", _RUN_AFTER_COMPILE], capture_output=True,
                          text=True, timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    compiled_in_run = json.loads(done.stdout.strip().splitlines()[-1])
    assert compiled_in_run == {}, (
        f"kernels compiled during the run, not by compile_kernels: {compiled_in_run}")


class _Restart(Exception):
    pass


@pytest.fixture
def first_run(monkeypatch):
    """compile_first with the cache reported cold, compiling and exec recorded, not done;
    ``cold["waited"]``: the cache another process compiled while this one waited for its lock
    (warm after the wait)."""
    calls = {"compiled": 0, "execv": None, "locked": 0}
    cold = {"before": True, "after": False, "waited": False}

    def kernels_cache_is_cold(law_kernels=()):
        if calls["locked"] and cold["waited"]:
            return False
        return cold["before"] if calls["compiled"] == 0 else cold["after"]

    def compile_kernels(law_kernels=()):
        calls["compiled"] += 1

    @contextlib.contextmanager
    def compile_lock(wait=True, stream=None):
        calls["locked"] += 1
        yield True

    def execv(path, argv):
        calls["execv"] = (path, argv)
        raise _Restart

    monkeypatch.setattr(kernel_cache, "kernels_cache_is_cold", kernels_cache_is_cold)
    monkeypatch.setattr(kernel_cache, "compile_kernels", compile_kernels)
    monkeypatch.setattr(kernel_cache, "compile_lock", compile_lock)
    monkeypatch.setattr(os, "execv", execv)
    monkeypatch.delenv(restart.RESTARTED, raising=False)
    return calls, cold


def test_cold_cache_compiles_then_restarts_as_it_was_started(first_run, monkeypatch):
    calls, _ = first_run
    # As the console script starts it: the restart must run the same script (the same
    # installed package and cache), not "-m aerial_drake", which a source tree in the working
    # directory would shadow.
    monkeypatch.setattr(sys, "orig_argv", ["python3", "/venv/bin/aerial-drake", "run", "paper"])
    with pytest.raises(_Restart):
        restart.compile_first(restartable=True)
    assert calls["compiled"] == 1
    assert calls["execv"] == (sys.executable,
                              [sys.executable, "/venv/bin/aerial-drake", "run", "paper"])
    assert os.environ[restart.RESTARTED] == "1"  # the restarted process will not restart


@pytest.mark.parametrize("case", ["warm", "called from python", "restarted", "cache not written",
                                  "compiled by another process meanwhile"])
def test_no_restart(first_run, monkeypatch, case):
    calls, cold = first_run
    restartable = True
    if case == "warm":
        cold["before"] = False
    elif case == "called from python":
        restartable = False  # cli.main(argv): never replace the caller's process
    elif case == "restarted":
        monkeypatch.setenv(restart.RESTARTED, "1")
    elif case == "cache not written":
        cold["after"] = True
    else:  # a first 'run SCENARIO''s background compile, waited for under the lock
        cold["waited"] = True
    restart.compile_first(restartable)
    assert calls["execv"] is None
    assert calls["compiled"] == (1 if case == "cache not written" else 0)
    assert calls["locked"] == (1 if case in ("cache not written",
                                             "compiled by another process meanwhile") else 0)


def test_main_from_python_does_not_restart(monkeypatch):
    seen = {}
    monkeypatch.setattr(info, "cmd_info", lambda args: seen.setdefault("restart", args.restartable)
                        and 0)
    cli.main(["info"])
    assert seen["restart"] is False
