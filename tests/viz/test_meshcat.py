"""Meshcat: live view over HTTP, the scene tree, replay.html, safety, and a real browser.

All runs are short (0.3 s of simulation). The browser tests need Chromium (Debian:
``apt-get install -y chromium``; ``.ci/run`` installs it when run as root) and are skipped,
saying so, only where it is missing.
"""

import base64
import json
import re
import signal
import socket
import subprocess
import sys
import urllib.request
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RotationMatrix

from aerial_drake.cli import main as cli_main
from aerial_drake.control.law import diagnostics_slices
from aerial_drake.robots.models import make_plant
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import Disturbance, load_scenario, shipped_scenarios
from aerial_drake.viz import meshcat_view as dut
from aerial_drake.viz.screenshot import (
    colourful_fraction,
    find_chromium,
    open_page,
    replay_time_script,
    screenshot,
)
from processes import signal_at_first_progress

DURATION = 0.3  # s
#: Robot paths MeshcatVisualizer draws: /drake/visualizer/<model instance>/<body>.
ROBOT_PATHS = ("helicopter/helicopter", "lwr/lwr_link_1", "lwr/lwr_link_7")
ROTOR_PATHS = ("helicopter/rotor_left", "helicopter/rotor_right")


def short_scenario(name="nominal", **overrides):
    """``name`` for DURATION s, with both disturbance windows inside the run: the
    helicopter's over 0.1-0.2 s, the end effector's from 0.2 s to the end (so the last frame,
    which a replay stops on, shows the orange arrow)."""
    disturbances = [
        Disturbance(target="vehicle", start=0.1, stop=0.2, force=[0.0, 50.0, 0.0]),
        Disturbance(target="end_effector", start=0.2, stop=1.0, force=[40.0, 40.0, 40.0],
                    torque=[20.0, 20.0, 20.0]),
    ]
    return load_scenario(name, overrides={"duration": DURATION, "disturbances": disturbances,
                                          **overrides})


@pytest.fixture(scope="module")
def watched(tmp_path_factory):
    """One short run of the rotors plant watched live on a free port, its replay written."""
    scenario = short_scenario("disturbed" if "disturbed" in shipped_scenarios() else "nominal",
                              plant_variant="rotors")
    view = dut.MeshcatView(scenario, port=0)
    out = tmp_path_factory.mktemp("watched")
    result = run_scenario(scenario, out_dir=out, progress=False, configure=view.configure,
                          extra_files=view.finish)
    replay = out / dut.REPLAY_FILE
    return view, result, replay


def _replay_blobs(html: str) -> list[bytes]:
    """The msgpack commands embedded in a replay.html (base64 data: URLs)."""
    return [base64.b64decode(b) for b in
            re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)]


# --- The live server and the scene tree -------------------------------------------------------

def test_live_page_answers_over_http(watched):
    view, _, _ = watched
    assert view.url.startswith("http://localhost:")
    with urllib.request.urlopen(view.url, timeout=10) as response:
        assert response.status == 200
        page = response.read().decode()
    assert "meshcat" in page.lower() and "<html" in page.lower()


def test_scene_holds_robot_paths_and_overlays(watched):
    view, _, _ = watched
    for path in ROBOT_PATHS + ROTOR_PATHS:
        assert view.meshcat.HasPath(f"{dut.ROBOT_PREFIX}/{path}"), path
    for name in dut.OVERLAY_PATHS:
        assert view.meshcat.HasPath(view.overlay.path(name)), name
    assert view.meshcat.HasPath(f"{dut.OVERLAY_PREFIX}/ee_path")  # the trajectory line
    assert not view.meshcat.HasPath(f"{dut.OVERLAY_PREFIX}/no_such_thing")
    with pytest.raises(ValueError, match="Valid names are"):
        view.overlay.path("trajectory")


