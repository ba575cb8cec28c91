"""What a study refuses before any run, each as exit 2 naming the folder, file or address and
the fix: a folder another study holds (its lock), a folder whose rows were run from another
spec (unless --restart), a table that is not UTF-8, a scheduler that does not answer. And a
study's robot named by a path relative to its own file or to its base scenario's."""

import json
import shutil
from pathlib import Path

import pytest
from pydrake.common.yaml import yaml_load

from aerial_drake import cli
from aerial_drake.simulation.outputs import OutputError, prepare_folder
from aerial_drake.studies import identity
from aerial_drake.studies.executor import ClusterError
from aerial_drake.studies.spec import load_study
from aerial_drake.studies.study import PROVENANCE_NAME, TABLE_NAME, _provenance, run_study
from aerial_drake.studies.table import ResultsTable, write_provenance
from tests.own_robot import write_robot

SMALL = Path(__file__).resolve().parent / "small_study.yaml"


def _done_before(folder, loaded, rows=1):
    """``folder`` as a study of ``loaded`` left it: its provenance and ``rows`` rows."""
    from aerial_drake.studies.study import table_columns
    write_provenance(folder / PROVENANCE_NAME, _provenance(loaded, 6), {"scheduler": "local"})
    table = ResultsTable.open(folder / TABLE_NAME, table_columns(loaded))
    for i in range(rows):
        table.append({"run_id": f"old{i}", "index": i, "draw": 0, "completed": True})


def _study(capsys, *args):
    status = cli.main(["study", str(SMALL), "--quiet", *args])
    return status, capsys.readouterr().err


def test_a_folder_another_study_holds_is_refused_before_any_run(tmp_path, capsys):
    lock = prepare_folder(tmp_path)  # as the first study holds it while it runs
    try:
        status, err = _study(capsys, "--out", str(tmp_path))
    finally:
        lock.release()
    assert status == 2
    assert str(tmp_path) in err and "in use" in err and "another --out" in err
    assert not (tmp_path / TABLE_NAME).exists()  # nothing written, nothing run


@pytest.mark.parametrize("args, said", [
    (["--duration", "0.2"], "duration: 0.3 before, 0.2 now"),
])
def test_a_changed_spec_is_refused_on_resume(tmp_path, capsys, args, said):
    _done_before(tmp_path, load_study(SMALL))
    kept = (tmp_path / TABLE_NAME).read_text(), (tmp_path / PROVENANCE_NAME).read_text()
    status, err = _study(capsys, "--out", str(tmp_path), *args)
    assert status == 2
    assert str(tmp_path) in err and said in err and "--restart" in err
    assert ((tmp_path / TABLE_NAME).read_text(), (tmp_path / PROVENANCE_NAME).read_text()) \
        == kept  # the table and the provenance still say one spec


def test_every_field_of_the_identity_is_told(tmp_path):
    loaded = load_study(SMALL)
    now = _provenance(loaded, 6)
    edits = {"name": "other", "duration": 2.0, "seed": 8,
             "parameters": [{"field": "gains.k_R", "values": [1.0]}]}
    for key, value in edits.items():
        before = json.loads(json.dumps(now, default=str))
        before["spec"][key] = value
        said = identity.changes(identity.identity(before), identity.identity(now))
        assert len(said) == 1 and said[0].startswith(f"{key}:"), said
    for key in ("settings", "base_scenario"):
        before = dict(now, **{key: {"x": 1} if key == "settings" else "other"})
        assert len(identity.changes(identity.identity(before), identity.identity(now))) == 1
    # Not the description, the metrics kept or the number of draws (they change no run).
    before = json.loads(json.dumps(now, default=str))
    before["spec"].update(description="other", metrics=["x"], draws=99)
    assert identity.changes(identity.identity(before), identity.identity(now)) == []


def test_rows_without_their_provenance_are_refused(tmp_path):
    loaded = load_study(SMALL)
    _done_before(tmp_path, loaded)
    (tmp_path / PROVENANCE_NAME).unlink()
    with pytest.raises(identity.StudyChanged, match="cannot be read"):
        run_study(loaded, tmp_path, progress=False)


