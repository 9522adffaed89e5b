"""Rebuild this corpus from the wheels it comes from (run by hand; CI uses the copies).

    pip download --no-deps -d WHEELS pybullet==3.2.7 rtb-data==2.0.0 airo-models==0.0.12 \
        hello-robot-stretch-urdf==0.1.2
    python tests/data/third_party/make_corpus.py WHEELS

Each URDF is copied as its package ships it, less the ``<visual>`` and ``<collision>``
elements that reference mesh files (the meshes are not copied: the kinematics do not need
them, and they are most of each package's size). Nothing else is changed.
"""

from __future__ import annotations

import re
import sys
import zipfile
from pathlib import Path

HERE = Path(__file__).parent

CORPUS = {
    "pybullet-3.2.7": [
        ("pybullet_data/franka_panda/panda.urdf", "pybullet_panda.urdf"),
        ("pybullet_data/xarm/xarm6_robot.urdf", "pybullet_xarm6_robot.urdf"),
        ("pybullet_data/xarm/xarm6_with_gripper.urdf", "pybullet_xarm6_with_gripper.urdf"),
        ("pybullet_data/kuka_iiwa/model.urdf", "pybullet_kuka_iiwa.urdf"),
        ("pybullet-3.2.7.dist-info/LICENSE.txt", "LICENSE-pybullet.txt"),
        ("pybullet_data/franka_panda/LICENSE.txt", "LICENSE-pybullet-franka_panda.txt"),
    ],
    "rtb_data-2.0.0": [
        ("rtbdata/xacro/abb_irb140_description/urdf/irb140.urdf", "rtb_irb140.urdf"),
        ("rtbdata/xacro/kuka_description/kuka_kr16/urdf/kr16_2.urdf", "rtb_kr16_2.urdf"),
        ("rtbdata/xacro/kuka_description/kuka_kr120/urdf/kr120r2500pro.urdf", "rtb_kr120r2500pro.urdf"),
        ("rtbdata/xacro/kuka_description/kuka_kr210/urdf/kr210l150.urdf", "rtb_kr210l150.urdf"),
        ("rtbdata/xacro/kuka_description/kuka_lbr_iiwa/urdf/lbr_iiwa_14_r820.urdf", "rtb_lbr_iiwa_14_r820.urdf"),
        ("rtbdata/xacro/lynxmotion_al5d_description/urdf/al5d_robot.urdf", "rtb_al5d_robot.urdf"),
        ("rtbdata/xacro/unimation_puma560_description/urdf/puma560_robot.urdf", "rtb_puma560_robot.urdf"),
    ],
    "airo_models-0.0.12": [
        ("airo_models/arms/ur3e/ur3e.urdf", "airo_ur3e.urdf"),
        ("airo_models/arms/ur5e/ur5e.urdf", "airo_ur5e.urdf"),
        ("airo_models-0.0.12.dist-info/licenses/LICENSE", "LICENSE-airo-models.txt"),
    ],
    "hello_robot_stretch_urdf-0.1.2": [
        (
            "stretch_urdf/SE3/stretch_description_SE3_eoa_wrist_dw3_tool_sg3.urdf",
            "stretch_SE3_eoa_wrist_dw3_tool_sg3.urdf",
        ),
        ("hello_robot_stretch_urdf-0.1.2.dist-info/LICENSE.md", "LICENSE-hello-robot-stretch-urdf.md"),
    ],
}


ELEMENT = re.compile(rb"[ \t]*<(visual|collision)\b[^>]*>.*?</\1>[ \t]*\r?\n?", re.DOTALL)


def strip_meshes(text: bytes) -> bytes:
    """The URDF without the visual and collision elements that reference a mesh file, edited
    as text: airo-models' files use an undeclared ``drake:`` prefix, which an XML parser
    refuses and which has to reach pinrate as shipped."""
    return ELEMENT.sub(lambda match: b"" if b"<mesh" in match.group(0) else match.group(0), text)


def main(wheels: Path) -> None:
    for stem, members in CORPUS.items():
        (wheel,) = wheels.glob(f"{stem}-*.whl")
        with zipfile.ZipFile(wheel) as archive:
            for member, name in members:
                data = archive.read(member)
                (HERE / name).write_bytes(strip_meshes(data) if name.endswith(".urdf") else data)


if __name__ == "__main__":
    main(Path(sys.argv[1]))
