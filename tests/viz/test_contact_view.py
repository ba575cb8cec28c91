"""Drake's contact visualizer in the Meshcat view: added only with an environment, and its
arrows recorded in replay.html, where they follow the log's contact wrench frame by frame.

One 4 s wall press (the end effector touches the wall at about 3.4 s and presses 10 N): the
recorded run, and the same run unwatched. The browser test needs Chromium and is skipped,
saying so, where it is missing.
"""

import base64
import re
import time

import msgpack
import numpy as np
import pytest
from pydrake.common.eigen_geometry import Quaternion

from aerial_drake.simulation.contact import contact_slices
from aerial_drake.simulation.diagram import build_simulation
from aerial_drake.simulation.runner import run_scenario
from aerial_drake.simulation.scenarios import load_scenario
from aerial_drake.viz import contact_view as dut
from aerial_drake.viz.meshcat_view import PUBLISH_PERIOD, MeshcatView
from aerial_drake.viz.screenshot import find_chromium, open_page, replay_time_script

DURATION = 4.5  # s
CONTACT_PATH = f"/drake/{dut.CONTACT_PREFIX}/point/"
#: (camera, target) in World: beside and below the tool (-y), looking at the touch.
SIDE_CAMERA = (np.array([0.1, -1.7, 1.15]), np.array([0.75, 0.0, 1.45]))


@pytest.fixture(scope="module")
def wall_press():
    """The shipped wall press up to half a second after the touch (about 3.8 s)."""
    return load_scenario("wall_press", overrides={"duration": DURATION})


@pytest.fixture(scope="module")
def recorded(wall_press, tmp_path_factory):
    """The wall press recorded (not live) on a free port; its result and replay.html.
    The camera looks from the robot's side of the wall (SIDE_CAMERA; the view's own looks
    from +x, through the wall)."""
    view = MeshcatView(wall_press, port=0, live=False)
    out = tmp_path_factory.mktemp("recorded")

    def configure(builder, loop):
        view.configure(builder, loop)
        view.meshcat.SetCameraPose(*SIDE_CAMERA)

    result = run_scenario(wall_press, out_dir=out, progress=False, configure=configure,
                          extra_files=view.finish)
    return view, result, out / "replay.html"


def _animation(html: str) -> dict:
    """The replay's set_animation command (msgpack in a base64 data: URL)."""
    for blob in re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html):
        message = msgpack.unpackb(base64.b64decode(blob), raw=False, strict_map_key=False)
        if message.get("type") == "set_animation":
            return message
    raise AssertionError("replay.html holds no animation")


def _tracks(animation: dict, prefix: str) -> dict[tuple[str, str], list[dict]]:
    """(path, property) -> keyframes, for every animated path under ``prefix``."""
    return {(a["path"], track["name"].lstrip(".")): track["keys"]
            for a in animation["animations"] if a["path"].startswith(prefix)
            for track in a["clip"]["tracks"]}


def _step(keys: list[dict], frame: int):
    """A discrete track's value at ``frame``, as three.js plays it: the last key at or
    before it, the first key's before any."""
    value = keys[0]["value"]
    for key in keys:
        if key["time"] > frame:
            break
        value = key["value"]
    return value


def test_params_make_ten_newtons_half_a_metre():
    params = dut.contact_visualizer_params(PUBLISH_PERIOD)
    assert params.publish_period == PUBLISH_PERIOD
    assert params.prefix == dut.CONTACT_PREFIX
    assert 10.0 / params.newtons_per_meter == pytest.approx(0.5)


def test_no_contact_visualizer_without_an_environment():
    """The paper's runs (no environment, no contact_wrench output) get no new system."""
    scenario = load_scenario("nominal", overrides={"duration": 0.1})
    builder, loop, _ = build_simulation(scenario)
    assert not loop.has_output_port("contact_wrench")
    view = MeshcatView(scenario, port=0, live=False)
    view.configure(builder, loop)
    assert view.contact_visualizer is None
    names = [system.get_name() for system in builder.GetSystems()]
    assert "meshcat_contact_forces" not in names
    view.finish()


