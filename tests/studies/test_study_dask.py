"""A small study on Dask: the same rows on a cluster of separate processes on localhost
(``dask scheduler`` and two ``dask worker``) as on the default local cluster; a worker killed
mid-study loses nothing; Ctrl-C (to the whole process group, as a terminal sends it) prints
no worker's traceback, and a resume then runs every run exactly once. Every signal and
kill is sent at an observed event (a row written, a worker executing), never after a time."""

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from aerial_drake.studies.spec import load_study, plan_runs
from aerial_drake.studies.study import run_study
from aerial_drake.studies.table import read_table

SMALL = Path(__file__).resolve().parent / "small_study.yaml"
#: Columns that differ between identical runs: the wall time and where it ran.
VOLATILE = ("wall_time_s", "worker")
DASK = str(Path(sys.executable).parent / "dask")
TIMEOUT_S = 300


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _rows(path):
    return {r["run_id"]: {k: v for k, v in r.items() if k not in VOLATILE}
            for r in read_table(path)}


@pytest.fixture(scope="module")
def cluster():
    """``dask scheduler`` and two ``dask worker`` processes (one thread each) on 127.0.0.1;
    yields the scheduler's address. The scheduler retries a run once after its worker dies
    (as the local cluster does)."""
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    env = dict(os.environ, DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES="1")
    processes = [subprocess.Popen([DASK, "scheduler", "--host", "127.0.0.1", "--port",
                                   str(port), "--no-dashboard"], env=env,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    for _ in range(2):
        processes.append(subprocess.Popen(
            [DASK, "worker", address, "--nworkers", "1", "--nthreads", "1", "--host",
             "127.0.0.1", "--no-dashboard"], env=env, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL))
    from distributed import Client
    try:
        with Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
        yield address
    finally:
        for p in processes:
            p.terminate()
        for p in processes:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


@pytest.fixture(scope="module")
def local_rows(tmp_path_factory):
    """The small study on the default local cluster (two workers)."""
    out = tmp_path_factory.mktemp("local")
    result = run_study(load_study(SMALL), out, workers=2, progress=False)
    assert result.complete and result.ran == 6
    return _rows(result.table)


def test_same_rows_on_separate_processes_and_on_the_local_cluster(cluster, local_rows,
                                                                   tmp_path):
    result = run_study(load_study(SMALL), tmp_path, scheduler=cluster, progress=False)
    assert result.complete and result.ran == 6
    rows = _rows(result.table)
    assert rows == local_rows
    assert any(r["completed"] == "true" for r in rows.values())
    planned = {r.run_id for r in plan_runs(load_study(SMALL))}
    assert set(rows) == planned
    # Two worker processes took runs.
    assert len({r["worker"] for r in read_table(result.table)}) == 2


def _study_command(out, *extra):
    return [sys.executable, "-m", "aerial_drake.cli", "study", str(SMALL), "--out", str(out),
            "--quiet", *extra]


def _wait_for(condition, process, what):
    while not condition():
        if process.poll() is not None:
            raise AssertionError(f"the study ended before {what}: "
                                 f"{process.stdout.read() if process.stdout else ''}")
        time.sleep(0.05)


def _row_count(path):
    return len(read_table(path)) if path.is_file() else 0


def test_a_killed_worker_loses_nothing(cluster, local_rows, tmp_path):
    from distributed import Client
    table = tmp_path / "results.csv"
    # Longer runs (so that a run is under way when the kill comes); the same study else.
    process = subprocess.Popen(_study_command(tmp_path, "--scheduler", cluster, "--duration",
                                              "1.0", "--draws", "4"),
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    killed = None
    with Client(cluster, timeout="60s") as client:
        try:
            _wait_for(lambda: _row_count(table) >= 1, process, "its first row")

            def executing():
                busy = client.run(lambda dask_worker: len(dask_worker.state.executing))
                return [address for address, n in busy.items() if n]
            _wait_for(lambda: executing(), process, "a worker took a run")
            address = executing()[0]
            killed = client.run(os.getpid, workers=[address])[address]
            os.kill(killed, signal.SIGKILL)
            output, _ = process.communicate(timeout=TIMEOUT_S)
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()
        client.wait_for_workers(2, timeout=120)  # the nanny replaced it
    assert process.returncode == 0, output
    rows = read_table(table)
    planned = {r.run_id for r in plan_runs(load_study(SMALL, duration=1.0, draws=4))}
    assert sorted(r["run_id"] for r in rows) == sorted(planned)  # each once, none missing
    for row in rows:  # retried on a live worker, or recorded as the cluster's failure
        assert row["completed"] == "true" or row["failure_kind"] == "worker", row


def test_ctrl_c_then_resume_runs_each_run_once(local_rows, tmp_path):
    table = tmp_path / "results.csv"
    # Its own process group, signalled whole: a terminal's Ctrl-C reaches every process of
    # the foreground group, the local cluster's workers included.
    process = subprocess.Popen(_study_command(tmp_path, "--workers", "2"),
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               start_new_session=True)
    try:
        _wait_for(lambda: _row_count(table) >= 1, process, "its first row")
        os.killpg(process.pid, signal.SIGINT)
        output, _ = process.communicate(timeout=TIMEOUT_S)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == 130, output
    assert "interrupted" in output
    assert "Traceback" not in output and "KeyboardInterrupt" not in output  # (workers quiet)
    first = _rows(table)
    assert 1 <= len(first) <= 6
    assert len(read_table(table)) == len(first)  # no run twice
    done = subprocess.run(_study_command(tmp_path, "--workers", "2", "--json"),
                          capture_output=True, text=True, timeout=TIMEOUT_S)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["skipped_done_before"] == len(first)
    assert summary["ran"] == 6 - len(first) and summary["complete"]
    rows = read_table(table)
    assert len(rows) == 6 and len({r["run_id"] for r in rows}) == 6
    assert _rows(table) == local_rows  # the same rows as one uninterrupted study


def test_show_run_reproduces_a_row_in_a_single_run(local_rows, tmp_path):
    from aerial_drake.simulation.runner import run_scenario
    from aerial_drake.simulation.scenarios import load_scenario
    from aerial_drake.studies.metrics_table import flatten_metrics
    run_id, row = sorted(local_rows.items())[0]
    shown = subprocess.run([sys.executable, "-m", "aerial_drake.cli", "study", str(SMALL),
                            "--show-run", run_id], capture_output=True, text=True, timeout=120)
    assert shown.returncode == 0, shown.stderr
    path = tmp_path / "run.yaml"
    path.write_text(shown.stdout)
    metrics = flatten_metrics(run_scenario(load_scenario(path), progress=False).metrics)
    kept = [c for c in row if c in metrics]
    assert kept
    for column in kept:
        assert row[column] == ("" if metrics[column] is None else repr(metrics[column]))


def test_where_drake_keeps_diagrams_the_local_workers_have_a_lifetime(monkeypatch, tmp_path):
    """Where Drake keeps every run's diagram alive (drake 1.51.1), the local cluster's workers
    retire and restart periodically (executor.WORKER_LIFETIME_S; Dask reschedules what a
    retiring worker held); elsewhere they live as long as the study. Checked on the workers
    themselves, not by waiting for a restart (a test must not depend on the machine's speed);
    a study under the setting records each run once."""
    import aerial_drake.drake_compat as compat
    from aerial_drake.studies import executor

    def lifetimes() -> set:
        with executor.study_client(1) as (client, _):
            return set(client.run(lambda dask_worker: dask_worker.lifetime).values())

    monkeypatch.setattr(compat, "python_systems_outlive_diagrams", lambda: False)
    assert lifetimes() == {None}
    monkeypatch.setattr(compat, "python_systems_outlive_diagrams", lambda: True)
    got = lifetimes()
    assert len(got) == 1 and abs(got.pop() - executor.WORKER_LIFETIME_S) <= (
        executor.WORKER_LIFETIME_STAGGER_S)
    loaded = load_study(SMALL, duration=0.3, draws=2)
    result = run_study(loaded, tmp_path, workers=1, progress=False)
    assert result.complete and result.ran == 4
    rows = read_table(result.table)
    assert sorted(r["run_id"] for r in rows) == sorted(r.run_id for r in plan_runs(loaded))