def test_listens_on_localhost_only(watched):
    """Bound to 127.0.0.1 (or ::1), not to every interface (Linux: /proc/net/tcp*)."""
    view, _, _ = watched
    port = view.meshcat.port()
    tables = [Path(p) for p in ("/proc/net/tcp", "/proc/net/tcp6") if Path(p).exists()]
    if not tables:
        pytest.skip("no /proc/net/tcp on this system")
    listening = []
    for table in tables:
        for line in table.read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if state == "0A" and int(hex_port, 16) == port:  # 0A = LISTEN
                listening.append(address)
    assert listening, f"nothing listens on port {port}"
    loopback = {"0100007F", "00000000000000000000000001000000"}
    assert set(listening) <= loopback, listening


# --- Recording ----------------------------------------------------------------------------

def test_replay_animates_robot_and_overlays(watched):
    _, result, replay = watched
    html = replay.read_text()
    assert html.lstrip().lower().startswith("<!doctype html") or "<html" in html[:500].lower()
    blobs = _replay_blobs(html)
    animations = [b for b in blobs if b"set_animation" in b]
    assert len(animations) == 1
    animation = animations[0]
    for path in ROBOT_PATHS + ROTOR_PATHS:
        assert f"{dut.ROBOT_PREFIX}/{path}".encode() in animation, path
    for name in ("ee_actual", "ee_desired", "com_actual", "com_desired",
                 "base_attitude_desired", "force_vehicle", "force_end_effector"):
        assert f"{dut.OVERLAY_PREFIX}/{name}".encode() in animation, name
    assert b"visible" in animation  # the arrows come and go with their windows
    assert b"/drake/contact_forces" not in b"".join(blobs)  # no environment, no contact arrows
    # The static lines are objects of the scene (animations carry no objects).
    scene = b"".join(b for b in blobs if b"set_object" in b)
    assert f"{dut.OVERLAY_PREFIX}/ee_path".encode() in scene
    assert f"{dut.OVERLAY_PREFIX}/com_path".encode() in scene
    assert result.metrics["simulated_time_s"] == pytest.approx(DURATION)


def test_drawn_base_attitude_is_the_controllers(watched):
    """The overlay's R_d, with the logged base attitude R, gives the logged e_R of (14):
    e_R = vee(1/2 (R_d^T R - R^T R_d)), at every 20 ms frame of the run."""
    view, result, _ = watched
    log = result.log
    rigid, simulated = make_plant("rigid"), make_plant(result.scenario.plant_variant)
    context = rigid.plant.CreateDefaultContext()
    e_R_slice = diagnostics_slices(rigid.n)["e_R"]
    frames = np.flatnonzero(np.isclose(np.mod(log["t"] + 1e-9, dut.PUBLISH_PERIOD), 0.0,
                                       atol=1e-6))
    assert len(frames) >= 10
    for k in frames:
        R_d = view.overlay.desired_base_attitude(log["plant_state"][k], log["com_reference"][k],
                                                 log["heading_reference"][k])
        rigid.plant.SetPositionsAndVelocities(
            context, log["plant_state"][k][simulated.rigid_state_indices])
        R = rigid.plant.EvalBodyPoseInWorld(context, rigid.base_body).rotation().matrix()
        A = 0.5 * (R_d.T @ R - R.T @ R_d)
        e_R = np.array([A[2, 1], A[0, 2], A[1, 0]])
        np.testing.assert_allclose(e_R, log["diagnostics"][k][e_R_slice], atol=1e-9,
                                   err_msg=f"t = {log['t'][k]}")


def test_watching_changes_no_number():
    """The 20 ms frames fall on the 1 ms steps: a watched run logs exactly what an unwatched
    one does, with the same number of control-law evaluations."""
    scenario = short_scenario()
    plain = run_scenario(scenario, progress=False)
    view = dut.MeshcatView(scenario, port=0, live=False)
    watched_run = run_scenario(scenario, progress=False, configure=view.configure)
    assert plain.log.keys() == watched_run.log.keys()
    for key in plain.log:
        np.testing.assert_array_equal(plain.log[key], watched_run.log[key], err_msg=key)
    assert (plain.metrics["controller_evaluations"]
            == watched_run.metrics["controller_evaluations"])


def test_realtime_rate_paces_the_run():
    scenario = load_scenario("nominal", overrides={"duration": 0.2})
    result = run_scenario(scenario, progress=False, realtime_rate=0.2)
    assert result.wall_time_s >= 0.2 / 0.2 * 0.95


