"""A robot the project does not ship, as a user would bring it: one URDF of a 6.5 kg hexacopter
with a 6-joint arm (UR-like axes: pan, shoulder, elbow, three wrist joints) and a massless
``tool0`` link welded at the flange, transmissions on every joint, effort limits, and no
robot description. ``robot init`` starts from it (docs/robots.md, "From a URDF to a flying
scenario"; tests/analysis/onboarding/test_init.py).

    python tests/hexarm.py FOLDER      # writes FOLDER/hexarm.urdf
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

#: Links: name, mass (kg), principal inertia (kg m^2), centre of mass in the link (m).
LINKS = (("hexacopter", 6.5, (0.21, 0.21, 0.38), (0.0, 0.0, 0.0)),
         ("pan", 0.5, (6e-4, 6e-4, 4e-4), (0.0, 0.0, -0.03)),
         ("upper_arm", 1.1, (6e-3, 6e-3, 8e-4), (0.0, 0.0, -0.12)),
         ("forearm", 0.7, (3e-3, 3e-3, 4e-4), (0.0, 0.0, -0.1)),
         ("wrist_1", 0.3, (2e-4, 2e-4, 1.5e-4), (0.0, 0.0, -0.03)),
         ("wrist_2", 0.3, (2e-4, 2e-4, 1.5e-4), (0.0, 0.0, -0.03)),
         ("wrist_3", 0.15, (8e-5, 8e-5, 8e-5), (0.0, 0.0, -0.02)))
#: Joints: name, parent, child, origin in the parent (m), axis, limit (rad), effort (N m).
JOINTS = (("pan_joint", "hexacopter", "pan", (0.0, 0.0, -0.08), (0, 0, 1), 3.0, 28.0),
          ("shoulder_joint", "pan", "upper_arm", (0.0, 0.0, -0.06), (0, 1, 0), 2.6, 28.0),
          ("elbow_joint", "upper_arm", "forearm", (0.0, 0.0, -0.24), (0, 1, 0), 2.8, 14.0),
          ("wrist_1_joint", "forearm", "wrist_1", (0.0, 0.0, -0.21), (0, 1, 0), 3.0, 6.0),
          ("wrist_2_joint", "wrist_1", "wrist_2", (0.0, 0.0, -0.06), (1, 0, 0), 3.0, 6.0),
          # The flange turns about the tool's axis, as on a UR arm.
          ("wrist_3_joint", "wrist_2", "wrist_3", (0.0, 0.0, -0.06), (0, 0, 1), 3.0, 6.0))
ROTOR_RADIUS = 0.45  # m, the rotors' centres from the vehicle's axis


def _xyz(v) -> str:
    return " ".join(f"{x:g}" for x in v)


def urdf() -> str:
    """The URDF text."""
    out = ['<?xml version="1.0"?>', '<robot name="hexarm">']
    for name, mass, (ixx, iyy, izz), com in LINKS:
        visual = ""
        if name == "hexacopter":  # a hub and six rotor discs (their size sets the torques)
            visual = ('<visual><geometry><cylinder radius="0.15" length="0.08"/></geometry>'
                      '</visual>')
            for k in range(6):
                a = k * math.pi / 3
                visual += (f'<visual><origin xyz="{ROTOR_RADIUS * math.cos(a):.4f} '
                           f'{ROTOR_RADIUS * math.sin(a):.4f} 0.05"/><geometry><cylinder '
                           'radius="0.12" length="0.01"/></geometry></visual>')
        else:
            visual = ('<visual><origin xyz="' + _xyz(com) + '"/><geometry><cylinder '
                      'radius="0.03" length="0.06"/></geometry></visual>')
        out.append(f'  <link name="{name}"><inertial><origin xyz="{_xyz(com)}"/>'
                   f'<mass value="{mass}"/><inertia ixx="{ixx}" iyy="{iyy}" izz="{izz}" '
                   f'ixy="0" ixz="0" iyz="0"/></inertial>{visual}</link>')
    for name, parent, child, origin, axis, limit, effort in JOINTS:
        out.append(f'  <joint name="{name}" type="revolute"><parent link="{parent}"/>'
                   f'<child link="{child}"/><origin xyz="{_xyz(origin)}"/>'
                   f'<axis xyz="{_xyz(axis)}"/><limit lower="{-limit}" upper="{limit}" '
                   f'effort="{effort}" velocity="3.0"/></joint>')
        out.append(f'  <transmission name="{name}_tr"><type>transmission_interface/'
                   f'SimpleTransmission</type><joint name="{name}"><hardwareInterface>'
                   'EffortJointInterface</hardwareInterface></joint><actuator '
                   f'name="{name}_motor"><mechanicalReduction>1</mechanicalReduction>'
                   '</actuator></transmission>')
    out.append('  <link name="tool0"/>')
    out.append('  <joint name="flange_tool0" type="fixed"><parent link="wrist_3"/>'
               '<child link="tool0"/><origin xyz="0 0 -0.05"/></joint>')
    out.append("</robot>")
    return "\n".join(out) + "\n"


def write(folder: Path) -> Path:
    """Writes ``folder/hexarm.urdf``; returns its path."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / "hexarm.urdf"
    path.write_text(urdf())
    return path


if __name__ == "__main__":
    print(write(Path(sys.argv[1] if len(sys.argv) > 1 else ".")))
