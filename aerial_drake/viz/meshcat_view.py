"""Watch a run in a browser: Drake's Meshcat, live and recorded to a self-contained replay.

:class:`MeshcatView` is one run's Meshcat. Its :meth:`MeshcatView.configure` is the runner's
``configure(builder, loop)`` hook: it adds Drake's ``MeshcatVisualizer`` for the simulated
plant's illustration geometry (the rotors, in the ``rotors`` variant, are bodies and spin),
a :class:`TrackingOverlay`, a camera that keeps the robot in view over the whole run
(:func:`aerial_drake.viz.camera.camera_for`), and starts recording.
:meth:`MeshcatView.finish` stops the recording, publishes it (a live browser gets the playback
controls) and writes ``replay.html`` (``Meshcat.StaticHtml()``: three.js and the whole
animation in one file; opens offline from ``file://``).

What :class:`TrackingOverlay` draws, under ``/drake/overlays`` (``OVERLAY_PATHS``):

- the desired end-effector path x_ed(t) (magenta line) and the desired CoM path x_d(t) (cyan
  line), sampled once over the run from the run's reference (``loop.reference.source``);
- the desired end-effector frame (p_ed, R_ed) as a long, thin, translucent triad and the actual
  one (the plant's frame E) as a short, thick, opaque triad (x red, y green, z blue);
- the desired CoM x_d (translucent cyan sphere) and the actual CoM (small navy sphere); the CoM
  is about 0.15 m under the helicopter frame, inside the fuselage, so the robot is drawn at
  ``ROBOT_ALPHA`` opacity (the alpha slider of the live view changes it);
- the desired base attitude R_d of (12)-(13) as a faint, long triad at the actual CoM. R_d is
  recomputed here from the references and the plant state with the controller's own formulas:
  f_d of (10) from the actual CoM position and velocity, then
  :func:`aerial_drake.control.law.desired_attitude` with b1d. The frames fall on the controller's
  1 kHz samples, so it is the controller's R_d of that sample (``tests/viz/test_meshcat.py``
  rebuilds the logged e_R from it); the diagnostics port carries e_R only, and evaluating it
  here would run the control law an extra time per frame;
- the disturbance forces while a window is active, as arrows starting at their points of
  application, ``FORCE_SCALE`` m per N: green on the helicopter frame origin, orange on the
  end-effector point (the paper's green and orange windows). Torques are not drawn.

With an environment (the closed loop's ``contact_wrench`` output), Drake's
``ContactVisualizer`` also draws the contact forces, under ``/drake/contact_forces``
(:mod:`aerial_drake.viz.contact_view`).

Every pose and visibility is sent with ``time_in_recording`` = the simulation time, so the
overlays animate in ``replay.html`` as the robot does.

Publishing every ``PUBLISH_PERIOD`` = 20 ms (50 Hz): a multiple of the 1 ms controller and log
periods, so watching adds no integrator step and leaves the logged numbers unchanged
(``tests/viz/test_meshcat.py`` holds a watched and an unwatched run equal). At 26 pi rad/s the
rotors turn 94 deg per frame, under the 180 deg of the two-bladed rotor's symmetry, so the
replay's interpolation shows them turning the right way.

Safety: Meshcat listens on ``localhost`` unless told otherwise (:func:`start_meshcat`). Without
a port Drake takes the first free one of 7000-7099; port 0 takes any free port; a port that is
busy is an error (:class:`MeshcatPortInUse`), never silently another one.
"""

from __future__ import annotations

import numpy as np
from pydrake.geometry import (
    Cylinder,
    Meshcat,
    MeshcatCone,
    MeshcatParams,
    MeshcatVisualizer,
    MeshcatVisualizerParams,
    Rgba,
    Role,
    Sphere,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.meshcat import ContactVisualizer
from pydrake.systems.framework import Context, DiagramBuilder, EventStatus, LeafSystem

from aerial_drake.control.law import desired_attitude, desired_force
from aerial_drake.robots.models import AerialManipulator
from aerial_drake.simulation.diagram import ClosedLoop
from aerial_drake.simulation.scenarios import Scenario
from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
    unpack_com_reference,
    unpack_heading_reference,
    unpack_task_reference,
)
from aerial_drake.viz.camera import camera_for
from aerial_drake.viz.contact_view import add_contact_visualizer

