"""A small two-wheel robot (a URDF model and its robot file) for the tests of robot files."""

import textwrap

CYL = '<cylinder radius="{r}" length="0.02"/>'
URDF = """<?xml version="1.0"?>
<robot name="twowheel">
  <link name="base_link">
    <inertial><origin xyz="-0.03 0 0.06"/><mass value="1.0"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.08"/><geometry><box size="0.14 0.12 0.06"/></geometry></collision>
    <collision name="caster"><origin xyz="-0.06 0 0.01"/>
      <geometry><sphere radius="0.01"/></geometry></collision>
  </link>
  {wheels}
</robot>
"""
WHEEL = """
  <link name="{side}_wheel">
    <inertial><mass value="0.05"/>
      <inertia ixx="1e-5" iyy="2e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin rpy="1.5707963267948966 0 0"/><geometry>{shape}</geometry></collision>
  </link>
  <joint name="{side}_joint" type="{type}">
    <parent link="base_link"/><child link="{side}_wheel"/>
    <origin xyz="0 {y} {z}"/><axis xyz="0 1 0"/>
  </joint>"""


def two_wheel_robot(tmp_path, yaml: str = "", radius=0.033, z=0.033,
                    joint_type="continuous"):
    """A robot file and URDF model in `tmp_path`: two wheels of `radius` at height `z` on
    `joint_type` joints, 16 cm apart, a rear ball caster; `yaml` replaces the robot file."""
    wheels = "".join(WHEEL.format(side=s, y=y, z=z, type=joint_type,
                                  shape=CYL.format(r=radius))
                     for s, y in (("left", 0.08), ("right", -0.08)))
    (tmp_path / "twowheel.urdf").write_text(URDF.format(wheels=wheels))
    path = tmp_path / "robot.yaml"
    path.write_text(yaml or textwrap.dedent("""\
        model: twowheel.urdf
        base: base_link
        wheels: {left: [left_joint], right: [right_joint]}
        drive: {top_speed: 0.22}
        """))
    return path


SIX_WHEELS = """<?xml version="1.0"?>
<robot name="sixwheel">
  <link name="base_link">
    <inertial><origin xyz="0 0 0.08"/><mass value="4.0"/>
      <inertia ixx="0.03" iyy="0.05" izz="0.06" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 0.11"/><geometry><box size="0.36 0.18 0.08"/></geometry></collision>
  </link>
  {wheels}
</robot>
"""
SIX_WHEEL_XS = (0.13, 0.0, -0.13)
"""m: each side's wheels along the robot, front to back (a third axle at the middle)."""
SIX_WHEEL_Y = 0.14
"""m: the wheels' centres either side (a track of 28 cm)."""


def six_wheel_robot(tmp_path):
    """A robot file and URDF model in `tmp_path`: a 4.3 kg skid steer with three 5 cm wheels
    a side, equally spaced (`SIX_WHEEL_XS`), its mass centred over the middle axle."""
    wheels = "".join(
        WHEEL.format(side=f"{name}_{side}", y=y, z=0.05, type="continuous",
                     shape=CYL.format(r=0.05)).replace('<origin xyz="0 ', f'<origin xyz="{x} ')
        for side, y in (("left", SIX_WHEEL_Y), ("right", -SIX_WHEEL_Y))
        for name, x in zip(("front", "middle", "rear"), SIX_WHEEL_XS, strict=True))
    (tmp_path / "sixwheel.urdf").write_text(SIX_WHEELS.format(wheels=wheels))
    path = tmp_path / "robot.yaml"
    path.write_text(textwrap.dedent("""\
        model: sixwheel.urdf
        base: base_link
        wheels: {left: [front_left_joint, middle_left_joint, rear_left_joint],
                 right: [front_right_joint, middle_right_joint, rear_right_joint]}
        drive: {top_speed: 0.5}
        """))
    return path