def test_restart_discards_the_old_spec_rows(tmp_path):
    loaded = load_study(SMALL, duration=0.2)
    _done_before(tmp_path, load_study(SMALL))
    with pytest.raises(identity.StudyChanged):
        run_study(loaded, tmp_path, progress=False)
    # (no scheduler answers at port 1: the restart is seen before the cluster is tried)
    with pytest.raises(ClusterError):
        run_study(loaded, tmp_path, progress=False, restart=True, scheduler="tcp://127.0.0.1:1")
    assert (tmp_path / TABLE_NAME).read_text().count("\n") == 1  # the header alone
    stored = json.loads((tmp_path / PROVENANCE_NAME).read_text())["study"]
    assert stored["spec"]["duration"] == 0.2


def test_the_same_spec_resumes(tmp_path):
    loaded = load_study(SMALL)
    _done_before(tmp_path, loaded)
    identity.check_same_study(tmp_path / TABLE_NAME, tmp_path / PROVENANCE_NAME,
                              _provenance(load_study(SMALL, draws=5), 10))  # no error


def test_an_unreachable_scheduler_is_exit_2_naming_it(tmp_path, capsys):
    status, err = _study(capsys, "--out", str(tmp_path), "--scheduler", "tcp://127.0.0.1:1")
    assert status == 2
    assert "--scheduler tcp://127.0.0.1:1" in err and "no Dask scheduler answered" in err
    assert "unexpected" not in err


def test_a_table_that_is_not_utf8_is_exit_2_naming_it(tmp_path, capsys):
    (tmp_path / TABLE_NAME).write_bytes(b"run_id,index\n\xff\xfe,1\n")
    status, err = _study(capsys, "--out", str(tmp_path))
    assert status == 2
    assert str(tmp_path / TABLE_NAME) in err and "not UTF-8" in err and "unexpected" not in err
    with pytest.raises(OutputError, match="not UTF-8"):
        ResultsTable.open(tmp_path / TABLE_NAME, ["run_id", "index"])


def test_a_robot_relative_to_the_base_or_to_the_study_file_is_found(tmp_path):
    description, scenario = write_robot(tmp_path / "robot")
    study = tmp_path / "study.yaml"
    kept = "metrics: ['phase*.ee_position_error_m.max']\n"
    study.write_text(f"name: own\nbase: robot/{scenario.name}\n{kept}")  # beside the base
    assert load_study(study).base.robot == str(description.resolve())
    shutil.copy(description, tmp_path / "mine.robot.yaml")  # robot: beside the study file
    shutil.copy(tmp_path / "robot" / "quad_arm.urdf", tmp_path / "quad_arm.urdf")
    study.write_text(f"name: own\nbase: robot/{scenario.name}\n{kept}"
                     "settings: {robot: mine.robot.yaml}\n")
    assert load_study(study).base.robot == str((tmp_path / "mine.robot.yaml").resolve())


def test_help_lists_every_shipped_study_and_show_run_tells_the_studys_own(capsys):
    from aerial_drake.cli.parser import build_parser
    from aerial_drake.studies.spec import shipped_studies
    names = list(shipped_studies())
    # robustness, directions, gains, gains_attitude and each with _plus; the three contact
    # studies (docs/contact.md)
    assert len(names) == 11
    text = " ".join(build_parser()._subparsers._group_actions[0].choices["study"]
                    .format_help().split())
    assert all(name in text for name in names)
    assert cli.main(["study", "gains", "--show-run", "3"]) == 0
    shown = yaml_load(data=capsys.readouterr().out)["description"]
    assert shown.startswith("Run 3 (run_id ") and "gains.K_y = 0.25" in shown
    assert "of study 'gains'. K_y and K_z (Table II's diagonals)" in shown
    assert load_study("gains").base.description not in shown  # not the base scenario's