#: Seconds between frames (live and recorded), for the robot and the overlays.
PUBLISH_PERIOD = 0.02
#: The replay's file name in a run's folder.
REPLAY_FILE = "replay.html"
#: Where the overlays live in the Meshcat scene tree.
OVERLAY_PREFIX = "/drake/overlays"
#: Where MeshcatVisualizer puts the robot (``/drake/<prefix>/<model>/<body>/...``).
ROBOT_PREFIX = "/drake/visualizer"
#: Opacity of the robot, so the CoM markers inside the fuselage show.
ROBOT_ALPHA = 0.7
#: Length of a disturbance-force arrow per newton of force (m/N).
FORCE_SCALE = 0.01
#: Samples per second of the drawn reference paths.
PATH_RATE = 100.0

_HEAD_LENGTH = 0.12  # m, of an arrow's head
_TRIAD_RGB = ((0.9, 0.1, 0.1), (0.1, 0.75, 0.1), (0.1, 0.2, 0.9))
_VEHICLE_GREEN = Rgba(0.1, 0.7, 0.2, 1.0)
_END_EFFECTOR_ORANGE = Rgba(1.0, 0.5, 0.0, 1.0)

#: Overlay paths (under ``OVERLAY_PREFIX``) and what they show.
OVERLAY_PATHS = {
    "ee_path": "desired end-effector path x_ed(t) (line)",
    "com_path": "desired CoM path x_d(t) (line)",
    "ee_desired": "desired end-effector frame (p_ed, R_ed) (triad)",
    "ee_actual": "actual end-effector frame E (triad)",
    "com_desired": "desired CoM x_d (sphere)",
    "com_actual": "actual CoM (sphere)",
    "base_attitude_desired": "desired base attitude R_d at the actual CoM (faint triad)",
    "force_vehicle": "disturbance force on the vehicle (green arrow)",
    "force_end_effector": "disturbance force on the end effector (orange arrow)",
}


class MeshcatPortInUse(RuntimeError):
    """The requested Meshcat port is taken."""


def start_meshcat(host: str = "localhost", port: int | None = None) -> Meshcat:
    """A Meshcat server on ``host`` (default: this machine only).

    ``port`` None: the first free port of 7000-7099 (Drake's choice); 0: any free port; else
    exactly that port, and :class:`MeshcatPortInUse` if it is taken.
    """
    params = MeshcatParams()
    params.host = host
    if port is not None:
        if not 0 <= port <= 65535:
            raise ValueError(f"Meshcat port must be in 0..65535, got {port}")
        params.port = port
    try:
        return Meshcat(params)
    except RuntimeError as err:
        where = f"port {port}" if port is not None else "any port of 7000-7099"
        raise MeshcatPortInUse(
            f"Meshcat could not listen on {host}, {where}: another program (or another "
            "aerial-drake run) probably holds it. Pass --meshcat-port with a free port, or "
            f"--meshcat-port 0 for any free one. (Drake: {str(err).strip()})") from err


def _triad(meshcat: Meshcat, path: str, length: float, radius: float, alpha: float) -> None:
    """Three cylinders along the x (red), y (green), z (blue) axes of ``path``."""
    poses = (RigidTransform(RotationMatrix.MakeYRotation(np.pi / 2), [length / 2, 0, 0]),
             RigidTransform(RotationMatrix.MakeXRotation(-np.pi / 2), [0, length / 2, 0]),
             RigidTransform([0, 0, length / 2]))
    for name, rgb, X in zip("xyz", _TRIAD_RGB, poses):
        meshcat.SetObject(f"{path}/{name}", Cylinder(radius, length), Rgba(*rgb, alpha))
        meshcat.SetTransform(f"{path}/{name}", X)


def _arrow(meshcat: Meshcat, path: str, rgba: Rgba) -> None:
    """An arrow along +z of ``path``: a unit shaft (scaled per frame) and a head."""
    meshcat.SetObject(f"{path}/shaft", Cylinder(0.02, 1.0), rgba)
    meshcat.SetObject(f"{path}/head", MeshcatCone(_HEAD_LENGTH, 0.05, 0.05), rgba)


