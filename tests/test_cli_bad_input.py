"""A user's mistakes on the command line, one row each: the file or option, the exit status,
and what the message must name. Every row is refused before anything is simulated, with one
line on stderr and no traceback (docs/reliability.md)."""

import json
from pathlib import Path

import pytest

from aerial_drake import cli
from aerial_drake.simulation.scenarios import shipped_scenarios

NOMINAL = shipped_scenarios()["nominal"].read_text()


def _edit(old: str, new: str) -> str:
    assert old in NOMINAL, old
    return NOMINAL.replace(old, new, 1)


def _actuation(lines: str) -> str:
    """The nominal scenario with ``lines`` added to its actuation section (the shipped file
    sets no limit: the robot description's apply unless overridden)."""
    return _edit("  saturate: true\n", "  saturate: true\n" + lines)


#: (id, file content (str, bytes, or None for the shipped nominal), extra options,
#:  substrings the message must hold (the field, the value)).
BAD_FILES = [
    ("yaml-syntax", "duration: [1, 2\n", [], ["YAML syntax error", "line"]),
    ("tab", "gains:\n\tk_R: 1\n", [], ["tab", "line 2"]),
    ("unknown-tag", "duration: !seconds 3\n", [], ["YAML", "tag"]),
    ("binary", b"\x00\x01\x02", [], ["binary"]),
    ("latin-1", "name: caf\xe9\n".encode("latin-1"), [], ["UTF-8", "line 1"]),
    ("empty-file", "", [], ["empty"]),
    ("only-comments", "# nothing\n", [], ["empty"]),
    ("empty-section", "gains:\n", [], ["gains", "empty section"]),
    ("mapping-for-list", "disturbances: {target: x}\n", [], ["disturbances", "list"]),
    ("list-for-mapping", "- 1\n- 2\n", [], ["top level", "mapping"]),
    ("misspelt-key", _edit("duration:", "duraton:"), [], ["duraton"]),
    ("bool-for-number", _edit("duration: 15.0", "duration: true"), [], ["duration", "true"]),
    ("duration-inf", _edit("duration: 15.0", "duration: .inf"), [], ["duration", ".inf"]),
    ("duration-nan", _edit("duration: 15.0", "duration: .nan"), [], ["duration", ".nan"]),
    ("max-step-zero", _edit("max_step_size: 0.001", "max_step_size: 0.0"), [],
     ["simulator.max_step_size", "0.0", ">= 1e-06"]),
    ("accuracy-nan", _edit("accuracy: 1.0e-6", "accuracy: .nan"), [],
     ["simulator.accuracy", ".nan"]),
    ("scheme", _edit("runge_kutta3", "runge_kutta9"), [],
     ["simulator.integration_scheme", "runge_kutta9"]),
    ("log-period-tiny", _edit("log_period: 0.001", "log_period: 1.0e-7"), [],
     ["log_period", "1e-07"]),
    ("log-too-big", _edit("log_period: 0.001", "log_period: 1.0e-5"), [],
     ["estimated log", "max_log_mb"]),
    ("controller-period-100", _edit("controller_period: 0.001", "controller_period: 100"), [],
     ["controller_period", "100"]),
    ("window-inf", _edit("stop: 5.0", "stop: .inf"), [], ["disturbances[0].stop", ".inf"]),
    ("window-reversed", _edit("stop: 5.0", "stop: 3.0"), [],
     ["disturbances[0].stop", "start"]),
    ("force-1e300", _edit("force: [0.0, 50.0, 0.0]", "force: [0.0, 1.0e300, 0.0]"), [],
     ["disturbances[0].force[1]", "1e+300"]),
    ("gain-1e300", _edit("k_R: 250.0", "k_R: 1.0e300"), [], ["gains.k_R", "1e+300"]),
    ("gain-negative", _edit("K_x: [800.0, 800.0, 800.0]", "K_x: [-40.0, 800.0, 800.0]"), [],
     ["gains.K_x", "[-40.0, 800.0, 800.0]", ".yaml"]),
    ("gain-wrong-length", _edit("K_x: [800.0, 800.0, 800.0]", "K_x: [800.0]"), [],
     ["gains.K_x", "3"]),
    ("thrust-min-inf", _actuation("  thrust_min: .inf\n"), [],
     ["actuation.thrust_min", ".inf"]),
    ("thrust-max-below-min", _actuation("  thrust_max: -1.0\n"), [],
     ["actuation.thrust_max", "-1.0"]),
    ("arm-offset-length", _edit("arm_offset: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
                                "arm_offset: [0.0]"), [], ["initial.arm_offset"]),
    ("name-empty", _edit("name: nominal", "name: ''"), [], ["name", "''"]),
    ("name-only-dots", _edit("name: nominal", "name: '../..'"), [], ["name"]),
    ("start-time", _edit("target_realtime_rate: 0.0",
                         "target_realtime_rate: 0.0\n  start_time: 2.0"), [],
     ["simulator.start_time"]),
    # Options.
    (None, None, ["--duration", "1e7"], ["duration", "--duration"]),
    (None, None, ["--duration", "nan"], ["duration", ".nan"]),
    (None, None, ["--duration", "-1"], ["duration", "-1.0"]),
    (None, None, ["--duration", "100", "--max-log-mb", "1"], ["max_log_mb", "estimated log"]),
    (None, None, ["--max-log-mb", "-5"], ["max_log_mb", "-5.0"]),
    (None, None, ["--realtime-rate", "-1"], ["--realtime-rate", "-1"]),
    (None, None, ["--meshcat-port", "70000"], ["--meshcat-port", "70000"]),
    (None, None, ["--seed", "-3"], ["--seed", "-3"]),
]


