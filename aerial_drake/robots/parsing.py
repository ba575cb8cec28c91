"""Parsing a robot description's model files into a plant: a Parser that knows only our package
and the description's package map (nothing downloads), and each ``models`` entry resolved and
parsed by its kind (SDF, URDF, Drake model directives)."""

from __future__ import annotations

from pathlib import Path

from pydrake.multibody.parsing import LoadModelDirectives, Parser, ProcessModelDirectives
from pydrake.multibody.plant import MultibodyPlant

from aerial_drake.robots.description import RIGID_VARIANT, RobotDescription, RobotDescriptionError
from aerial_drake.robots.resources import model_directory


def make_parser(plant: MultibodyPlant, robot: RobotDescription | None = None) -> Parser:
    """A Parser for ``plant`` that knows the ``aerial_drake`` package and ``robot``'s
    ``package_map``, and nothing else.

    Drake's default package map includes ``drake_models``, which downloads on first use; our
    models need nothing but their own files, so every other package is removed and a stray
    ``package://`` URL fails at once instead of reaching for the network.
    """
    parser = Parser(plant)
    package_map = parser.package_map()
    for name in package_map.GetPackageNames():
        package_map.Remove(name)
    package_map.AddPackageXml(str(model_directory() / "package.xml"))
    if robot is not None:
        for name, folder in robot.package_map.items():
            path = Path(folder).expanduser()
            path = path if path.is_absolute() else robot.folder() / path
            if not path.is_dir():
                raise RobotDescriptionError(
                    f"{robot.source}: package_map.{name}: folder {path} does not exist",
                    f"package_map.{name}")
            if package_map.Contains(name):
                raise RobotDescriptionError(
                    f"{robot.source}: package_map.{name}: the name '{name}' is taken by "
                    "aerial_drake's own models; rename the package", f"package_map.{name}")
            package_map.Add(name, str(path))
    return parser


def _model_file(robot: RobotDescription, entry: str, parser: Parser, field: str) -> str:
    """The file of a ``models`` entry: a package:// URL or a path from the description."""
    if entry.startswith("package://"):
        name, _, rest = entry[len("package://"):].partition("/")
        if not parser.package_map().Contains(name):
            raise RobotDescriptionError(
                f"{robot.source}: {field}: '{entry}' names the package '{name}', which is not "
                f"in package_map (known: {', '.join(parser.package_map().GetPackageNames())})",
                field)
        path = Path(parser.package_map().GetPath(name)) / rest
    else:
        path = Path(entry).expanduser()
        path = path if path.is_absolute() else robot.folder() / path
    if not path.is_file():
        raise RobotDescriptionError(f"{robot.source}: {field}: model file {path} not found",
                                    field)
    if not str(path).endswith((".sdf", ".urdf", ".dmd.yaml")):
        raise RobotDescriptionError(
            f"{robot.source}: {field}: {path.name} is not an SDF (.sdf), URDF (.urdf) or "
            "Drake model directives (.dmd.yaml) file", field)
    return str(path)


def parse_models(plant: MultibodyPlant, robot: RobotDescription, variant: str) -> None:
    parser = make_parser(plant, robot)
    field = "models" if variant == RIGID_VARIANT else f"variants[{variant}].models"
    for i, entry in enumerate(robot.variant(variant).models):
        path = _model_file(robot, entry, parser, f"{field}[{i}]")
        try:
            if path.endswith(".dmd.yaml"):
                ProcessModelDirectives(LoadModelDirectives(path), plant, parser)
            else:
                parser.AddModels(path)
        except RuntimeError as err:
            raise RobotDescriptionError(f"{robot.source}: {field}[{i}]: Drake could not parse "
                                        f"{path}: {err}", f"{field}[{i}]") from None