def _z_towards(direction: np.ndarray) -> RotationMatrix:
    """A rotation whose z axis is the unit vector ``direction``."""
    z = direction / np.linalg.norm(direction)
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return RotationMatrix(np.column_stack([x, np.cross(z, x), z]))


class TrackingOverlay(LeafSystem):
    """Draws the references, the actual task frames and the disturbances in Meshcat.

    Input ports (connect them to the closed loop's exported outputs and the disturbance
    sources, as :meth:`MeshcatView.configure` does):

    - ``plant_state``: the simulated plant's state (either variant).
    - ``com_reference`` (15), ``task_reference`` (24 + 3 n_j), ``heading_reference`` (9).
    - ``vehicle_wrench``, ``end_effector_wrench``: ``[torque; force]`` in World (6).

    A periodic publish (``publish_period``) sends every pose with the simulation time as the
    recording time; an initialization publish (re)draws the static objects. The actual
    end-effector pose and CoM come from the robot's rigid model (the controller's) in
    this system's own context, fed with the simulated state mapped by ``rigid_state_indices``.
    ``reference``: the run's, whose paths are drawn (None: built from ``scenario.trajectory``).
    """

    def __init__(self, meshcat: Meshcat, scenario: Scenario, simulated_plant: AerialManipulator,
                 *, publish_period: float = PUBLISH_PERIOD, prefix: str = OVERLAY_PREFIX,
                 reference: ReferenceSource | None = None):
        super().__init__()
        self._meshcat = meshcat
        self._prefix = prefix
        self._model = scenario.controller_model()
        plant = self._model.plant
        self._context = plant.CreateDefaultContext()
        self._state_indices = simulated_plant.rigid_state_indices
        self._mass = plant.CalcTotalMass(self._context)
        self._gravity = -plant.gravity_field().gravity_vector()[2]
        self._K_x = np.asarray(scenario.gains.K_x, dtype=float)
        self._D_x = np.asarray(scenario.gains.D_x, dtype=float)
        times = np.linspace(0.0, scenario.duration,
                            int(round(scenario.duration * PATH_RATE)) + 1)
        reference = reference or reference_of(scenario.trajectory,
                                              self._model.task_joint_nominal())
        ref = reference.sample(times)
        self._ee_path, self._com_path = ref.p_ed.T.copy(), ref.com[:, 0].T.copy()
        # arrow path -> visible, to send a visibility only when it changes
        self._shown: dict[str, bool] = {}

        nx = simulated_plant.plant.num_positions() + simulated_plant.plant.num_velocities()
        self._state_port = self.DeclareVectorInputPort("plant_state", nx)
        self._com_port = self.DeclareVectorInputPort("com_reference", COM_REFERENCE_SIZE)
        assert self._model.task is not None
        self._task_port = self.DeclareVectorInputPort(
            "task_reference", task_reference_size(self._model.task.n_joints))
        self._heading_port = self.DeclareVectorInputPort("heading_reference",
                                                         HEADING_REFERENCE_SIZE)
        self._vehicle_port = self.DeclareVectorInputPort("vehicle_wrench", 6)
        self._ee_port = self.DeclareVectorInputPort("end_effector_wrench", 6)
        self.DeclareInitializationPublishEvent(self._draw_static)
        self.DeclarePeriodicPublishEvent(publish_period, 0.0, self._draw_frame)

    def path(self, name: str) -> str:
        """The Meshcat path of the overlay ``name`` (a key of ``OVERLAY_PATHS``)."""
        if name not in OVERLAY_PATHS:
            raise ValueError(f"Unknown overlay '{name}'. Valid names are: "
                             f"{', '.join(OVERLAY_PATHS)}")
        return f"{self._prefix}/{name}"

    def _draw_static(self, context: Context) -> EventStatus:
        m, p = self._meshcat, self.path
        m.Delete(self._prefix)
        m.SetLine(p("ee_path"), self._ee_path, 2.0, Rgba(0.85, 0.1, 0.6, 1.0))
        m.SetLine(p("com_path"), self._com_path, 2.0, Rgba(0.0, 0.65, 0.75, 1.0))
        _triad(m, p("ee_desired"), length=0.3, radius=0.005, alpha=0.6)
        _triad(m, p("ee_actual"), length=0.18, radius=0.012, alpha=1.0)
        _triad(m, p("base_attitude_desired"), length=0.6, radius=0.008, alpha=0.3)
        m.SetObject(p("com_desired"), Sphere(0.05), Rgba(0.0, 0.75, 0.85, 0.6))
        m.SetObject(p("com_actual"), Sphere(0.035), Rgba(0.05, 0.05, 0.35, 1.0))
        _arrow(m, p("force_vehicle"), _VEHICLE_GREEN)
        _arrow(m, p("force_end_effector"), _END_EFFECTOR_ORANGE)
        self._shown = {}
        return self._draw_frame(context)

    def _draw_frame(self, context: Context) -> EventStatus:
        t = context.get_time()
        m, p = self._meshcat, self.path
        plant = self._model.plant
        plant.SetPositionsAndVelocities(
            self._context, self._state_port.Eval(context)[self._state_indices])
        X_WE = self._model.end_effector_frame.CalcPoseInWorld(self._context)
        X_WB = plant.EvalBodyPoseInWorld(self._context, self._model.base_body)
        p_WG = plant.CalcCenterOfMassPositionInWorld(self._context)
        v_WG = plant.CalcCenterOfMassTranslationalVelocityInWorld(self._context)
        com = unpack_com_reference(self._com_port.Eval(context))
        task = unpack_task_reference(self._task_port.Eval(context))
        b1d = unpack_heading_reference(self._heading_port.Eval(context))

        m.SetTransform(p("ee_actual"), X_WE, t)
        m.SetTransform(p("ee_desired"), RigidTransform(RotationMatrix(task.R_ed), task.p_ed), t)
        m.SetTransform(p("com_actual"), RigidTransform(p_WG), t)
        m.SetTransform(p("com_desired"), RigidTransform(com[0]), t)
        R_d = self._desired_base_attitude(p_WG, v_WG, com, b1d)
        if R_d is not None:
            m.SetTransform(p("base_attitude_desired"),
                           RigidTransform(RotationMatrix(R_d), p_WG), t)
        # Disturbance forces at their points of application.
        for name, port, point in (("force_vehicle", self._vehicle_port, X_WB.translation()),
                                  ("force_end_effector", self._ee_port, X_WE.translation())):
            self._draw_force(p(name), port.Eval(context)[3:], point, t)
        return EventStatus.Succeeded()

    def _desired_base_attitude(self, p_WG, v_WG, com, b1d) -> np.ndarray | None:
        """R_d of (12)-(13) for the CoM at p_WG moving at v_WG (None if f_d vanishes)."""
        f_d = desired_force(self._mass, self._gravity, com, p_WG - com[0], v_WG - com[1],
                            self._K_x, self._D_x)  # (10)
        if not np.linalg.norm(f_d) > 1e-9:
            return None
        zero = np.zeros(3)  # R_d itself needs neither f_d' nor f_d''
        return desired_attitude(f_d, zero, zero, b1d)[0]

    def desired_base_attitude(self, plant_state: np.ndarray, com_reference: np.ndarray,
                              heading_reference: np.ndarray) -> np.ndarray | None:
        """The R_d this overlay draws for a simulated plant state and the packed references
        (None if f_d vanishes); the controller's R_d at the same state."""
        plant = self._model.plant
        plant.SetPositionsAndVelocities(self._context, plant_state[self._state_indices])
        return self._desired_base_attitude(
            plant.CalcCenterOfMassPositionInWorld(self._context),
            plant.CalcCenterOfMassTranslationalVelocityInWorld(self._context),
            unpack_com_reference(com_reference), unpack_heading_reference(heading_reference))

    def _draw_force(self, path: str, force: np.ndarray, point: np.ndarray, t: float) -> None:
        m = self._meshcat
        magnitude = float(np.linalg.norm(force))
        visible = magnitude > 1e-9
        if self._shown.get(path) != visible:
            m.SetProperty(path, "visible", visible, t)
            self._shown[path] = visible
        if not visible:
            return
        length = FORCE_SCALE * magnitude
        m.SetTransform(path, RigidTransform(_z_towards(force), point), t)
        m.SetTransform(f"{path}/shaft", RigidTransform([0.0, 0.0, length / 2]), t)
        m.SetProperty(f"{path}/shaft", "scale", [1.0, 1.0, length], t)
        # MeshcatCone opens along +z from its apex: turned over, apex ahead and base on the
        # shaft's end.
        X_head = RigidTransform(RotationMatrix.MakeXRotation(np.pi), [0, 0, length + _HEAD_LENGTH])
        m.SetTransform(f"{path}/head", X_head, t)