def test_replay_animates_the_contact_force_as_logged(recorded):
    """Each 20 ms frame of replay.html shows the arrow exactly while the log has a contact,
    at the logged contact point, along the logged force, |f| / NEWTONS_PER_METER long."""
    view, result, replay = recorded
    assert view.contact_visualizer is not None
    animation = _animation(replay.read_text())
    tracks = _tracks(animation, CONTACT_PATH)
    paths = {path for path, _ in tracks if "/" not in path[len(CONTACT_PATH):]}
    end_effector = result.scenario.controller_model().end_effector_frame.body().name()
    assert len(paths) == 1, paths  # one pair: the tool and the wall
    (path,) = paths
    assert path.rsplit("/", 1)[-1] in (f"{end_effector}+wall", f"wall+{end_effector}"), path
    fps = animation["animations"][0]["clip"]["fps"]
    assert fps == pytest.approx(1.0 / PUBLISH_PERIOD)

    log, at = result.log, contact_slices()
    wrench = log["contact_wrench"]
    threshold = dut.contact_visualizer_params(PUBLISH_PERIOD).force_threshold
    shown = []
    for frame in range(int(round(DURATION * fps)) + 1):
        (k,) = np.flatnonzero(np.isclose(log["t"], frame / fps, atol=1e-9))
        force = wrench[k][at["force"]]
        in_contact = wrench[k][at["contacts"]][0] > 0
        expected = bool(in_contact and np.linalg.norm(force) >= threshold)
        visible = _step(tracks[(path, "visible")], frame)
        assert visible == expected, f"frame {frame} (t = {frame / fps:g} s)"
        if not visible:
            continue
        shown.append(frame)
        # Meshcat files a publication at time t under frame floor(t fps): on the continuous
        # plant the simulator's time gathers round-off, and a publication at (f + 1) / fps
        # may land just below it, in frame f. So a frame shows the logged sample at its time
        # or the next frame's (and a frame left without a key of its own keeps the one
        # before, as three.js plays a discrete track).
        candidates = [k + j * int(round(1.0 / (fps * result.scenario.log_period)))
                      for j in (0, 1) if k + j < len(log["t"])]
        scale, position, rotation = (_step(tracks[key], frame) for key in (
            (path + "/cylinder", "scale"), (path, "position"), (path, "quaternion")))
        assert any(_shows(scale[2], position, rotation,
                          wrench[c][at["force"]], wrench[c][at["point"]])
                   for c in candidates), f"frame {frame} (t = {frame / fps:g} s)"
    # Pressing for the last half second or more, and not before the touch.
    assert len(shown) >= 25, shown
    assert shown == list(range(shown[0], shown[-1] + 1))
    assert np.linalg.norm(wrench[-1][at["force"]]) > 5.0  # the press is on at the end


def _shows(length, position, rotation, force, point) -> bool:
    """Whether an arrow of ``length``, at ``position``, turned by the three.js quaternion
    ``rotation`` draws ``force`` at ``point``."""
    size = np.linalg.norm(force)
    x, y, z, w = rotation  # three.js order
    axis = Quaternion(w, x, y, z).rotation()[:, 2]
    return bool(abs(length - size / dut.NEWTONS_PER_METER) <= 1e-9 * size
                and np.allclose(position, point, atol=1e-9)
                and abs(abs(axis @ force) - size) < 1e-6 * size)


def test_watching_contact_changes_no_number(wall_press, recorded):
    """The contact visualizer publishes on the 1 ms steps: the recorded run logs exactly
    what an unwatched one does."""
    _, watched, _ = recorded
    plain = run_scenario(wall_press, progress=False)
    assert plain.log.keys() == watched.log.keys()
    for key in plain.log:
        np.testing.assert_array_equal(plain.log[key], watched.log[key], err_msg=key)


@pytest.fixture(scope="module")
def chromium():
    path = find_chromium()
    if path is None:
        pytest.skip("Chromium is not installed (Debian: apt-get install -y chromium)")
    return path


def _purple_pixels(png) -> int:
    """Pixels of about CONTACT_COLOR's hue: blue and red well above green."""
    import matplotlib.image

    image = matplotlib.image.imread(str(png))[..., :3].astype(float)
    r, g, b = image[..., 0], image[..., 1], image[..., 2]
    return int(np.sum((b > g + 0.3) & (r > g + 0.15) & (b > r)))


def test_browser_replay_draws_the_arrow_in_contact_only(recorded, chromium, tmp_path):
    """replay.html in Chromium (SIDE_CAMERA): purple pixels (the arrow) at 4.3 s, in
    contact, and none at 2.0 s, before the touch."""
    _, _, replay = recorded
    with open_page(replay.resolve().as_uri(), size=(800, 600), chromium=chromium) as page:
        counts = {}
        for t in (2.0, 4.3):
            page.evaluate(replay_time_script(t))
            time.sleep(1.0)
            counts[t] = _purple_pixels(page.capture(tmp_path / f"replay_{t:g}.png"))
    assert counts[2.0] < 20, counts
    assert counts[4.3] > 200, counts