def test_arrow_rotation_points_z_along_the_force():
    for force in ([0, 50, 0], [40, 40, 40], [1, 0, 0], [0, 0, -3], [1e-3, -2, 5]):
        f = np.asarray(force, float)
        R = dut._z_towards(f).matrix()
        np.testing.assert_allclose(R[:, 2], f / np.linalg.norm(f), atol=1e-12)
        np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)


# --- Safety: busy ports, the command line, Ctrl-C -----------------------------------------

def test_busy_port_is_a_clear_error(tmp_path, capsys):
    with socket.socket() as taken:
        taken.bind(("localhost", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(dut.MeshcatPortInUse, match=f"port {port}.*--meshcat-port 0"):
            dut.start_meshcat(port=port)
        code = cli_main(["run", "nominal", "--duration", "0.1", "--meshcat", "--meshcat-port",
                         str(port), "--out", str(tmp_path)])
    assert code == 2
    assert f"port {port}" in capsys.readouterr().err
    assert not (tmp_path / "nominal").exists()  # nothing ran


def _cli(*args):
    return [sys.executable, "-m", "aerial_drake", "run", "nominal", *args]


def test_cli_meshcat_run_prints_url_writes_replay_and_exits(tmp_path):
    # --no-wait: no browser here (tests/viz/test_live.py covers the wait for one).
    done = subprocess.run(_cli("--duration", "0.2", "--meshcat", "--meshcat-port", "0",
                               "--quiet", "--no-wait", "--no-plots", "--out", str(tmp_path)),
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert re.search(r"Meshcat: open http://localhost:\d+", done.stdout)
    assert (done.stdout + done.stderr).count("http://") == 1  # the URL once, not Drake's too
    for name in ("log.npz", "metrics.json", "replay.html"):
        assert (tmp_path / "nominal" / name).is_file(), name


def test_ctrl_c_stops_cleanly_and_writes_what_was_logged(tmp_path):
    # Signalled at its first progress line (t = 1 s simulated), whatever the machine's speed
    # (a fixed sleep raced the model's build).
    status, output = signal_at_first_progress(
        _cli("--duration", "30", "--record", "--out", str(tmp_path)), signal.SIGINT)
    assert status == 130, output
    assert "interrupted (Ctrl-C)" in output
    out = tmp_path / "nominal"
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["completed"] is False
    assert metrics["failure"].startswith("interrupted (Ctrl-C) at t = ")
    assert 0.0 < metrics["simulated_time_s"] < 30.0
    assert (out / "log.npz").stat().st_size > 0
    assert b"set_animation" in b"".join(_replay_blobs((out / "replay.html").read_text()))


# --- A real browser -----------------------------------------------------------------------

#: The middle of the picture, where the camera puts the robot.
ROBOT_AREA = (0.2, 0.15, 0.8, 0.85)
#: Minimum share of coloured pixels there (an empty Meshcat scene has none: it is grey).
MIN_COLOURED = 0.01


@pytest.fixture(scope="module")
def chromium():
    path = find_chromium()
    if path is None:
        pytest.skip("Chromium is not installed (Debian: apt-get install -y chromium; "
                    ".ci/run installs it when run as root)")
    return path


def test_browser_live_page_renders_the_robot(watched, chromium, tmp_path):
    view, _, _ = watched
    png = screenshot(view.url, tmp_path / "live.png", size=(800, 600), chromium=chromium)
    assert matplotlib.image.imread(str(png)).shape[:2] == (600, 800)
    coloured = colourful_fraction(png, ROBOT_AREA)
    assert coloured > MIN_COLOURED, f"live page: only {coloured:.2%} coloured pixels ({png})"


def _logged_poses(result, t):
    """(p_WE, p_WG, p_WB) of the run's logged state at time t."""
    simulated = make_plant(result.scenario.plant_variant)
    rigid = make_plant("rigid")
    context = rigid.plant.CreateDefaultContext()
    k = int(np.argmin(np.abs(result.log["t"] - t)))
    assert abs(result.log["t"][k] - t) < 1e-9
    x = result.log["plant_state"][k][simulated.rigid_state_indices]
    rigid.plant.SetPositionsAndVelocities(context, x)
    return (rigid.end_effector_frame.CalcPoseInWorld(context).translation(),
            rigid.plant.CalcCenterOfMassPositionInWorld(context),
            rigid.plant.EvalBodyPoseInWorld(context, rigid.base_body).translation())


#: JavaScript: the three.js object at a Meshcat path, and what a test reads of it.
_NODE = 'viewer.scene_tree.find({path}).object'


def _read(page, path):
    parts = json.dumps([p for p in path.split("/") if p])
    node = _NODE.format(path=parts)
    return page.evaluate(f"({{visible: {node}.visible, position: {node}.position.toArray()}})")


def test_browser_replay_shows_robot_and_animates_overlays(watched, chromium, tmp_path):
    """replay.html opened from file:// in Chromium: the robot is drawn, and stopping its
    animation at frames of the run puts the robot and the overlays where the log says they
    were, with each force arrow shown exactly while its window acts."""
    _, result, replay = watched
    with open_page(replay.resolve().as_uri(), size=(800, 600), chromium=chromium) as page:
        png = page.capture(tmp_path / "replay.png")
        coloured = colourful_fraction(png, ROBOT_AREA)
        assert coloured > MIN_COLOURED, f"replay: only {coloured:.2%} coloured pixels ({png})"
        assert page.evaluate("viewer.animator.duration") == pytest.approx(DURATION, abs=1e-6)
        for t in (0.06, 0.16, 0.26):  # frames (20 ms) before, in, after the 0.1-0.2 s window
            page.evaluate(replay_time_script(t))
            p_WE, p_WG, p_WB = _logged_poses(result, t)
            ee = _read(page, f"{dut.OVERLAY_PREFIX}/ee_actual")
            com = _read(page, f"{dut.OVERLAY_PREFIX}/com_actual")
            body = _read(page, f"{dut.ROBOT_PREFIX}/helicopter/helicopter")
            np.testing.assert_allclose(ee["position"], p_WE, atol=1e-5, err_msg=f"t={t}")
            np.testing.assert_allclose(com["position"], p_WG, atol=1e-5, err_msg=f"t={t}")
            np.testing.assert_allclose(body["position"], p_WB, atol=1e-5, err_msg=f"t={t}")
            heli = _read(page, f"{dut.OVERLAY_PREFIX}/force_vehicle")
            end = _read(page, f"{dut.OVERLAY_PREFIX}/force_end_effector")
            assert heli["visible"] == (0.1 <= t < 0.2), t
            assert end["visible"] == (t >= 0.2), t
            if heli["visible"]:
                np.testing.assert_allclose(heli["position"], p_WB, atol=1e-5)
        # The rotors turn relative to the fuselage by their speed times the 20 ms frame.
        speed = result.scenario.rotors.speed
        assert speed > 0
        R_BR = []
        for t in (0.20, 0.22):
            page.evaluate(replay_time_script(t))
            R = {}
            for body in ("helicopter", "rotor_left"):
                x, y, z, w = page.evaluate(
                    _NODE.format(path=json.dumps(["drake", "visualizer", "helicopter", body]))
                    + ".quaternion.toArray()")
                R[body] = RotationMatrix(Quaternion(w, x, y, z)).matrix()
            R_BR.append(R["helicopter"].T @ R["rotor_left"])
        step = R_BR[0].T @ R_BR[1]  # a turn about the rotor's own axis z
        np.testing.assert_allclose(step[:, 2], [0, 0, 1], atol=1e-5)
        turned = np.arctan2(step[1, 0], step[0, 0])
        assert turned == pytest.approx(speed * dut.PUBLISH_PERIOD, rel=0.01)  # 1.63 rad


def test_browser_empty_scene_is_not_coloured(chromium, tmp_path):
    """The measure above tells an empty Meshcat scene from one with the robot."""
    meshcat = dut.start_meshcat(port=0)
    png = screenshot(meshcat.web_url(), tmp_path / "empty.png", size=(800, 600),
                     chromium=chromium)
    # Only the World axes at the origin are coloured (0.1 %; the robot's scene: 3.6 %).
    assert colourful_fraction(png, ROBOT_AREA) < 0.5 * MIN_COLOURED
