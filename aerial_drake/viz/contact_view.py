"""The contact forces in Meshcat: Drake's ``ContactVisualizer`` on the simulated plant.

:func:`add_contact_visualizer` is called by :meth:`aerial_drake.viz.meshcat_view.MeshcatView.
configure`. It adds Drake's :class:`pydrake.multibody.meshcat.ContactVisualizer` only where the
closed loop has a ``contact_wrench`` output, that is where the scenario has an environment to
touch (:func:`aerial_drake.simulation.contact.add_contact_sensing`); the paper's runs, with no
environment, get no new system and draw nothing new.

What Drake draws, under ``CONTACT_PREFIX`` (``/drake/contact_forces``):

- every point contact as a double arrow through the contact point, along the contact force,
  one head for each of the two bodies (the force on one and its opposite on the other), each
  half ``|f| / NEWTONS_PER_METER`` long: at ``NEWTONS_PER_METER`` = 20 N/m the 10 N of a
  wall press is a 0.5 m arrow each side of the contact (the end effector's side points back
  along the arm, the other half is inside and behind the wall), as long as a 50 N
  disturbance arrow of the overlay (0.01 m/N). Paths
  ``point/<body A>+<body B>`` (e.g. ``point/lwr_link_7+wall``), made when the pair first
  touches, hidden (``visible`` false) while it does not or its force is under
  ``params.force_threshold`` (Drake's default 0.01 N);
- hydroelastic contacts (none with the shipped models: their tool pads are point contacts) as
  a force arrow and a moment arrow at the contact surface's centroid (``hydroelastic/...``),
  the moment at ``NEWTON_METERS_PER_METER``.

Drake's visualizer sends each pose, scale and visibility with ``time_in_recording`` = the
simulation time (Drake 1.51 passes the publish event's time; the tracks in the replay show
it), so while
:class:`MeshcatView` records, the arrows are tracks of the recorded animation and move in
``replay.html`` with the robot (``tests/viz/test_contact_view.py`` reads them back from the
replay and compares them with the log's ``contact_wrench`` frame by frame).

It publishes at the view's ``publish_period`` (20 ms), a multiple of the 1 ms controller and
log periods, instead of Drake's default 1/32 s: watching adds no integrator step and leaves
the logged numbers unchanged (tested).
"""

from __future__ import annotations

from pydrake.geometry import Meshcat, Rgba
from pydrake.multibody.meshcat import ContactVisualizer, ContactVisualizerParams
from pydrake.systems.framework import DiagramBuilder

from aerial_drake.simulation.diagram import ClosedLoop

#: Where Drake's contact visualizer draws, under ``/drake`` (ContactVisualizerParams.prefix).
CONTACT_PREFIX = "contact_forces"
#: Newtons per metre of a contact-force arrow (each half): 10 N is 0.5 m.
NEWTONS_PER_METER = 20.0
#: Newton metres per metre of a hydroelastic contact's moment arrow.
NEWTON_METERS_PER_METER = 4.0
#: Radius of the arrows' shafts (m): as thick as the disturbance arrows' (0.02 m).
ARROW_RADIUS = 0.012
#: Colour of the point contacts' arrows: purple, apart from the overlays' colours: the
#: end-effector triad's red x axis (which a press along x lies on), the green (vehicle) and
#: orange (end effector) disturbance arrows, the magenta and cyan paths.
CONTACT_COLOR = Rgba(0.55, 0.1, 0.85, 1.0)


def contact_visualizer_params(publish_period: float) -> ContactVisualizerParams:
    """The project's ContactVisualizerParams (module docstring) publishing every
    ``publish_period`` s."""
    params = ContactVisualizerParams()
    params.publish_period = publish_period
    params.prefix = CONTACT_PREFIX
    params.newtons_per_meter = NEWTONS_PER_METER
    params.newton_meters_per_meter = NEWTON_METERS_PER_METER
    params.radius = ARROW_RADIUS
    params.color = CONTACT_COLOR
    return params


def add_contact_visualizer(builder: DiagramBuilder, loop: ClosedLoop, meshcat: Meshcat,
                           publish_period: float) -> ContactVisualizer | None:
    """Add Drake's ContactVisualizer for the simulated plant's contact results to ``builder``
    (the builder ``loop``'s systems were added to, as in the runner's ``configure`` hook), or
    nothing (None) where the closed loop has no ``contact_wrench`` output (no environment)."""
    if not loop.has_output_port("contact_wrench"):
        return None
    if loop.diagram is not None:
        raise ValueError("add_contact_visualizer needs the closed loop's systems in "
                         "'builder' (build_simulation), not a built closed-loop diagram whose "
                         "plant's contact results are not exported")
    visualizer = ContactVisualizer.AddToBuilder(
        builder, loop.simulated_plant.plant.get_contact_results_output_port(),
        loop.output_port("query_object"), meshcat, contact_visualizer_params(publish_period))
    visualizer.set_name("meshcat_contact_forces")
    return visualizer
