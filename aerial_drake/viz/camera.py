"""Where a run's camera looks from: :func:`camera_for` keeps the points the robot reaches
over the run (:func:`robot_envelope`) in view (Meshcat's, :mod:`aerial_drake.viz.meshcat_view`)."""

from __future__ import annotations

import numpy as np

from aerial_drake.robots.extent import vehicle_extent
from aerial_drake.simulation.scenarios import Scenario
from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.kinds import reference_of

__all__ = ["robot_envelope", "view_coordinates", "camera_for"]

#: Samples per second of the reference in the envelope.
ENVELOPE_RATE = 20.0
#: Camera direction from the target: azimuth -30 deg (in front, +x, and to the right, -y, so
#: World y, the helicopter's push, points to the right of the picture), elevation 20 deg.
CAMERA_AZIMUTH, CAMERA_ELEVATION = np.radians(-30.0), np.radians(20.0)
#: three.js' default vertical field of view (deg), and the narrowest window we frame for
#: (width / height; 4:3, wider windows show more).
CAMERA_FOV, CAMERA_ASPECT = 75.0, 4.0 / 3.0
#: Share of the half-width / half-height the robot may fill.
CAMERA_FILL = 0.9


def robot_envelope(scenario: Scenario, reference: ReferenceSource | None = None
                   ) -> np.ndarray:
    """Points (N, 3) the robot reaches over the run if it tracks: the desired end-effector
    path, and about each desired CoM the vehicle's lowest point (the helicopter's skids) and a
    ring at its highest (its rotor discs' outer rims) as wide as the vehicle, both from the
    model (:func:`aerial_drake.robots.extent.vehicle_extent` of the scenario's plant variant:
    the vehicle level at the nominal posture; the ring holds any heading). ``reference``: the
    run's (None: built from ``scenario.trajectory``)."""
    extent = vehicle_extent(scenario.plant_variant, scenario.robot_description())
    times = np.linspace(0.0, scenario.duration, int(scenario.duration * ENVELOPE_RATE) + 2)
    reference = reference or reference_of(scenario.trajectory,
                                          scenario.controller_model().task_joint_nominal())
    ref = reference.sample(times)
    G = ref.com[:, 0]
    angles = np.linspace(0.0, 2 * np.pi, 12, endpoint=False)
    rim = np.column_stack([extent.radius * np.cos(angles), extent.radius * np.sin(angles),
                           np.full(12, extent.top)])
    return np.vstack([ref.p_ed, G - [0.0, 0.0, extent.bottom],
                      (G[:, None, :] + rim).reshape(-1, 3)])


def view_coordinates(camera: np.ndarray, target: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``points`` on the picture of a camera at ``camera`` looking at ``target`` (z up), as
    (x right, y up) divided by tan(fov / 2): |y| <= 1 and |x| <= aspect are in view."""
    forward = (target - camera) / np.linalg.norm(target - camera)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rays = np.asarray(points) - camera
    depth = rays @ forward
    scale = np.tan(np.radians(CAMERA_FOV / 2)) * depth
    return np.column_stack([rays @ right / scale, rays @ up / scale])


def camera_for(scenario: Scenario, reference: ReferenceSource | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """(camera position, target) in World that keep :func:`robot_envelope` in view over the
    whole run: the target is the middle of the envelope's bounding box, the camera along
    (``CAMERA_AZIMUTH``, ``CAMERA_ELEVATION``) from it, as close as ``CAMERA_FILL`` of a
    ``CAMERA_ASPECT`` window allows."""
    points = robot_envelope(scenario, reference)
    target = 0.5 * (points.min(axis=0) + points.max(axis=0))
    direction = np.array([np.cos(CAMERA_ELEVATION) * np.cos(CAMERA_AZIMUTH),
                          np.cos(CAMERA_ELEVATION) * np.sin(CAMERA_AZIMUTH),
                          np.sin(CAMERA_ELEVATION)])

    def fill(distance: float) -> float:
        xy = view_coordinates(target + distance * direction, target, points)
        return max(np.abs(xy[:, 0]).max() / CAMERA_ASPECT, np.abs(xy[:, 1]).max())

    near = np.linalg.norm(points - target, axis=1).max() + 0.1  # all points in front
    far = 100.0 * near
    for _ in range(50):  # bisection: fill decreases with the distance
        middle = 0.5 * (near + far)
        near, far = (middle, far) if fill(middle) > CAMERA_FILL else (near, middle)
    return target + far * direction, target