def _ids():
    return [row[0] or " ".join(row[2]) for row in BAD_FILES]


def _run(tmp_path: Path, content, options, capsys) -> tuple[int, str, str]:
    if content is None:
        target = "nominal"
    else:
        path = tmp_path / "scenario.yaml"
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
        target = str(path)
    status = cli.main(["run", target, "--out", str(tmp_path / "out"), "--quiet", *options])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize("name,content,options,needles", BAD_FILES, ids=_ids())
def test_bad_input_is_refused_with_a_message_naming_the_field(tmp_path, capsys, name, content,
                                                              options, needles):
    status, out, err = _run(tmp_path, content, options, capsys)
    assert status == 2, err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    for needle in needles:
        assert needle in err, (needle, err)
    assert "Traceback" not in err + out
    assert "np.float64" not in err
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").rglob("*.npz"))


def test_json_prints_an_error_object_on_failure(tmp_path, capsys):
    status, out, err = _run(tmp_path, _actuation("  thrust_min: .inf\n"), ["--json"], capsys)
    assert status == 2
    error = json.loads(out)["error"]
    assert error["exit_status"] == 2 and error["field"] == "actuation.thrust_min"
    assert "actuation.thrust_min" in error["message"]


def test_a_folder_given_as_a_scenario_file(tmp_path, capsys):
    status = cli.main(["run", str(tmp_path), "--quiet"])
    err = capsys.readouterr().err
    assert status == 2 and "is a folder, not a scenario file" in err


def test_out_is_a_file(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    status = cli.main(["run", "nominal", "--out", str(tmp_path / "file"), "--quiet",
                       "--duration", "0.1"])
    err = capsys.readouterr().err
    assert status == 2 and "is a file, not a folder" in err and "Traceback" not in err


def test_unexpected_errors_are_one_line_unless_debug(monkeypatch, capsys):
    from aerial_drake.robots import models

    def broken(*args, **kwargs):
        raise KeyError("a bug")

    monkeypatch.setattr(models, "make_plant", broken)
    assert cli.main(["info"]) == 1
    err = capsys.readouterr().err
    assert "unexpected KeyError" in err and "--debug" in err and "Traceback" not in err
    with pytest.raises(KeyError):
        cli.main(["info", "--debug"])
