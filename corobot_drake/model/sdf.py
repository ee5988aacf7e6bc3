"""Generates the Corobot's SDFormat model from `dimensions` and the contact parameters.

`models/corobot.sdf` is this module's output at the default parameters (written by
`tools/make_model.py`; a test keeps it in step). The simulation builds each robot from the
same function with that robot's own name and contact parameters.
"""


from dataclasses import dataclass

from corobot_drake import limits as lim
from corobot_drake.limits import Range, bounded
from corobot_drake.model import dimensions as dim

PACKAGE_NAME = "corobot_drake"
"""Package name under which `MODELS_DIR` is registered (`package://corobot_drake/...`)."""


@dataclass
class WheelContact:
    """Compliant-hydroelastic tyre and motor parameters of one robot.

    Defaults come from the tire-grip sweep (docs/tuning.md): smooth turning, no flip at the box.
    """

    friction: float = bounded(0.5, lim.FRICTION)
    """Coulomb friction of the tyres (static = dynamic); the ground's is combined with it."""
    hydroelastic_modulus: float = bounded(1.0e6, lim.TYRE_MODULUS)
    """Pa. Soft enough for a smooth contact patch, stiff enough to sink < 1 mm under 9.3 N."""
    resolution_hint: float = bounded(0.005, lim.RESOLUTION_HINT)
    """m. The tyre's tetrahedral mesh size: coarser turns the wheel into a polygon (jitter)."""
    hunt_crossley_dissipation: float = bounded(5.0, lim.DISSIPATION)
    """s/m. Damps the tyre's vertical bounce (the original used restitution 0.2)."""
    effort_limit: float = bounded(0.3, Range(0.0, 1000.0, low_open=True, unit="N m",
                                             why="1000: an unlimited motor, as the tire-grip "
                                                 "studies model one"))
    """N m. Motor stall torque per axle. Above the traction limit mu N R ~ 0.28 N m so
    it never limits top speed or turning, but low enough that the robot cannot climb (and flip
    on) the giant box."""
    servo_damping: float = bounded(10.0, Range(0.0, 1000.0, low_open=True, unit="N m s/rad"))
    """N m s/rad. Velocity-servo gain kd of Drake's implicit PD (kp = 0)."""


def _pose(xyz, rpy=(0.0, 0.0, 0.0)) -> str:
    return " ".join(f"{v:.9g}" for v in (*xyz, *rpy))


def _inertial(mass: float, diag, xyz=(0.0, 0.0, 0.0)) -> str:
    ixx, iyy, izz = diag
    return f"""      <inertial>
        <pose>{_pose(xyz)}</pose>
        <mass>{mass:.9g}</mass>
        <inertia>
          <ixx>{ixx:.9g}</ixx><iyy>{iyy:.9g}</iyy><izz>{izz:.9g}</izz>
          <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz>
        </inertia>
      </inertial>"""


def _chassis_inertia() -> tuple[float, tuple[float, float, float], tuple[float, float, float]]:
    """Combined mass, centre of mass and principal-axis inertia about the CoM of both boxes."""
    parts = (dim.CHASSIS, dim.PLATFORM)
    mass = sum(p.mass for p in parts)
    com_z = sum(p.mass * p.center[2] for p in parts) / mass
    ixx = iyy = izz = 0.0
    for p in parts:
        jx, jy, jz = p.inertia_diagonal()
        dz = p.center[2] - com_z
        ixx += jx + p.mass * dz**2
        iyy += jy + p.mass * dz**2
        izz += jz
    return mass, (0.0, 0.0, com_z), (ixx, iyy, izz)


CHASSIS_MESHES = ("chassis", "platform", "standoffs", "camera", "ir_front", "ir_rear")
"""Visual meshes (models/meshes, by tools/make_meshes.py) posed in the chassis frame."""
VISUALS = ("meshes", "boxes")
"""`meshes`: the generated look; `boxes`: the collision shapes drawn (MRDS's physics view)."""

LINKS = ("chassis", *(f"{w}_wheel" for w in dim.WHEEL_NAMES))
"""The robot model's links: the frames a sensor can be mounted on (`X_PB.base_frame`)."""


def _mesh_visual(name: str) -> str:
    return f"""      <visual name="{name}">
        <geometry><mesh><uri>package://{PACKAGE_NAME}/meshes/{name}.obj</uri></mesh></geometry>
      </visual>"""


def _box_visual(name: str, part: dim.BoxPart, color: str) -> str:
    size = " ".join(f"{v:.9g}" for v in part.size)
    return f"""      <visual name="{name}_box">
        <pose>{_pose(part.center)}</pose>
        <geometry><box><size>{size}</size></box></geometry>
        <material><diffuse>{color}</diffuse></material>
      </visual>"""


def _box_collision(name: str, part: dim.BoxPart) -> str:
    size = " ".join(f"{v:.9g}" for v in part.size)
    return f"""      <collision name="{name}">
        <pose>{_pose(part.center)}</pose>
        <geometry><box><size>{size}</size></box></geometry>
        <drake:proximity_properties>
          <drake:mu_dynamic>0.5</drake:mu_dynamic>
          <drake:mu_static>0.5</drake:mu_static>
        </drake:proximity_properties>
      </collision>"""