class MeshcatView:
    """Meshcat for one run: pass :meth:`configure` as the runner's ``configure`` hook, then
    call :meth:`finish` (also after a failure or Ctrl-C) to write ``replay.html``.

    Args:
        scenario: the scenario about to run (for the reference paths and the camera).
        meshcat: an existing Meshcat, else one is started with ``host`` and ``port`` (see
            :func:`start_meshcat`).
        live: send every frame to connected browsers as it is simulated; False records only
            (``--record``: the frames go to the replay, browsers see the scene at the end).
    """

    def __init__(self, scenario: Scenario, *, meshcat: Meshcat | None = None, live: bool = True,
                 host: str = "localhost", port: int | None = None,
                 publish_period: float = PUBLISH_PERIOD):
        self.scenario = scenario
        self.meshcat = meshcat if meshcat is not None else start_meshcat(host, port)
        self.live = live
        self.publish_period = publish_period
        self.visualizer: MeshcatVisualizer | None = None
        self.overlay: TrackingOverlay | None = None
        self.contact_visualizer: ContactVisualizer | None = None  # with an environment

    @property
    def url(self) -> str:
        return self.meshcat.web_url()

    def configure(self, builder: DiagramBuilder, loop: ClosedLoop) -> None:
        """Add the visualizer, the overlay and (with an environment) the contact visualizer
        to ``builder`` (before Build), frame the camera and start recording."""
        params = MeshcatVisualizerParams()
        params.role = Role.kIllustration
        params.publish_period = self.publish_period
        params.prefix = ROBOT_PREFIX.rsplit("/", 1)[-1]
        params.enable_alpha_slider = True
        params.initial_alpha_slider_value = ROBOT_ALPHA
        self.visualizer = MeshcatVisualizer.AddToBuilder(
            builder, loop.output_port("query_object"), self.meshcat, params)
        reference = loop.reference.source  # the run's own: no second build
        overlay = builder.AddSystem(TrackingOverlay(
            self.meshcat, self.scenario, loop.simulated_plant, publish_period=self.publish_period,
            reference=reference))
        overlay.set_name("meshcat_overlay")
        for port in ("plant_state", "com_reference", "task_reference", "heading_reference"):
            builder.Connect(loop.output_port(port), overlay.GetInputPort(port))
        # The disturbance sources are whatever drives the closed loop's wrench inputs.
        sources = builder.connection_map()
        for port in ("vehicle_wrench", "end_effector_wrench"):
            wrench_input = loop.input_port(port)
            system, index = sources[(wrench_input.get_system(), wrench_input.get_index())]
            builder.Connect(system.get_output_port(index), overlay.GetInputPort(port))
        self.overlay = overlay
        self.contact_visualizer = add_contact_visualizer(builder, loop, self.meshcat,
                                                         self.publish_period)
        self.meshcat.SetCameraPose(*camera_for(self.scenario, reference))
        self.meshcat.StartRecording(1.0 / self.publish_period,
                                    set_visualizations_while_recording=self.live)

    def finish(self) -> dict[str, str]:
        """Stop recording, publish the animation to connected browsers, and return the replay
        as ``{"replay.html": text}`` for the run's result set (``run_scenario``'s
        ``extra_files``: written with the run's other files, inside its folder's lock)."""
        self.meshcat.StopRecording()
        self.meshcat.PublishRecording()
        return {REPLAY_FILE: self.meshcat.StaticHtml()}
