"""The world around the robot: Drake model directives (walls, tables, objects, welded to the
world or free) parsed into the simulated plant beside the robot, as in Drake's hardware_sim
example (``ProcessModelDirectives`` on the scenario's ``directives``).

The shipped environment models are in ``models/sdf/environments/`` (``package://aerial_drake/
environments/wall.sdf``, ``table.sdf``, ``box.sdf``; docs/world.md). The robot's structure
check and the controller's model never see these bodies: the controller's plant is built from
the robot description alone (:func:`aerial_drake.robots.models.make_plant`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from pydrake.multibody.parsing import ModelDirectives, Parser, ProcessModelDirectives
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JointIndex, ModelInstanceIndex

from aerial_drake.robots.parsing import make_parser

#: The URL schemes Drake resolves in a directive's ``file``.
_SCHEMES = ("package://", "model://", "file://")


class WorldError(ValueError):
    """A bad environment; the message names the directive, file or package and the fix."""


def environment_parser(plant: MultibodyPlant, packages: Sequence[str | Path] = ()) -> Parser:
    """A Parser for ``plant`` that knows the ``aerial_drake`` package (its environment models
    included) and the packages of ``packages`` (folders holding a ``package.xml``; Drake's
    ``PackageMap.AddPackageXml``), and nothing else: nothing downloads."""
    parser = make_parser(plant)
    package_map = parser.package_map()
    for i, folder in enumerate(packages):
        xml = Path(folder) / "package.xml"
        if not xml.is_file():
            raise WorldError(f"environment.packages[{i}]: {folder} holds no package.xml: give "
                             "the folder of a ROS-style package (its package.xml names it)")
        try:
            package_map.AddPackageXml(str(xml))
        except RuntimeError as err:
            raise WorldError(f"environment.packages[{i}]: {xml}: {err} (a package of that "
                             "name is already known; rename it)") from None
    return parser


def _check_files(directives: ModelDirectives, parser: Parser) -> None:
    """Each directive's ``file`` is a URL Drake resolves, of a known package, before Drake
    reads any (its own message names neither the directive nor the known packages)."""
    package_map = parser.package_map()
    for i, directive in enumerate(directives.directives):
        for kind in ("add_model", "add_directives"):
            item = getattr(directive, kind)
            if item is None:
                continue
            where = f"environment.directives[{i}].{kind}.file"
            if not item.file.startswith(_SCHEMES):
                raise WorldError(f"{where}: '{item.file}' is not a URL: write "
                                 "package://aerial_drake/environments/<model>.sdf, or a path "
                                 "relative to the scenario file in a scenario")
            if item.file.startswith("package://"):
                name = item.file[len("package://"):].split("/", 1)[0]
                if not package_map.Contains(name):
                    raise WorldError(
                        f"{where}: '{item.file}' names the package '{name}', which is not "
                        f"known (known: {', '.join(sorted(package_map.GetPackageNames()))}); "
                        "add its folder to environment.packages")


def add_environment(plant: MultibodyPlant, directives: ModelDirectives,
                    packages: Sequence[str | Path] = (),
                    robot: Sequence[ModelInstanceIndex] = ()) -> tuple[ModelInstanceIndex, ...]:
    """Process ``directives`` into ``plant`` (unfinalized) and return the model instances they
    add. ``robot``: the robot's model instances, which no environment body may be welded or
    jointed to (a load the robot carries is the scenario's ``payload``).

    Raises:
        WorldError: naming the directive, file or package at fault.
    """
    parser = environment_parser(plant, packages)
    _check_files(directives, parser)
    first, first_joint = plant.num_model_instances(), plant.num_joints()
    try:
        ProcessModelDirectives(directives, plant, parser)
    except RuntimeError as err:
        raise WorldError(f"environment: Drake could not process the directives: {err}"
                         ) from None
    added = tuple(ModelInstanceIndex(i) for i in range(first, plant.num_model_instances()))
    robot_ids = {int(i) for i in robot}
    for index in range(first_joint, plant.num_joints()):
        joint = plant.get_joint(JointIndex(index))
        ends = {int(joint.parent_body().model_instance()),
                int(joint.child_body().model_instance())}
        if ends & robot_ids:
            raise WorldError(
                f"environment: the joint '{joint.name()}' attaches "
                f"'{joint.child_body().name()}' to '{joint.parent_body().name()}', a body of "
                "the robot: environment bodies are welded to the world or free. A load the "
                "robot carries is the scenario's payload section")
    return added
