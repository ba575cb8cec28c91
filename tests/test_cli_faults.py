"""Faults during a run, as a user meets them: a signal in each phase (loading, simulating,
writing), a full file system, a read-only folder, two runs into one folder. Each leaves either
a complete, valid result set or nothing, and says which. Every signal is sent when the run
reaches its phase (a hook in the run, or a marker the child process prints): nothing here
depends on the machine's speed."""

import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from aerial_drake import cli
from aerial_drake.simulation import outputs, runner, scenarios
from processes import signal_at_first_progress

SIGNALS = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP]
SHORT = ["--duration", "1.5", "--quiet"]


def result_set(folder: Path) -> str:
    """'complete' (metrics.json, log.npz and scenario.yaml, all valid and of one run) or
    'nothing' (no metrics.json, no log); anything else fails the test."""
    metrics_path = folder / "metrics.json"
    if not metrics_path.exists():
        assert not (folder / "log.npz").exists(), "a log without its metrics.json"
        assert not list(folder.glob(".*.tmp")) if folder.exists() else True
        return "nothing"
    metrics = json.loads(metrics_path.read_text(),
                         parse_constant=lambda c: pytest.fail(f"{c} in metrics.json"))
    log = np.load(folder / "log.npz")
    assert len(log["t"]) > 0 and log["t"][-1] == pytest.approx(metrics["simulated_time_s"])
    assert {len(log[k]) for k in log.files if k != "layout"} == {len(log["t"])}
    assert scenarios.load_scenario(folder / "scenario.yaml").name == metrics["scenario"]
    assert not list(folder.glob(".*.tmp"))
    return "complete"


def _signal_self(signum):
    os.kill(os.getpid(), signum)


@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_signal_while_loading_writes_nothing(tmp_path, capsys, monkeypatch, signum):
    load = scenarios.load_scenario

    def loading(*args, **kwargs):
        scenario = load(*args, **kwargs)
        _signal_self(signum)
        return scenario

    monkeypatch.setattr(scenarios, "load_scenario", loading)
    assert cli.main(["run", "nominal", "--out", str(tmp_path), *SHORT]) == 128 + signum
    err = capsys.readouterr().err
    assert "outside the simulation; nothing more written" in err and "Traceback" not in err
    assert result_set(tmp_path / "nominal") == "nothing"


@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_signal_while_simulating_writes_what_was_logged(tmp_path, capsys, monkeypatch, signum):
    def report(self, t):  # the first progress pause, at t = 1 s
        _signal_self(signum)

    monkeypatch.setattr(runner._Progress, "report", report)
    assert cli.main(["run", "nominal", "--out", str(tmp_path), *SHORT]) == 128 + signum
    err = capsys.readouterr().err
    assert "Traceback" not in err and f"logs up to the interruption are in {tmp_path}" in err
    assert result_set(tmp_path / "nominal") == "complete"
    metrics = json.loads((tmp_path / "nominal" / "metrics.json").read_text())
    assert metrics["completed"] is False
    assert metrics["failure"].startswith("interrupted (")
    assert metrics["simulated_time_s"] == pytest.approx(1.0)


@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_signal_while_writing_keeps_every_file(tmp_path, capsys, monkeypatch, signum):
    """A signal after the simulation, as log.npz is written: held until metrics.json is in
    place, then the command stops with 128 + signal."""
    write = outputs.write_atomically

    def writing(path, fn):
        if path.name == "log.npz":
            _signal_self(signum)
        write(path, fn)

    monkeypatch.setattr(outputs, "write_atomically", writing)
    assert cli.main(["run", "nominal", "--out", str(tmp_path), *SHORT]) == 128 + signum
    err = capsys.readouterr().err
    assert "while writing the results; they are complete" in err and "Traceback" not in err
    assert result_set(tmp_path / "nominal") == "complete"
    metrics = json.loads((tmp_path / "nominal" / "metrics.json").read_text())
    assert metrics["completed"] is True and metrics["simulated_time_s"] == 1.5


def test_signal_in_run_paper_does_not_start_the_next_case(tmp_path, capsys, monkeypatch):
    def report(self, t):
        _signal_self(signal.SIGTERM)

    monkeypatch.setattr(runner._Progress, "report", report)
    status = cli.main(["run", "paper", "--out", str(tmp_path), *SHORT])
    err = capsys.readouterr().err
    assert status == 128 + signal.SIGTERM, err
    assert "interrupted (SIGTERM)" in err and "'disturbed' not started" in err
    assert result_set(tmp_path / "paper" / "nominal") == "complete"
    assert not (tmp_path / "paper" / "disturbed").exists()
    assert not list((tmp_path / "paper").glob("fig*"))


# --- The file system ------------------------------------------------------------------------
def _mount_tmpfs(mount: Path, size: str) -> bool:
    """Mount a tmpfs of ``size`` on ``mount`` (needs root and mount); whether it worked."""
    mount.mkdir()
    return os.geteuid() == 0 and subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(mount)],
        capture_output=True).returncode == 0


@pytest.fixture
def small_tmpfs(tmp_path):
    """A 4 MB tmpfs; None where it cannot be mounted."""
    mount = tmp_path / "mnt"
    if not _mount_tmpfs(mount, "4m"):
        yield None
        return
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", str(mount)], capture_output=True)


def _fill(folder: Path) -> None:
    """Fill the file system holding ``folder`` (another process filling the disk)."""
    with open(folder / "filler", "wb") as f:
        try:
            while True:
                f.write(b"\0" * 65536)
                f.flush()
        except OSError:
            pass