def _wheel_visual(wheel: str, cyl_pose: str, cyl: str, visual: str) -> str:
    if visual == "meshes":
        return _mesh_visual("wheel").replace('name="wheel"', f'name="{wheel}_wheel"')
    # A light spoke shows the wheel turning when drawn as its collision cylinder.
    r, w = dim.WHEEL_RADIUS, dim.WHEEL_WIDTH
    return f"""      <visual name="{wheel}_tyre">
        <pose>{cyl_pose}</pose>
        <geometry>{cyl}</geometry>
        <material><diffuse>0.1 0.1 0.1 1</diffuse></material>
      </visual>
      <visual name="{wheel}_spoke">
        <pose>{_pose((0, 0, r * 0.5))}</pose>
        <geometry><box><size>{r * 0.3:.9g} {w * 1.02:.9g} {r * 0.6:.9g}</size></box></geometry>
        <material><diffuse>0.8 0.8 0.8 1</diffuse></material>
      </visual>"""


def _wheel_link(wheel: str, contact: WheelContact, visual: str) -> str:
    center = dim.wheel_center(wheel)
    # SDF cylinders lie along z; roll by 90 deg puts the axle along the link's y.
    cyl_pose = _pose((0, 0, 0), (1.5707963267948966, 0, 0))
    cyl = (f"<cylinder><radius>{dim.WHEEL_RADIUS:.9g}</radius>"
           f"<length>{dim.WHEEL_WIDTH:.9g}</length></cylinder>")
    return f"""    <link name="{wheel}_wheel">
      <pose>{_pose(center)}</pose>
{_inertial(dim.WHEEL_MASS, dim.wheel_inertia_diagonal())}
{_wheel_visual(wheel, cyl_pose, cyl, visual)}
      <collision name="{wheel}_tyre">
        <pose>{cyl_pose}</pose>
        <geometry>{cyl}</geometry>
        <drake:proximity_properties>
          <drake:compliant_hydroelastic/>
          <drake:hydroelastic_modulus>{contact.hydroelastic_modulus:.9g}</drake:hydroelastic_modulus>
          <drake:mesh_resolution_hint>{contact.resolution_hint:.9g}</drake:mesh_resolution_hint>
          <drake:hunt_crossley_dissipation>{contact.hunt_crossley_dissipation:.9g}</drake:hunt_crossley_dissipation>
          <drake:mu_dynamic>{contact.friction:.9g}</drake:mu_dynamic>
          <drake:mu_static>{contact.friction:.9g}</drake:mu_static>
        </drake:proximity_properties>
      </collision>
    </link>
    <joint name="{wheel}_axle" type="revolute">
      <parent>chassis</parent>
      <child>{wheel}_wheel</child>
      <axis>
        <xyz>0 1 0</xyz>
        <limit><effort>{contact.effort_limit:.9g}</effort></limit>
      </axis>
      <drake:controller_gains p="0" d="{contact.servo_damping:.9g}"/>
    </joint>"""


def corobot_sdf(model_name: str = "corobot", contact: WheelContact | None = None,
                visual: str = "meshes") -> str:
    """The robot's SDFormat text: body `chassis` plus four wheels on axles about +y.

    The chassis frame is on the ground midway between the axles (+x forward, +z up).
    Wheel axle actuators are ordered as `dimensions.WHEEL_NAMES`. `visual` is one of VISUALS;
    meshes are referenced as package://corobot_drake/meshes/... (register MODELS_DIR).
    """
    if visual not in VISUALS:
        raise ValueError(f"visual must be one of {VISUALS}, got {visual!r}")
    contact = contact or WheelContact()
    mass, com, inertia = _chassis_inertia()
    wheels = "\n".join(_wheel_link(w, contact, visual) for w in dim.WHEEL_NAMES)
    if visual == "meshes":
        body_visuals = "\n".join(_mesh_visual(m) for m in CHASSIS_MESHES)
    else:
        body_visuals = (_box_visual("chassis", dim.CHASSIS, "0.15 0.15 0.18 1") + "\n"
                        + _box_visual("platform", dim.PLATFORM, "0.55 0.1 0.1 1"))
    members = "\n".join(
        f"      <drake:member>{link}</drake:member>"
        for link in LINKS
    )
    return f"""<?xml version="1.0"?>
<!-- Generated by tools/make_model.py from corobot_drake/model/dimensions.py: do not edit. -->
<sdf version="1.9" xmlns:drake="http://drake.mit.edu">
  <model name="{model_name}">
    <link name="chassis">
{_inertial(mass, inertia, com)}
{body_visuals}
{_box_collision("chassis", dim.CHASSIS)}
{_box_collision("platform", dim.PLATFORM)}
    </link>
{wheels}
    <drake:collision_filter_group name="robot_self">
{members}
      <drake:ignored_collision_filter_group>robot_self</drake:ignored_collision_filter_group>
    </drake:collision_filter_group>
  </model>
</sdf>
"""