def test_a_disk_too_small_is_refused_before_simulating(tmp_path, capsys, monkeypatch):
    mount = tmp_path / "tiny"
    if not _mount_tmpfs(mount, "256k"):
        pytest.skip("needs root and mount for a 256 kB tmpfs")  # (the injected test covers it)
    try:
        monkeypatch.setattr(runner, "build_simulation", lambda *a, **k: pytest.fail("built"))
        status = cli.main(["run", "nominal", "--out", str(mount), *SHORT])
        err = capsys.readouterr().err
        assert status == 2 and "MB free; the run's files need up to" in err, err
        assert result_set(mount / "nominal") == "nothing"
    finally:
        subprocess.run(["umount", "-l", str(mount)], capture_output=True)


def test_full_disk_leaves_no_result_set_and_says_so(tmp_path, small_tmpfs, capsys, monkeypatch):
    """The disk fills up during the simulation (a 4 MB tmpfs filled at the first progress
    pause; without root, an injected ENOSPC): exit 3, and neither the new files nor an
    earlier run's metrics.json (which would say completed: true of a set it no longer
    describes) remain."""
    out = small_tmpfs if small_tmpfs is not None else tmp_path
    if small_tmpfs is None:
        write = outputs.write_atomically

        def full(path, fn):
            if path.name == "log.npz":
                raise OSError(28, "No space left on device")
            write(path, fn)
        monkeypatch.setattr(outputs, "write_atomically", full)
    else:
        monkeypatch.setattr(runner._Progress, "report", lambda self, t: _fill(out))
    folder = out / "nominal"
    folder.mkdir()
    (folder / "metrics.json").write_text('{"completed": true}')  # an earlier run's
    status = cli.main(["run", "nominal", "--out", str(out), *SHORT])
    err = capsys.readouterr().err
    assert status == 3, err
    assert "No space left on device" in err and "nothing of this run was left" in err
    assert "Traceback" not in err
    assert result_set(folder) == "nothing"


def test_read_only_folder_is_refused_before_simulating(tmp_path, small_tmpfs, capsys,
                                                       monkeypatch):
    def never(*args, **kwargs):
        pytest.fail("the model was built although the folder cannot be written")

    monkeypatch.setattr(runner, "build_simulation", never)
    if small_tmpfs is not None:
        subprocess.run(["mount", "-o", "remount,ro", str(small_tmpfs)], check=True)
        out = small_tmpfs
    else:
        out = tmp_path / "ro"
        out.mkdir()
        out.chmod(0o555)
    status = cli.main(["run", "nominal", "--out", str(out), *SHORT])
    err = capsys.readouterr().err
    assert status == 2, err
    assert str(out / "nominal") in err and "choose another --out" in err
    assert "Traceback" not in err


def test_a_locked_folder_is_refused_and_nothing_is_written(tmp_path, capsys):
    folder = tmp_path / "nominal"
    folder.mkdir()
    lock = outputs.prepare_folder(folder)  # another run holds it
    try:
        status = cli.main(["run", "nominal", "--out", str(tmp_path), *SHORT])
    finally:
        lock.release()
    err = capsys.readouterr().err
    assert status == 2 and "in use by another run" in err and "nothing was simulated" in err
    assert result_set(folder) == "nothing"
    assert cli.main(["run", "nominal", "--out", str(tmp_path), *SHORT]) == 0  # lock freed
    assert result_set(folder) == "complete"


def _cli(*args):
    return [sys.executable, "-m", "aerial_drake.cli", "run", "nominal", *args]


def test_two_concurrent_runs_into_one_folder(tmp_path):
    """Two processes into one --out: whichever order they take the lock, each ends with exit
    0 and a complete set, or exit 2 saying the folder was in use and nothing was written;
    the folder ends with one complete, valid set."""
    procs = [subprocess.Popen(_cli("--out", str(tmp_path), *SHORT), stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [(p.wait(timeout=600), p.stderr.read()) for p in procs]
    for p in procs:
        p.stdout.close()
        p.stderr.close()
    for status, err in results:
        assert status in (0, 2), err
        if status == 2:
            assert "in use by another run" in err and "nothing was simulated" in err
        assert "Traceback" not in err
    assert 0 in [s for s, _ in results]
    assert result_set(tmp_path / "nominal") == "complete"


def test_sigterm_from_outside_while_simulating(tmp_path):
    """A real SIGTERM from another process, sent when the run prints its first progress line."""
    status, output = signal_at_first_progress(_cli("--duration", "30", "--out", str(tmp_path)),
                                              signal.SIGTERM)
    assert status == 128 + signal.SIGTERM, output
    assert "interrupted (SIGTERM) at t = " in output and "Traceback" not in output
    assert result_set(tmp_path / "nominal") == "complete"
    metrics = json.loads((tmp_path / "nominal" / "metrics.json").read_text())
    assert metrics["completed"] is False and 0 < metrics["simulated_time_s"] < 30
    assert all(not isinstance(v, float) or math.isfinite(v) for v in metrics.values())


def test_replacing_the_results_of_other_settings_is_said(tmp_path, capsys):
    """A copied file that keeps ``name: nominal`` replaces nominal's results, with a note."""
    assert cli.main(["run", "nominal", "--out", str(tmp_path), *SHORT]) == 0
    assert "note:" not in capsys.readouterr().err
    assert cli.main(["run", "nominal", "--out", str(tmp_path), *SHORT]) == 0  # same: no note
    assert "note:" not in capsys.readouterr().err
    assert cli.main(["run", "nominal", "--out", str(tmp_path), "--quiet", "--duration", "1"]) == 0
    assert "holds the results of a run with other settings" in capsys.readouterr().err
    assert result_set(tmp_path / "nominal") == "complete"
